// What lucent's mesh pass (mesh.wgsl) and lucent-bevy's material shader (lucent.wgsl) share of
// the exit term (Mertens 2003 §5.4): the exit lobe T(mu_o) and the lights' highlight. WGSL has
// no includes: both add this file to their source, after spot.wgsl and fresnel.wgsl, and both
// declare what it reads: the constants PI, MAX_LIGHTS and EXIT_SAMPLES, and the uniform `u`
// with `params` (x: eta, y: highlight strength, z: Blinn-Phong exponent), `counts` (x: lights
// in use), `lights` (each `position`, `intensity`, `spot` as mesh.wgsl's Light) and
// `exit_lobe` (EXIT_SAMPLES samples, rgb).

// The exit lobe T at exit cosine cos_o, interpolated linearly as lucent-core's ExitLobe::at.
fn exit_lobe(cos_o: f32) -> vec3<f32> {
    let x = clamp(cos_o, 0.0, 1.0) * f32(EXIT_SAMPLES - 1u);
    let k = min(u32(x), EXIT_SAMPLES - 2u);
    return mix(u.exit_lobe[k].rgb, u.exit_lobe[k + 1u].rgb, x - f32(k));
}

// `l` plus the highlight of each light in turn at the point `world` with unit normal `n` and
// unit direction to the eye `v`: a normalised Blinn-Phong lobe weighted by the Fresnel
// reflectance at the half vector (the light the surface reflects is the light it does not
// transmit).
fn add_highlight(l_in: vec3<f32>, world: vec3<f32>, n: vec3<f32>, v: vec3<f32>, eta: f32) -> vec3<f32> {
    var l = l_in;
    let spec = u.params.y;
    let shininess = u.params.z;
    let count = min(u.counts.x, MAX_LIGHTS);
    for (var i = 0u; i < count; i = i + 1u) {
        let light = u.lights[i];
        var wi: vec3<f32>;
        var e: vec3<f32>;
        if (light.position.w > 0.5) {
            let d = light.position.xyz - world;
            let d2 = max(dot(d, d), 1e-12);
            wi = d * inverseSqrt(d2);
            e = light.intensity.rgb / d2 * spot_falloff(dot(light.spot.xyz, -wi), light.spot.w, light.intensity.w);
        } else {
            wi = -normalize(light.position.xyz);
            e = light.intensity.rgb;
        }
        let cos_i = dot(n, wi);
        if (cos_i > 0.0) {
            let h = normalize(wi + v);
            let lobe = (shininess + 8.0) / (8.0 * PI) * pow(max(dot(n, h), 0.0), shininess);
            l += spec * fresnel_dielectric(dot(h, v), eta) * lobe * cos_i * e;
        }
    }
    return l;
}
