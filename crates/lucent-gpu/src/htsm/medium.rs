//! HTSM's medium in physical coefficients, so that a path tracer can render the same object
//! (issue 55): a base material plus the density volume as extra absorption, Shopf 2007 §4.3.2,
//! eq. 4.1 (`sigma_at = sigma_a + alpha_d`: "a base material and the scalar density volume
//! defines the amount of material in each voxel").
//!
//! # The medium
//!
//! At a point `x` inside the mesh, with `rho(x)` the density volume's value in `[0, 1]`:
//!
//! * reduced scattering `sigma_s'(x) = sigma_s'` (mm^-1, per RGB channel; the scattering
//!   itself is isotropic with `sigma_s = sigma_s'`, the similarity relation lucent's materials
//!   and its path-tracer references use);
//! * absorption `sigma_a(x) = sigma_a + rho(x) * sigma_d` (mm^-1): the density adds the
//!   absorption `sigma_d` at density 1 (a vein, the thesis's dense cube);
//! * extinction `sigma_t(x) = sigma_s' + sigma_a(x)`, single-scattering albedo
//!   `sigma_s' / sigma_t(x)`;
//! * the object's largest bounding-box side is `scale_m` metres.
//!
//! # What HTSM takes from it
//!
//! HTSM carries light from lit surface points to a visible point along straight rays and
//! attenuates it along them (§4.3.3). For a medium that scatters far more than it absorbs, light
//! that crosses a body does so by diffusion, whose attenuation per unit length is the diffusion
//! transport coefficient `sigma_tr = sqrt(3 sigma_a sigma_t')` (Jensen et al. 2001, eq. 5), not
//! the extinction. HTSM's ray cast therefore integrates the local
//! `sigma_tr(x) = sqrt(3 sigma_a(x) (sigma_a(x) + sigma_s'))` along each sample ray (object
//! units: mm^-1 times the object's size in mm) and the Beer-Lambert model transmits
//! `exp(-integral sigma_tr)`. The thesis's model needs a transport colour and distance: `T_d` is
//! one diffusion length of the base material (`1 / sigma_tr`, the mean over the channels) and
//! `T_c = exp(-sigma_tr T_d)` per channel, so both models agree at `D = T_d` in a uniform body;
//! the density's part of the optical depth is its `alpha_i`.
//!
//! # The former inputs
//!
//! [`HtsmParams::transport_colour`] and [`HtsmParams::transport_distance`] (with
//! [`HtsmParams::density_scale`]) remain for renders without a medium ([`HtsmParams::medium`]
//! `None`): they are the special case `sigma_s' = 0`, `sigma_a = -ln(T_c) / (sqrt(3) T_d)` and
//! `sigma_d = density_scale / sqrt(3)` per object unit, for which `sigma_tr(x)` is
//! `-ln(T_c) / T_d + density_scale * rho(x)`, the attenuation they always meant.

use super::HtsmParams;
use glam::Vec3;

/// A base material plus the density volume's extra absorption (module docs), in physical units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HtsmMedium {
    /// Reduced scattering coefficient `sigma_s'` of the base material, mm^-1 per RGB channel,
    /// >= 0 (lucent's materials: 0.07..8).
    pub sigma_s_prime: Vec3,
    /// Absorption coefficient `sigma_a` of the base material (density 0), mm^-1 per channel,
    /// >= 0.
    pub sigma_a: Vec3,
    /// Absorption added at density 1, `sigma_d`, mm^-1 per channel, >= 0 (the absorption at
    /// density `rho` is `sigma_a + rho sigma_d`).
    pub density_sigma_a: Vec3,
    /// The object's size: its rest mesh's largest bounding-box side, metres, > 0.
    pub scale_m: f32,
}

/// The largest coefficient [`HtsmMedium::validate`] accepts, mm^-1 (a mean free path of a
/// micrometre; beyond it every path through an object is black and f32 optical depths overflow).
pub const MAX_COEFFICIENT: f32 = 1000.0;

/// Default `sigma_d`, mm^-1 (grey): at density 1 a vein absorbs about a hundred times more than
/// lucent's marble, so that veins read as dark sheets at a few centimetres.
pub const DEFAULT_DENSITY_SIGMA_A: f32 = 0.5;

/// The medium's coefficients per object unit (module docs): what the camera pass integrates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HtsmCoefficients {
    /// Base absorption `sigma_a` per object unit.
    pub sigma_a: Vec3,
    /// Reduced scattering `sigma_s'` per object unit.
    pub sigma_s_prime: Vec3,
    /// Absorption added at density 1 per object unit.
    pub density_sigma_a: Vec3,
}

impl HtsmCoefficients {
    /// The diffusion transport coefficient `sqrt(3 sigma_a (sigma_a + sigma_s'))` at density
    /// `rho`, per object unit.
    pub fn sigma_tr(&self, rho: f32) -> Vec3 {
        let a = self.sigma_a + rho * self.density_sigma_a;
        (3.0 * a * (a + self.sigma_s_prime)).map(f32::sqrt)
    }
}

impl HtsmMedium {
    /// Checks every field against its documented range; the message names the field.
    pub fn validate(&self) -> Result<(), String> {
        for (name, v) in [
            ("sigma_s'", self.sigma_s_prime),
            ("sigma_a", self.sigma_a),
            ("density sigma_a", self.density_sigma_a),
        ] {
            if !(v.cmpge(Vec3::ZERO).all() && v.cmple(Vec3::splat(MAX_COEFFICIENT)).all()) {
                return Err(format!("HTSM medium: {name} {v} mm^-1 must be within 0..={MAX_COEFFICIENT}"));
            }
        }
        if !(self.scale_m.is_finite() && self.scale_m > 0.0) {
            return Err(format!("HTSM medium: scale {} m must be > 0", self.scale_m));
        }
        Ok(())
    }

    /// The coefficients per object unit: mm^-1 times the object's size in millimetres.
    pub fn coefficients(&self) -> HtsmCoefficients {
        let mm = self.scale_m * 1000.0;
        HtsmCoefficients {
            sigma_a: self.sigma_a * mm,
            sigma_s_prime: self.sigma_s_prime * mm,
            density_sigma_a: self.density_sigma_a * mm,
        }
    }

    /// `params` with this medium as its input: [`HtsmParams::medium`] set, and the transport
    /// colour and distance the thesis's model and the lit side's diffuse tint use derived as the
    /// module docs say (`T_d` at most 10^4 object units, `T_c` at least 10^-6).
    pub fn apply(&self, params: HtsmParams) -> HtsmParams {
        let c = self.coefficients();
        let tr = c.sigma_tr(0.0);
        let mean = (tr.x + tr.y + tr.z) / 3.0;
        let t_d = if mean > 1e-4 { (1.0 / mean).min(1e4) } else { 1e4 };
        let t_c = (-tr * t_d).exp().clamp(Vec3::splat(1e-6), Vec3::ONE);
        HtsmParams { medium: Some(c), transport_colour: t_c, transport_distance: t_d, ..params }
    }
}

/// What the camera pass integrates, per object unit: `(sigma_a, sigma_s', sigma_d)` of the
/// medium, or for the former inputs the equivalent of module docs' last section.
pub fn extinction_terms(params: &HtsmParams) -> (Vec3, Vec3, Vec3) {
    match params.medium {
        Some(c) => (c.sigma_a, c.sigma_s_prime, c.density_sigma_a),
        None => {
            let root3 = 3f32.sqrt();
            (params.sigma() / root3, Vec3::ZERO, Vec3::splat(params.density_scale / root3))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_former_inputs_are_the_medium_without_scattering() {
        let p = HtsmParams::default();
        let (a, s, d) = extinction_terms(&p);
        let c = HtsmCoefficients { sigma_a: a, sigma_s_prime: s, density_sigma_a: d };
        for rho in [0.0f32, 0.3, 1.0] {
            let want = p.sigma() + Vec3::splat(p.density_scale * rho);
            assert!((c.sigma_tr(rho) - want).abs().max_element() < 1e-4 * want.max_element(), "rho {rho}");
        }
    }

    #[test]
    fn a_medium_gives_the_diffusion_coefficient_in_object_units_and_matching_thesis_inputs() {
        // Skim milk (Jensen 2001) at 5 cm.
        let m = HtsmMedium {
            sigma_s_prime: Vec3::new(0.70, 1.22, 1.90),
            sigma_a: Vec3::new(0.0014, 0.0025, 0.0142),
            density_sigma_a: Vec3::splat(0.5),
            scale_m: 0.05,
        };
        assert!(m.validate().is_ok());
        let p = m.apply(HtsmParams::default());
        let tr = p.medium.unwrap().sigma_tr(0.0);
        let red = (3.0f32 * 0.0014 * (0.0014 + 0.70)).sqrt() * 50.0;
        assert!((tr.x - red).abs() < 1e-4 * red);
        // Both models transmit T_c at T_d.
        assert!(((-tr * p.transport_distance).exp() - p.transport_colour).abs().max_element() < 1e-5);
        assert!(p.validate().is_ok());
        let bad = HtsmMedium { scale_m: 0.0, ..m };
        assert!(bad.validate().unwrap_err().contains("scale"));
        let bad = HtsmMedium { sigma_a: Vec3::new(-1.0, 0.0, 0.0), ..m };
        assert!(bad.validate().unwrap_err().contains("sigma_a"));
        for v in [f32::NAN, f32::INFINITY, 1e30] {
            let bad = HtsmMedium { density_sigma_a: Vec3::splat(v), ..m };
            assert!(bad.validate().unwrap_err().contains("density sigma_a"), "{v}");
        }
    }
}
