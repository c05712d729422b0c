// Exact unpolarised dielectric Fresnel reflectance (same formula as lucent-core's
// bssrdf::fresnel_dielectric), for a direction at cosine cos_i to the normal. Prepended to
// mesh.wgsl and to lucent-bevy's material shader (WGSL has no includes).
fn fresnel_dielectric(cos_i_in: f32, eta: f32) -> f32 {
    let cos_i = clamp(cos_i_in, 0.0, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if (sin2_t >= 1.0) {
        return 1.0;
    }
    let cos_t = sqrt(1.0 - sin2_t);
    let r_par = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5 * (r_par * r_par + r_perp * r_perp);
}
