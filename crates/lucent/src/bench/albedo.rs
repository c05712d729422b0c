//! `lucent bench albedo`: colour-and-distance materials (`--albedo`, `--mfp`) against what
//! lucent renders. Each requested slab albedo and mean free path is turned into coefficients by
//! `Material::from_albedo_mfp`, then a large flat slab of that material is lit with transmitted
//! irradiance 1 on its top and solved hierarchically (`lucent_core::solver::energy::slab_albedo`);
//! the mean `B` at the slab's centre is the albedo lucent renders.

use anyhow::Result;
use lucent_core::bssrdf::Material;
use lucent_core::solver::energy::slab_albedo;

/// Requested albedos: the grid of the issue, dense towards 1 where translucent materials live.
const ALBEDOS: [f64; 10] = [0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 0.8, 0.9, 0.95, 0.99];
/// Requested mean free paths, mm.
const MFPS: [f64; 3] = [0.1, 1.0, 10.0];

pub fn run(json: bool) -> Result<()> {
    let mut worst: f64 = 0.0;
    if !json {
        println!(
            "{:>5} {:>8} {:>8} {:>9} {:>8} {:>9} {:>8}",
            "eta", "mfp mm", "albedo", "rendered", "error", "side mm", "ms"
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
                let slab = slab_albedo(&material, 48);
                let ms = t.elapsed().as_secs_f64() * 1e3;
                for (c, &want) in chunk.iter().enumerate() {
                    let got = slab.rendered[c] as f64;
                    let error = (got - want) / want;
                    worst = worst.max(error.abs());
                    if json {
                        println!(
                            "{{\"eta\":{eta},\"mfp_mm\":{mfp},\"albedo\":{want},\"rendered\":{got:.6},\"error\":{error:.6},\"side_mm\":{:.1},\"ms\":{ms:.0}}}",
                            slab.side_mm
                        );
                    } else {
                        println!(
                            "{eta:>5} {mfp:>8} {want:>8} {got:>9.5} {:>+7.2}% {:>9.1} {ms:>8.0}",
                            100.0 * error,
                            slab.side_mm
                        );
                    }
                }
            }
        }
    }
    if json {
        println!("{{\"max_abs_error\":{worst:.6}}}");
    } else {
        println!("max |error| {:.2}%", 100.0 * worst);
    }
    Ok(())
}
