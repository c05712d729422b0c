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

/// The diffuse Fresnel reflectance `F_dr` by the polynomial fit of Jensen et al. 2001 (and
/// Mertens table 1), valid for `eta` roughly 1..2.
pub fn fresnel_diffuse_reflectance(eta: f64) -> f64 {
    -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta
}
// TEMPORARY SHIM
pub fn fresnel_moment1(eta: f64) -> f64 {
    let (e2, e3, e4, e5) = (eta * eta, eta * eta * eta, eta.powi(4), eta.powi(5));
    if eta < 1.0 {
        0.45966 - 1.73965 * eta + 3.37668 * e2 - 3.904945 * e3 + 2.49277 * e4 - 0.68441 * e5
    } else {
        -4.61686 + 11.1136 * eta - 10.4646 * e2 + 5.11455 * e3 - 1.27198 * e4 + 0.12746 * e5
    }
}
pub fn fresnel_moment2(eta: f64) -> f64 {
    eta
}
