//! The committed sphere table against its generator's grid and against fresh walks.

use super::*;
use crate::bssrdf::sphere_walk::transmitted;

/// The interpolation's bias bound, relative, up to 45 degrees from the antipode: halfway between
/// the table's points in radius, albedo and angle at once, `cargo run --release -p lucent-core
/// --example sphere_table -- --check 200000` found the table within 3.1% of fresh walks there
/// where `T > 1e-3` (mean +0.2%, each within 1.5 combined standard errors; docs/transmission.md).
/// Toward the terminator, where `T(θ)` bends upward between the angles, it is larger (up to 6-11%
/// at 80-85 degrees where `κ R > 2`).
const INTERPOLATION_BIAS: f64 = 0.03;

/// The committed file is the generator's grid, every value walked, and reads back as written.
#[test]
fn the_committed_table_is_the_generator_s_grid() {
    let table = Walked::committed();
    assert_eq!(table.albedo, grid_albedos());
    assert_eq!(table.radius, grid_radii());
    assert_eq!(table.theta_deg, THETA_DEG.to_vec());
    for (i, &p) in table.paths.iter().enumerate() {
        assert_eq!(p as usize, grid_paths(table.radius[i % table.radius.len()]));
    }
    assert!(table.ln_t.iter().all(|v| v.is_finite()));
    assert!(table.rel_se.iter().all(|v| v.is_finite() && *v > 0.0));
    assert!(table.tilt.iter().all(|v| v.is_finite() && v.abs() <= 1.0));
    assert!(
        (0..table.albedo.len() * table.radius.len()).all(|i| table.tilt[i * table.theta_deg.len()] == 0.0)
    );
    assert!(table.normal.iter().all(|v| v.is_finite() && *v > 0.0 && *v < 1.0));
    assert_eq!(Walked::decode(&table.encode()).as_ref(), Some(table));
    assert!(Walked::decode(&table.encode()[1..]).is_none());
}

/// The dielectric table is the same grid, walked forward with [`FORWARD_PATHS`] times the
/// photons; where it scored nothing it says so ([`UNSCORED_LN_T`], relative error 1), and only
/// where the index-1 table's `T` is already far below what an image shows. Up to 55 degrees
/// from the antipode its light is more than the index-1 table's wherever both are well measured
/// (internal reflection keeps the light in); toward the terminator of dark spheres it can be
/// less (light there entered next to it at grazing incidence, which the boundary reflects).
#[test]
fn the_dielectric_table_is_the_same_grid_and_holds_more_light() {
    let (one, table) = (Walked::committed(), Walked::committed_dielectric());
    assert_eq!((&table.albedo, &table.radius, &table.theta_deg), (&one.albedo, &one.radius, &one.theta_deg));
    for (i, &p) in table.paths.iter().enumerate() {
        let want = (grid_paths(table.radius[i % table.radius.len()]) as f64 * FORWARD_PATHS) as usize;
        assert_eq!(p as usize, want);
    }
    assert!(table.tilt.iter().chain(&table.normal).all(|v| v.is_finite() && v.abs() <= 1.0));
    let (mut more, mut compared) = (0, 0);
    for i in 0..table.ln_t.len() {
        if table.ln_t[i] == UNSCORED_LN_T {
            assert_eq!(table.rel_se[i], 1.0);
            assert!(
                one.ln_t[i] < (1e-5f32).ln(),
                "point {i}: unscored where index 1 has {}",
                one.ln_t[i].exp()
            );
        } else if table.rel_se[i] < 0.05
            && one.rel_se[i] < 0.05
            && table.theta_deg[i % table.theta_deg.len()] <= 55.0
        {
            compared += 1;
            more += usize::from(table.ln_t[i] > one.ln_t[i]);
        }
    }
    assert!(compared > 2000 && more == compared, "{more} of {compared}");
}

/// At its own points the table returns what was walked there.
#[test]
fn at_its_points_the_table_returns_the_walk() {
    let table = Walked::committed();
    for a in [0, 5, 17, table.albedo.len() - 3] {
        let at = SphereTable::from_walked(table, table.albedo[a]);
        for r in [0, 9, table.radius.len() - 1] {
            for t in 0..table.theta_deg.len() {
                let want = (table.ln_t[table.index(a, r, t)] as f64).exp();
                let got = at.at_angle(table.radius[r], table.theta_deg[t].to_radians());
                assert!((got / want - 1.0).abs() < 1e-5, "albedo {a} radius {r} angle {t}: {got} vs {want}");
            }
        }
    }
}

/// The table against fresh walks of [`transmitted`] (other seeds) at radii, albedos and angles
/// between its own (up to 45 degrees), within three combined standard errors plus the
/// interpolation's bias.
#[test]
fn the_committed_table_meets_fresh_walks() {
    let cases = [
        (1.3, 0.999, 0.0),
        (7.7, 0.999, 20.0),
        (3.1, 0.99, 40.0),
        (20.0, 0.9995, 0.0),
        (12.0, 0.95, 35.0),
        (2.2, 0.75, 10.0),
        (0.6, 0.99995, 45.0),
        (1.7, 0.45, 0.0),
    ];
    for (i, (r, rho, deg)) in cases.into_iter().enumerate() {
        let table = SphereTable::for_albedo(rho);
        let theta = f64::to_radians(deg);
        let (t, se) = transmitted(r, rho, &[theta], 40_000, 99 + i as u64);
        let got = table.at_angle(r, theta);
        let table_se = table.relative_error(r, theta) * got;
        let tol = 3.0 * (se[0] * se[0] + table_se * table_se).sqrt() + INTERPOLATION_BIAS * t[0];
        assert!((got - t[0]).abs() < tol, "rho {rho} R {r} theta {deg}: {got} vs {} +- {}", t[0], se[0]);
    }
}

/// Below its radii `T` goes as `R³`, beyond them as the slowest mode over the diameter, and
/// both meet the table at its ends; no light at albedo 0.
#[test]
fn beyond_its_radii_the_table_follows_the_limits() {
    let (lo, hi) = (grid_radii()[0], WALK_R);
    for rho in [0.3, 0.99, 0.9999, 1.0] {
        let table = SphereTable::for_albedo(rho);
        let kappa = asymptotic_decay(rho);
        let small = table.at(0.5 * lo) / table.at(lo);
        assert!((small - 0.125).abs() < 1e-9, "rho {rho}: {small}");
        let large = table.at(hi + 10.0) / table.at(hi);
        assert!((large / (-2.0 * kappa * 10.0).exp() - 1.0).abs() < 1e-9, "rho {rho}: {large}");
    }
    assert_eq!(SphereTable::for_albedo(0.0).at(2.0), 0.0);
}

/// The table's exit tilt and normal cosine meet fresh walks between its points, and the
/// independent forward walk's (`validation/sphere_transmission.py --directions`, 200,000
/// photons, which scores the direction each photon leaves in rather than by reciprocity): a 5
/// mean free path sphere of albedo 0.999 read a tilt of +0.103 over 45-70 degrees from the
/// antipode and +0.121 over 70-90 (normal cosines 0.726 and 0.702), and one of 2.41 mean free
/// paths and albedo 0.747 (ketchup's red at 2 cm) +0.137 and +0.134 (0.729 and 0.711).
#[test]
fn the_round_exit_meets_fresh_walks_and_the_forward_walk() {
    use crate::bssrdf::sphere_walk::walk_exits;
    for (i, (r, rho, deg)) in
        [(1.3, 0.999, 50.0), (7.7, 0.999, 70.0), (3.1, 0.99, 60.0), (2.2, 0.75, 80.0)].into_iter().enumerate()
    {
        let theta = f64::to_radians(deg);
        let got = SphereTable::for_albedo(rho).tilt_at(r, theta);
        let fresh = walk_exits(r, rho, &[theta], 40_000, 77 + i as u64);
        // The moments' standard errors at 40,000 photons are about 0.005; the interpolation's
        // bias in radius and albedo about as much.
        let walked = fresh.tilt[0];
        assert!((got - walked).abs() < 0.02, "rho {rho} R {r} theta {deg}: table {got:.3} walk {walked:.3}");
        let (got, walked) = (SphereTable::for_albedo(rho).normal_at(r, theta), fresh.normal[0]);
        assert!((got - walked).abs() < 0.02, "rho {rho} R {r} theta {deg}: normal {got:.3} walk {walked:.3}");
    }
    // Band means of the table (nodes 1 degree apart, weighted by the band's area).
    let band = |r: f64, rho: f64, lo: f64, hi: f64, normal: bool| {
        let table = SphereTable::for_albedo(rho);
        let (mut sum, mut area) = (0.0, 0.0);
        let mut deg = lo + 0.5;
        while deg < hi {
            let theta = f64::to_radians(deg);
            // The tilt weighted by the light leaving there, as the forward walk's mean is.
            let w = theta.sin() * table.at_angle(r, theta.min(f64::to_radians(87.0)));
            sum += w * if normal { table.normal_at(r, theta) } else { table.tilt_at(r, theta) };
            area += w;
            deg += 1.0;
        }
        sum / area
    };
    for (r, rho, lo, hi, tilt, normal) in [
        (5.0, 0.999, 45.0, 70.0, 0.103, 0.726),
        (5.0, 0.999, 70.0, 90.0, 0.121, 0.702),
        (2.41, 0.747, 45.0, 70.0, 0.137, 0.729),
        (2.41, 0.747, 70.0, 90.0, 0.134, 0.711),
    ] {
        let got = band(r, rho, lo, hi, false);
        assert!(
            (got - tilt).abs() < 0.025,
            "R {r} albedo {rho} {lo}-{hi}: tilt {got:.3}, forward walk {tilt}"
        );
        let got = band(r, rho, lo, hi, true);
        assert!(
            (got - normal).abs() < 0.02,
            "R {r} albedo {rho} {lo}-{hi}: normal {got:.3}, forward walk {normal}"
        );
    }
}
