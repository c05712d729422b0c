//! Irradiance at the leaves (Mertens §5.3): light arriving at each face's midpoint and
//! transmitted through the smooth dielectric boundary, `E = ∫ L_i F_t(eta, w_i) cos dω`.

use crate::Rgb;
use crate::bssrdf::fresnel_transmittance;
use crate::mesh::Mesh;
use glam::Vec3;
use rayon::prelude::*;

/// A light source. Radiometric units are arbitrary but consistent (think W and W/m^2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// An isotropic point light at `position` (mesh units) with radiant `intensity` per channel
    /// (W/sr); irradiance falls off as `1 / d^2` with `d` in mesh units.
    Point { position: Vec3, intensity: Rgb },
    /// A distant light shining *along* `direction` (need not be unit), giving `irradiance`
    /// (W/m^2 per channel) on a surface facing it.
    Directional { direction: Vec3, irradiance: Rgb },
}

/// Fresnel-transmitted irradiance at every face centroid from `lights`, without shadows.
pub fn face_irradiance(mesh: &Mesh, lights: &[Light], eta: f64) -> Vec<Rgb> {
    (0..mesh.triangles.len())
        .into_par_iter()
        .map(|f| {
            let p = mesh.face_centroid(f);
            let n = mesh.face_normal(f);
            lights.iter().map(|l| light_irradiance(l, p, n, eta)).sum()
        })
        .collect()
}

/// Irradiance transmitted into the surface at `p` with unit normal `n` from one light.
pub fn light_irradiance(light: &Light, p: Vec3, n: Vec3, eta: f64) -> Rgb {
    let (to_light, e) = match *light {
        Light::Point { position, intensity } => {
            let d = position - p;
            let d2 = d.length_squared().max(1e-12);
            (d / d2.sqrt(), intensity / d2)
        }
        Light::Directional { direction, irradiance } => (-direction.normalize_or_zero(), irradiance),
    };
    let cos = n.dot(to_light);
    if cos <= 0.0 {
        return Rgb::ZERO;
    }
    e * cos * fresnel_transmittance(cos as f64, eta) as f32
}
