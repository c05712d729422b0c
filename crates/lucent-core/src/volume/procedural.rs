//! Procedural densities: marble/mineral veins and the embedded cube of Shopf 2007 fig. 5.8.
//!
//! Generators are evaluated at voxel centres. Coordinates are measured in units of the grid's
//! largest side, so a grid whose sides follow the bounding box's proportions gets isotropic
//! features (the renderer sizes grids that way).

use super::{DensityVolume, VolumeError, check_dims};
use glam::Vec3;
use noise::Perlin;
use rayon::prelude::*;

/// Parameters of the marble/mineral vein generator: the classic marble construction, a sine
/// of a position phase perturbed by turbulence (Perlin 1985), sharpened into thin dense sheets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Veins {
    /// Seed of the Perlin noise. Default 7.
    pub seed: u32,
    /// Vein frequency: sine periods across the largest side of the box. Default 3.
    pub scale: f32,
    /// Turbulence amplitude, radians of phase per unit turbulence. Default 4.
    pub turbulence: f32,
    /// Exponent that thins the veins: density rises as `(1 - |sin|)^sharpness`. Default 4.
    pub sharpness: f32,
    /// Density between the veins, in `[0, 1]`. Default 0.02.
    pub background: f32,
}

impl Default for Veins {
    fn default() -> Self {
        Veins { seed: 7, scale: 3.0, turbulence: 4.0, sharpness: 4.0, background: 0.02 }
    }
}

impl Veins {
    /// Fractal turbulence `sum_o |noise(2^o p)| / 2^o` over 5 octaves, in about `[0, 1]`.
    fn turbulence_at(noise: &Perlin, p: Vec3) -> f32 {
        let mut sum = 0.0;
        let mut freq = 1.0f64;
        for _ in 0..5 {
            let q = [p.x as f64 * freq, p.y as f64 * freq, p.z as f64 * freq];
            sum += crate::mesh::deform::perlin_periodic(noise, q).abs() / freq;
            freq *= 2.0;
        }
        sum as f32
    }

    /// Density at `p` (units of the grid's largest side), in `[0, 1]`.
    pub fn density(&self, noise: &Perlin, p: Vec3) -> f32 {
        let q = p * self.scale;
        // The vein sheets are oblique so that no mesh axis lines up with them.
        let phase = q.dot(Vec3::new(1.0, 0.6, 0.35)) * std::f32::consts::PI
            + self.turbulence * Self::turbulence_at(noise, q * 1.5);
        let vein = (1.0 - phase.sin().abs()).powf(self.sharpness);
        (self.background + (1.0 - self.background) * vein).clamp(0.0, 1.0)
    }

    /// A `dims` grid of vein densities.
    pub fn generate(&self, dims: [u32; 3]) -> Result<DensityVolume, VolumeError> {
        check_dims(dims)?;
        let noise = Perlin::new(self.seed);
        let largest = *dims.iter().max().expect("three sides") as f32;
        let [nx, ny, _] = dims;
        let data = (0..dims.iter().map(|&d| d as usize).product::<usize>())
            .into_par_iter()
            .map(|v| {
                let v = v as u32;
                let (i, j, k) = (v % nx, (v / nx) % ny, v / (nx * ny));
                let p = (Vec3::new(i as f32, j as f32, k as f32) + 0.5) / largest;
                self.density(&noise, p)
            })
            .collect();
        Ok(DensityVolume { dims, data })
    }
}

/// The thesis's embedded cube (Shopf 2007 fig. 5.8): density 1 inside an axis-aligned cube
/// centred in the box, 0 (clear base material) outside. `size` is the cube's side as a fraction
/// of each side of the box, in `(0, 1]`.
pub fn embedded_cube(dims: [u32; 3], size: f32) -> Result<DensityVolume, VolumeError> {
    check_dims(dims)?;
    let half = 0.5 * size.clamp(0.0, 1.0);
    let [nx, ny, nz] = dims;
    let mut data = Vec::with_capacity((nx * ny * nz) as usize);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let tc = Vec3::new(
                    (i as f32 + 0.5) / nx as f32,
                    (j as f32 + 0.5) / ny as f32,
                    (k as f32 + 0.5) / nz as f32,
                );
                let inside = (tc - 0.5).abs().max_element() <= half;
                data.push(if inside { 1.0 } else { 0.0 });
            }
        }
    }
    Ok(DensityVolume { dims, data })
}
