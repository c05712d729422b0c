//! `lucent bench albedo`: colour-and-distance materials (`--albedo`, `--mfp`) against what
//! lucent renders. Each requested slab albedo and mean free path is turned into coefficients by
//! `Material::from_albedo_mfp`, then a large flat slab of that material is lit with transmitted
//! irradiance 1 on its top (`lucent_core::solver::energy::slab_albedo`), and the mean `B` at the
//! slab's centre is the albedo lucent renders. Two solves per material: the hierarchical one
//! that `lucent render` uses (48² squares a side), and the exact one (12² squares; its form
//! factors are exact, so the tessellation does not matter), which isolates the inversion and the
//! profile's table from the hierarchical solver's own error.

use anyhow::Result;
use lucent_core::bssrdf::Material;
use lucent_core::solver::energy::{SlabSolver, slab_albedo};

/// Requested albedos: the grid of the issue, dense towards 1 where translucent materials live.
const ALBEDOS: [f64; 10] = [0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 0.8, 0.9, 0.95, 0.99];
/// Requested mean free paths, mm.
const MFPS: [f64; 3] = [0.1, 1.0, 10.0];
/// Squares per side of the slab for the hierarchical solve (fine near the centre, as rendered).
const HIERARCHICAL_SUBDIVISIONS: u32 = 48;
/// Squares per side for the exact solve.
const EXACT_SUBDIVISIONS: u32 = 12;

pub fn run(json: bool) -> Result<()> {
    let (mut worst, mut worst_exact): (f64, f64) = (0.0, 0.0);
    if !json {
        println!(
            "{:>5} {:>8} {:>8} {:>9} {:>8} {:>9} {:>8} {:>9} {:>7}",
            "eta", "mfp mm", "albedo", "rendered", "error", "exact", "error", "side mm", "ms"
        );
    }
    for eta in [1.3, 1.0] {
        for mfp in MFPS {
            // Three albedos per solve, one per channel.
            for chunk in ALBEDOS.chunks(3) {
                let mut request = [chunk[0]; 3];
                request[..chunk.len()].copy_from_slice(chunk);
                let material = Material::from_albedo_mfp("bench", request, [mfp; 3], eta)?;
                let t = std::time::Instant::now();
                let slab = slab_albedo(&material, HIERARCHICAL_SUBDIVISIONS, SlabSolver::Hierarchical);
                let ms = t.elapsed().as_secs_f64() * 1e3;
                let exact = slab_albedo(&material, EXACT_SUBDIVISIONS, SlabSolver::Exact);
                for (c, &want) in chunk.iter().enumerate() {
                    let (got, got_exact) = (slab.rendered[c] as f64, exact.rendered[c] as f64);
                    let (error, error_exact) = ((got - want) / want, (got_exact - want) / want);
                    worst = worst.max(error.abs());
                    worst_exact = worst_exact.max(error_exact.abs());
                    if json {
                        println!(
                            "{{\"eta\":{eta},\"mfp_mm\":{mfp},\"albedo\":{want},\"rendered\":{got:.6},\
                             \"error\":{error:.6},\"exact\":{got_exact:.6},\"exact_error\":{error_exact:.6},\
                             \"side_mm\":{:.1},\"ms\":{ms:.0}}}",
                            slab.side_mm
                        );
                    } else {
                        println!(
                            "{eta:>5} {mfp:>8} {want:>8} {got:>9.5} {:>+7.2}% {got_exact:>9.5} {:>+7.3}% {:>9.1} {ms:>7.0}",
                            100.0 * error,
                            100.0 * error_exact,
                            slab.side_mm
                        );
                    }
                }
            }
        }
    }
    if json {
        println!("{{\"max_abs_error\":{worst:.6},\"max_abs_error_exact\":{worst_exact:.6}}}");
    } else {
        println!("max |error| {:.2}% (exact solve {:.3}%)", 100.0 * worst, 100.0 * worst_exact);
    }
    Ok(())
}
