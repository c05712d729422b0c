// Tone mapping of the HTSM HDR image to 8 bits: the exposure curve 1 - exp(-exposure * L)
// (linear for small L, never clips), then the sRGB transfer curve.

@group(0) @binding(0) var hdr: texture_2d<f32>;
@group(0) @binding(1) var<uniform> exposure: vec4<f32>;

@vertex
fn vs_fullscreen(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

fn srgb_encode(c: vec3<f32>) -> vec3<f32> {
    let lo = c * 12.92;
    let hi = 1.055 * pow(c, vec3<f32>(1.0 / 2.4)) - 0.055;
    return select(hi, lo, c <= vec3<f32>(0.0031308));
}

@fragment
fn fs_tonemap(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    let c = textureLoad(hdr, vec2<i32>(floor(frag.xy)), 0);
    let mapped = srgb_encode(1.0 - exp(-max(c.rgb, vec3<f32>(0.0)) * exposure.x));
    return vec4<f32>(mapped, 1.0);
}
