//! Walks the sphere's transmittance table over albedo, radius and exit angle and writes
//! `crates/lucent-core/src/bssrdf/sphere_table.bin` (`bssrdf::sphere_table` has the grid).
//!
//! ```sh
//! cargo run --release -p lucent-core --example sphere_table              # write the table
//! cargo run --release -p lucent-core --example sphere_table -- --eta 1.3 # the dielectric one
//! cargo run --release -p lucent-core --example sphere_table -- --check   # table vs fresh walks
//! ```
//!
//! `--eta 1.3` walks forward with the dielectric boundary (`bssrdf::sphere_forward`,
//! [`st::FORWARD_PATHS`] times the photons) into `sphere_table_eta1.3.bin`.
//! `--scale F` multiplies every photon count (a quick try), `--out PATH` writes elsewhere.
//! `--check N` walks `N` photons (default 100,000) at points between the grid's, in all three
//! directions, and prints the committed table's error there against the walk's standard error.

use lucent_core::bssrdf::sphere_forward::forward_exits;
use lucent_core::bssrdf::sphere_table::{self as st, SphereTable, Walked};
use lucent_core::bssrdf::sphere_walk::{transmitted, walk_exits};
use rayon::prelude::*;
use std::time::Instant;

/// One point's walk: (albedo, radius) indices, photons, and what it measured per angle.
type Walk = ((usize, usize), usize, lucent_core::bssrdf::sphere_walk::Exits);

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let value = |name: &str| args.iter().position(|a| a == name).and_then(|i| args.get(i + 1));
    if args.iter().any(|a| a == "--check") {
        let paths = value("--check").and_then(|v| v.parse().ok()).unwrap_or(100_000);
        return check(paths);
    }
    let scale: f64 = value("--scale").and_then(|v| v.parse().ok()).unwrap_or(1.0);
    let eta: f64 = value("--eta").and_then(|v| v.parse().ok()).unwrap_or(1.0);
    let name = if eta == 1.0 { "sphere_table.bin".to_string() } else { format!("sphere_table_eta{eta}.bin") };
    let out = value("--out")
        .cloned()
        .unwrap_or_else(|| format!("{}/src/bssrdf/{name}", env!("CARGO_MANIFEST_DIR")));
    let (albedo, radius) = (st::grid_albedos(), st::grid_radii());
    let thetas: Vec<f64> = st::THETA_DEG.iter().map(|d| d.to_radians()).collect();
    let start = Instant::now();
    // The costliest points (large radii, albedos near 1) first, for the threads' balance.
    let mut points: Vec<(usize, usize)> =
        (0..albedo.len()).flat_map(|a| (0..radius.len()).map(move |r| (a, r))).collect();
    points.sort_by_key(|&(a, r)| (a, std::cmp::Reverse(r)));
    let walked: Vec<Walk> = points
        .par_iter()
        .map(|&(a, r)| {
            let seed = st::SEED + 64 * a as u64 + r as u64;
            let (paths, exits) = if eta == 1.0 {
                let paths = ((st::grid_paths(radius[r]) as f64 * scale) as usize).max(64);
                (paths, walk_exits(radius[r], albedo[a], &thetas, paths, seed))
            } else {
                let paths = ((st::grid_paths(radius[r]) as f64 * st::FORWARD_PATHS * scale) as usize).max(64);
                (paths, forward_exits(radius[r], albedo[a], eta, &thetas, paths, seed))
            };
            if r == 0 {
                eprintln!("albedo {:.6}: {:.0} s", albedo[a], start.elapsed().as_secs_f64());
            }
            ((a, r), paths, exits)
        })
        .collect();
    let cells = albedo.len() * radius.len();
    let mut table = Walked {
        albedo: albedo.clone(),
        radius: radius.clone(),
        theta_deg: st::THETA_DEG.to_vec(),
        paths: vec![0; cells],
        ln_t: vec![0.0; cells * thetas.len()],
        rel_se: vec![0.0; cells * thetas.len()],
        tilt: vec![0.0; cells * thetas.len()],
        normal: vec![0.0; cells * thetas.len()],
    };
    for ((a, r), paths, exits) in walked {
        let (t, se) = (&exits.t, &exits.se);
        table.paths[a * radius.len() + r] = paths as u32;
        for k in 0..thetas.len() {
            let i = table.index(a, r, k);
            if t[k] > 0.0 {
                table.ln_t[i] = t[k].ln() as f32;
                table.rel_se[i] = (se[k] / t[k]) as f32;
            } else {
                // Nothing left through this band (the forward walk, dark thick spheres): far
                // below what any image shows, and flagged as unmeasured.
                assert!(eta != 1.0, "albedo {} radius {} angle {}: nothing scored", albedo[a], radius[r], k);
                table.ln_t[i] = st::UNSCORED_LN_T;
                table.rel_se[i] = 1.0;
            }
            table.tilt[i] = exits.tilt[k] as f32;
            table.normal[i] = exits.normal[k] as f32;
        }
    }
    let worst = table.rel_se.iter().cloned().fold(0.0f32, f32::max);
    std::fs::write(&out, table.encode()).expect("write the table");
    eprintln!(
        "{} albedos x {} radii x {} angles, {:.0} s, largest relative error {:.3}: {out}",
        albedo.len(),
        radius.len(),
        thetas.len(),
        start.elapsed().as_secs_f64(),
        worst
    );
}

/// The committed table against fresh walks (other seeds) halfway between its points.
fn check(paths: usize) {
    let (albedo, radius) = (st::grid_albedos(), st::grid_radii());
    let mid_albedo = |a: usize| {
        // Halfway in the interpolation variable, found by bisection in the albedo.
        let want = 0.5 * (st::albedo_variable(albedo[a]) + st::albedo_variable(albedo[a + 1]));
        let (mut lo, mut hi) = (albedo[a + 1], albedo[a]);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if st::albedo_variable(mid) > want { lo = mid } else { hi = mid }
        }
        0.5 * (lo + hi)
    };
    let mut points = Vec::new();
    for a in (0..albedo.len() - 1).step_by(3) {
        for r in (0..radius.len() - 1).step_by(4) {
            let t = (a + r) % (st::THETA_DEG.len() - 1);
            let theta = 0.5 * (st::THETA_DEG[t] + st::THETA_DEG[t + 1]);
            points.push((mid_albedo(a), (radius[r] * radius[r + 1]).sqrt(), theta));
        }
    }
    let rows: Vec<String> = points
        .par_iter()
        .enumerate()
        .map(|(i, &(rho, r, theta))| {
            let table = SphereTable::for_albedo(rho);
            let got = table.at_angle(r, theta.to_radians());
            let (t, se) = transmitted(r, rho, &[theta.to_radians()], paths, 0xc4ec + i as u64);
            let sigma = (se[0] * se[0] + (table.relative_error(r, theta.to_radians()) * got).powi(2)).sqrt();
            format!(
                "rho {rho:.6} R {r:7.3} theta {theta:4.1}: table {got:.4e} walk {:.4e} +- {:.2}%  diff {:+.2}% = {:+.1} sigma",
                t[0],
                100.0 * se[0] / t[0],
                100.0 * (got / t[0] - 1.0),
                (got - t[0]) / sigma
            )
        })
        .collect();
    rows.iter().for_each(|r| println!("{r}"));
}
