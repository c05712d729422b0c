// Tone mapping (Mertens 2003 §5.4: "a simple gamma curve per pixel"): exposure, an optional
// filmic curve (Narkowicz's ACES fit), clamp, gamma encode; then the background is composited
// where the HDR target has no coverage. Full-screen triangle; one HDR texel per output pixel.

struct ToneUniforms {
    // x: exposure multiplier, y: 1 / gamma, z: operator (0 gamma only, 1 ACES fit then gamma),
    // w: 1 when the target is an sRGB format (the hardware will encode: undo it here).
    params: vec4<f32>,
    // rgb: background colour, display-encoded (0..1).
    background: vec4<f32>,
};

@group(0) @binding(0) var<uniform> t: ToneUniforms;
@group(0) @binding(1) var hdr: texture_2d<f32>;

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    // One triangle covering the viewport: (-1,-1), (3,-1), (-1,3).
    let x = f32(i32(i & 1u) * 4 - 1);
    let y = f32(i32(i >> 1u) * 4 - 1);
    return vec4<f32>(x, y, 0.0, 1.0);
}

fn aces_fit(x: vec3<f32>) -> vec3<f32> {
    return (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14);
}

fn srgb_to_linear(c: vec3<f32>) -> vec3<f32> {
    let lo = c / 12.92;
    let hi = pow((c + 0.055) / 1.055, vec3<f32>(2.4));
    return select(hi, lo, c <= vec3<f32>(0.04045));
}

@fragment
fn fs_main(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    let texel = textureLoad(hdr, vec2<i32>(pos.xy), 0);
    let coverage = clamp(texel.a, 0.0, 1.0);
    // Multisample resolve averaged radiance with the cleared (0, 0, 0, 0) background:
    // un-premultiply so edge pixels are tone mapped like the object, then blend.
    var c = max(texel.rgb, vec3<f32>(0.0)) / max(coverage, 1e-4) * t.params.x;
    if (t.params.z > 0.5) {
        c = aces_fit(c);
    }
    c = pow(clamp(c, vec3<f32>(0.0), vec3<f32>(1.0)), vec3<f32>(t.params.y));
    c = mix(t.background.rgb, c, coverage);
    if (t.params.w > 0.5) {
        c = srgb_to_linear(c);
    }
    return vec4<f32>(c, 1.0);
}
