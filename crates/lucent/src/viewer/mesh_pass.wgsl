// Viewer mesh pass (Mertens §5.4): per-vertex diffuse radiance B/pi, times the exit Fresnel
// transmittance per pixel, times exposure, then the paper's simple gamma tone curve.

struct Uniforms {
    view_proj: mat4x4<f32>,
    // xyz: eye position (mesh units); w: relative index of refraction eta.
    eye_eta: vec4<f32>,
    // x: exposure; y: 1 when the target is sRGB (hardware encodes), else 0; z: 1 to show the
    // radiance without the Fresnel factor (false-colour overlays).
    params: vec4<f32>,
};

@group(0) @binding(0) var<uniform> u: Uniforms;

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) radiance: vec3<f32>,
};

@vertex
fn vs_main(
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) radiance: vec3<f32>,
) -> VsOut {
    var out: VsOut;
    out.clip = u.view_proj * vec4<f32>(position, 1.0);
    out.world = position;
    out.normal = normal;
    out.radiance = radiance;
    return out;
}

// F_t = 1 - F_r for a smooth dielectric of relative index eta and the outside direction at
// cos_o to the normal; by reciprocity it also weights light leaving towards the eye. The same
// formula as lucent_core::bssrdf::fresnel_transmittance.
fn fresnel_transmittance(cos_o: f32, eta: f32) -> f32 {
    // Refracted angle inside, by Snell's law (eta > 1: no total internal reflection).
    let sin_o2 = max(0.0, 1.0 - cos_o * cos_o);
    let sin_i2 = sin_o2 / (eta * eta);
    let cos_i = sqrt(max(0.0, 1.0 - sin_i2));
    let rs = (cos_o - eta * cos_i) / (cos_o + eta * cos_i);
    let rp = (eta * cos_o - cos_i) / (eta * cos_o + cos_i);
    return 1.0 - 0.5 * (rs * rs + rp * rp);
}

@fragment
fn fs_main(in: VsOut) -> @location(0) vec4<f32> {
    let n = normalize(in.normal);
    let v = normalize(u.eye_eta.xyz - in.world);
    // Back faces (seen through dents or open meshes) use the flipped normal.
    let cos_o = clamp(abs(dot(n, v)), 0.0, 1.0);
    var radiance = in.radiance;
    if (u.params.z < 0.5) {
        radiance = radiance * fresnel_transmittance(cos_o, u.eye_eta.w);
    }
    var c = max(radiance * u.params.x, vec3<f32>(0.0));
    if (u.params.y < 0.5) {
        c = pow(min(c, vec3<f32>(1.0)), vec3<f32>(1.0 / 2.2));
    }
    return vec4<f32>(c, 1.0);
}
