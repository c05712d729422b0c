//! Dielectric Fresnel terms for a smooth boundary between air (index 1) and a material of
//! relative index `eta`.

/// Exact unpolarised Fresnel reflectance for light arriving from the outside at an angle whose
/// cosine to the normal is `cos_i` (clamped to 0..1), onto a dielectric of relative index `eta`.
/// Handles `eta < 1` (total internal reflection returns 1).
pub fn fresnel_dielectric(cos_i: f64, eta: f64) -> f64 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let r_par = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (r_par * r_par + r_perp * r_perp)
}

/// Fresnel transmittance `F_t(eta, w) = 1 - F_r` for a direction whose cosine to the normal is
/// `cos_theta`. By reciprocity the same factor applies to light leaving towards `w`.
pub fn fresnel_transmittance(cos_theta: f64, eta: f64) -> f64 {
    1.0 - fresnel_dielectric(cos_theta, eta)
}

/// The cosine to the normal inside a dielectric of relative index `eta` (>= 1) of light that
/// arrives from outside at cosine `cos_i` (0..=1): Snell's law.
pub fn refracted_cosine(cos_i: f64, eta: f64) -> f64 {
    (1.0 - (1.0 - cos_i * cos_i) / (eta * eta)).max(0.0).sqrt()
}

/// The boundary's `A = (1 + F_dr) / (1 - F_dr)` (Jensen et al. 2001), with `F_dr` from
/// [`fresnel_diffuse_reflectance`]: how far internal reflection at a smooth boundary raises
/// the fluence there (about 1 at `eta = 1`, 2.6 at 1.3).
pub fn boundary_a(eta: f64) -> f64 {
    let f_dr = fresnel_diffuse_reflectance(eta);
    (1.0 + f_dr) / (1.0 - f_dr)
}

/// The diffuse Fresnel reflectance `F_dr` by the polynomial fit of Jensen et al. 2001 (and
/// Mertens table 1), valid for `eta` roughly 1..2.
pub fn fresnel_diffuse_reflectance(eta: f64) -> f64 {
    -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta
}
/// The first angular moment of the dielectric Fresnel reflectance, `∫_0^1 F_r(μ) μ dμ`, for
/// light travelling from a medium of index `eta` into one of index 1 (pbrt's convention:
/// `eta > 1` is internal reflection, with total reflection past the critical angle; `1/eta` is
/// external reflection onto index `eta`). 0 at `eta = 1`. Simpson's rule on 2,048 intervals,
/// split at the critical angle (accurate to ~1e-9).
pub fn fresnel_moment1(eta: f64) -> f64 {
    fresnel_moment(eta, 1)
}

/// The second moment, `∫_0^1 F_r(μ) μ² dμ`, in the convention of [`fresnel_moment1`].
pub fn fresnel_moment2(eta: f64) -> f64 {
    fresnel_moment(eta, 2)
}

fn fresnel_moment(eta: f64, power: i32) -> f64 {
    // Light from index `eta` into 1 sees the relative index 1/eta.
    let rel = 1.0 / eta;
    let f = |mu: f64| fresnel_dielectric(mu, rel) * mu.powi(power);
    let simpson = |a: f64, b: f64| {
        const N: usize = 1024;
        let h = (b - a) / N as f64;
        let inner: f64 = (1..N).map(|i| f(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 }).sum();
        (f(a) + f(b) + inner) * h / 3.0
    };
    // Total internal reflection (F_r = 1) below the critical cosine.
    let mu_c = if rel < 1.0 { (1.0 - rel * rel).sqrt() } else { 0.0 };
    let below = if mu_c > 0.0 { mu_c.powi(power + 1) / (power + 1) as f64 } else { 0.0 };
    below + simpson(mu_c, 1.0)
}
