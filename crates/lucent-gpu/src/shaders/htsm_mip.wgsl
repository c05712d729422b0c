// HTSM mip generation (Shopf 2007 §4.3.1): each texel of level k is the mean of the 2x2 texels
// of level k-1 it covers. Level 0 holds coverage in alpha and colour premultiplied by it (1 or
// 0), so plain averages stay premultiplied: the sampler divides by alpha to get the mean over
// covered texels only, and irradiance (used without division) is the mean over the area.

@group(0) @binding(0) var src_irradiance: texture_2d<f32>;
@group(0) @binding(1) var src_texcoord: texture_2d<f32>;
@group(0) @binding(2) var src_normal: texture_2d<f32>;
@group(0) @binding(3) var src_deformation: texture_2d<f32>;

struct MipOut {
    @location(0) irradiance: vec4<f32>,
    @location(1) texcoord: vec4<f32>,
    @location(2) normal: vec4<f32>,
    @location(3) deformation: vec4<f32>,
}

@vertex
fn vs_fullscreen(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    // One triangle that covers the viewport.
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

fn mean4(t: texture_2d<f32>, p: vec2<i32>) -> vec4<f32> {
    return 0.25 * (textureLoad(t, p, 0) + textureLoad(t, p + vec2<i32>(1, 0), 0)
        + textureLoad(t, p + vec2<i32>(0, 1), 0) + textureLoad(t, p + vec2<i32>(1, 1), 0));
}

@fragment
fn fs_mip(@builtin(position) frag: vec4<f32>) -> MipOut {
    let p = vec2<i32>(floor(frag.xy)) * 2;
    var out: MipOut;
    out.irradiance = mean4(src_irradiance, p);
    out.texcoord = mean4(src_texcoord, p);
    out.normal = mean4(src_normal, p);
    out.deformation = mean4(src_deformation, p);
    return out;
}
