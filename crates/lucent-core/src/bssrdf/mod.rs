//! The dipole diffusion BSSRDF (Jensen, Marschner, Levoy & Hanrahan 2001), in the form of
//! Mertens et al. 2003, table 1, with the measured materials of Jensen et al. 2001.
//!
//! The real source sits `z_r` below the surface and the virtual source `z_v` *above* it
//! (`x_v = x_i + z_v N_i`, as Mertens writes; the Shopf thesis's table 3.1 has a sign typo).

mod fresnel;
mod material;

pub use fresnel::{fresnel_dielectric, fresnel_diffuse_reflectance, fresnel_transmittance};
pub use material::{Material, MaterialError, PRESETS};

/// The dipole coefficients of one material at one model scale, per colour channel, with every
/// length in *mesh units* (coefficients are measured in mm^-1 and converted by `mm_per_unit`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dipole {
    /// Effective transport coefficient `sigma_tr = sqrt(3 sigma_a sigma_t')`, per mesh unit.
    pub sigma_tr: [f64; 3],
    /// Depth of the real source below the surface, `z_r = 1 / sigma_t'`, in mesh units.
    pub z_r: [f64; 3],
    /// Height of the virtual source above the surface, `z_v = z_r (1 + 4A/3)`, in mesh units.
    pub z_v: [f64; 3],
    /// Reduced albedo `alpha' = sigma_s' / sigma_t'` (unitless, 0..1).
    pub alpha_prime: [f64; 3],
    /// Relative index of refraction of the material (unitless, > 0; 1.3 for the measured table).
    pub eta: f64,
    /// How many millimetres one mesh unit stands for.
    pub mm_per_unit: f64,
}

impl Dipole {
    /// Dipole coefficients for `material` when one mesh unit is `mm_per_unit` millimetres.
    pub fn new(material: &Material, mm_per_unit: f64) -> Self {
        let f_dr = fresnel_diffuse_reflectance(material.eta);
        let a = (1.0 + f_dr) / (1.0 - f_dr);
        let mut d = Dipole {
            sigma_tr: [0.0; 3],
            z_r: [0.0; 3],
            z_v: [0.0; 3],
            alpha_prime: [0.0; 3],
            eta: material.eta,
            mm_per_unit,
        };
        for c in 0..3 {
            let sigma_a = material.sigma_a[c] * mm_per_unit;
            let sigma_s = material.sigma_s_prime[c] * mm_per_unit;
            let sigma_t = sigma_a + sigma_s;
            d.sigma_tr[c] = (3.0 * sigma_a * sigma_t).sqrt();
            d.z_r[c] = 1.0 / sigma_t;
            d.z_v[c] = d.z_r[c] * (1.0 + 4.0 * a / 3.0);
            d.alpha_prime[c] = sigma_s / sigma_t;
        }
        d
    }

    /// Dipole coefficients for a mesh whose bounding box's largest side (`extent`, in mesh
    /// units) is `scale_m` metres, as in the paper's "marble scaled at 10 cm".
    pub fn for_model_scale(material: &Material, extent: f64, scale_m: f64) -> Self {
        Self::new(material, scale_m * 1000.0 / extent)
    }

    /// `R_d` for a point source pair at planar distance `r` (mesh units), per mesh unit^2.
    pub fn rd_planar(&self, r: f64) -> [f64; 3] {
        std::array::from_fn(|c| {
            let (zr, zv) = (self.z_r[c], self.z_v[c]);
            let s_r = (r * r + zr * zr).sqrt();
            let s_v = (r * r + zv * zv).sqrt();
            self.rd_from_distances(c, s_r, s_v)
        })
    }

    /// `R_d(x_i, x_o)` for arbitrary points with the dipole placed at `x_i` along its normal
    /// `n_i` (unit), as in Mertens table 1.
    pub fn rd(&self, x_i: glam::DVec3, n_i: glam::DVec3, x_o: glam::DVec3) -> [f64; 3] {
        std::array::from_fn(|c| {
            let s_r = (x_i - self.z_r[c] * n_i - x_o).length();
            let s_v = (x_i + self.z_v[c] * n_i - x_o).length();
            self.rd_from_distances(c, s_r, s_v)
        })
    }

    /// `R_d` in channel `c` from the distances to the real (`s_r`) and virtual (`s_v`) sources.
    #[inline]
    pub fn rd_from_distances(&self, c: usize, s_r: f64, s_v: f64) -> f64 {
        let sigma = self.sigma_tr[c];
        let term = |z: f64, s: f64| z * (1.0 + sigma * s) * (-sigma * s).exp() / (s * s * s);
        self.alpha_prime[c] / (4.0 * std::f64::consts::PI) * (term(self.z_r[c], s_r) + term(self.z_v[c], s_v))
    }

    /// Total diffuse reflectance `R_d_total = ∫ R_d dA` over an infinite plane, closed form
    /// (Jensen et al. 2001, eq. 6), per channel. Unitless, 0..1.
    pub fn total_diffuse_reflectance(&self) -> [f64; 3] {
        let f_dr = fresnel_diffuse_reflectance(self.eta);
        let a = (1.0 + f_dr) / (1.0 - f_dr);
        std::array::from_fn(|c| {
            let ap = self.alpha_prime[c];
            let k = (3.0 * (1.0 - ap)).sqrt();
            0.5 * ap * (1.0 + (-(4.0 / 3.0) * a * k).exp()) * (-k).exp()
        })
    }
}

#[cfg(test)]
mod tests;
