// The spot's angular falloff, as lucent-core's irradiance::spot_falloff: 1 inside the inner
// angle cone * (1 - soft_edge), 0 outside the cone, a smoothstep in angle between. A cone wider
// than pi is no cone (the mesh pass encodes point lights so): 1 everywhere. Prepended to
// mesh.wgsl and to the HTSM shaders (WGSL has no includes).
fn spot_falloff(cos_angle: f32, cone: f32, soft_edge: f32) -> f32 {
    if (cone > 3.14159265) {
        return 1.0;
    }
    let angle = acos(clamp(cos_angle, -1.0, 1.0));
    let inner = cone * (1.0 - clamp(soft_edge, 0.0, 1.0));
    if (angle >= cone) {
        return 0.0;
    }
    if (angle <= inner) {
        return 1.0;
    }
    let t = (cone - angle) / (cone - inner);
    return t * t * (3.0 - 2.0 * t);
}
