// Mesh pass (Mertens 2003 §5.4): Gouraud-interpolated per-vertex diffuse radiance B/pi and
// single-scattered radiance (interpolated geometrically: it falls off exponentially across a
// face near the terminator, where a linear blend overstates it many times), times the exit
// Fresnel transmittance F_t(eta, w_o) per pixel (eq. 3) and, for the diffuse part, the exit
// lobe T(mu_o) (lucent_core::bssrdf::ExitLobe; 1 for the paper's), plus a Fresnel-weighted
// Blinn-Phong highlight for the lights and an optional Fresnel-weighted environment reflection.
// Output: HDR radiance in rgb, coverage 1 in alpha (the tone-map pass composites the background
// where alpha is 0).

const PI: f32 = 3.14159265358979;
const MAX_LIGHTS: u32 = 8u;
// Samples of the exit lobe (ExitLobe::COUNT), at mu_o = k / (EXIT_SAMPLES - 1).
const EXIT_SAMPLES: u32 = 33u;

struct Light {
    // xyz: position (mesh units) when w = 1; direction the light travels when w = 0.
    position: vec4<f32>,
    // rgb: radiant intensity (point, spot on its axis, W/sr) or irradiance (directional, W/m^2);
    // w: a spot's soft-edge fraction (0..1).
    intensity: vec4<f32>,
    // xyz: a spot's unit axis (the way it shines); w: cone half-angle, radians (> pi: no cone).
    spot: vec4<f32>,
};

struct Uniforms {
    view_proj: mat4x4<f32>,
    // Clip space to world (mesh units), for the background's view rays.
    inv_view_proj: mat4x4<f32>,
    // xyz: eye position, mesh units.
    eye: vec4<f32>,
    // x: eta (relative index), y: specular strength (0 = none), z: Blinn-Phong exponent,
    // w: environment reflection strength (0 = none).
    params: vec4<f32>,
    // x: number of lights in use (<= MAX_LIGHTS); y: 1 to blend single scattering linearly
    // (the validation's ablation of the geometric blend), 0 geometrically.
    counts: vec4<u32>,
    // x: scale of the environment drawn behind the mesh (0 = none).
    background: vec4<f32>,
    lights: array<Light, MAX_LIGHTS>,
    // rgb: the exit lobe T(mu_o) per channel.
    exit_lobe: array<vec4<f32>, EXIT_SAMPLES>,
};

@group(0) @binding(0) var<uniform> u: Uniforms;
// Environment hook: an equirectangular HDR map (1x1 black until one is set).
@group(1) @binding(0) var env_map: texture_2d<f32>;
@group(1) @binding(1) var env_sampler: sampler;
// A mesh's colour texture, linear RGB (1x1 white without one): the radiance is multiplied by its
// square root per pixel, the exit half of the texture's modulation (the entry half scaled the
// irradiance before the solve).
@group(2) @binding(0) var albedo_map: texture_2d<f32>;
@group(2) @binding(1) var albedo_sampler: sampler;

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    // B / pi: diffuse exitant radiance before the exit Fresnel factor (HDR).
    @location(2) radiance: vec3<f32>,
    @location(3) uv: vec2<f32>,
    // Single-scattered radiance before the exit Fresnel factor (HDR, >= 0).
    @location(4) single: vec3<f32>,
};

// Below this a vertex's single scattering counts as none (HDR radiance; the log stays finite).
const SINGLE_FLOOR: f32 = 1e-30;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) radiance: vec3<f32>,
    @location(3) uv: vec2<f32>,
    // Centroid: with multisampling a pixel centre outside the face would extrapolate the
    // logarithm, and its exponential overshoots without bound.
    @location(4) @interpolate(perspective, centroid) log_single: vec3<f32>,
    // The same linearly, for the ablation of the geometric blend only.
    @location(5) single: vec3<f32>,
};

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    var o: VertexOut;
    o.clip = u.view_proj * vec4<f32>(v.position, 1.0);
    o.world = v.position;
    o.normal = v.normal;
    o.radiance = v.radiance;
    o.uv = v.uv;
    o.log_single = log(max(v.single, vec3<f32>(SINGLE_FLOOR)));
    o.single = v.single;
    return o;
}

// fresnel_dielectric: fresnel.wgsl, prepended.

// exit_lobe, add_highlight: exit.wgsl, prepended.

// spot_falloff: spot.wgsl, prepended.

fn equirect_uv(d: vec3<f32>) -> vec2<f32> {
    let u_ = atan2(d.x, -d.z) / (2.0 * PI) + 0.5;
    let v_ = acos(clamp(d.y, -1.0, 1.0)) / PI;
    return vec2<f32>(u_, v_);
}

@fragment
fn fs_main(in: VertexOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    let eta = u.params.x;
    let v = normalize(u.eye.xyz - in.world);
    // The side seen: flipped only where the winding and the shading normal both say it is the
    // back (the inside of a far wall through a hole). Decimated scans hold faces folded over,
    // whose winding opposes their vertices' normals; by the winding alone they showed their
    // inside (black specks on the 11K-203K dragons).
    var n = normalize(in.normal);
    if (!front && dot(n, v) < 0.0) {
        n = -n;
    }
    let cos_o = dot(n, v);
    // L = F_t(eta, w_o) (T(mu_o) B / (c pi) + L_single) (Mertens eq. 3, §5.4, with the exit
    // lobe), times sqrt(texture) at exit.
    let albedo = sqrt(max(textureSampleLevel(albedo_map, albedo_sampler, in.uv, 0.0).rgb, vec3<f32>(0.0)));
    var single = exp(in.log_single);
    if (u.counts.y == 1u) {
        single = max(in.single, vec3<f32>(0.0));
    }
    let subsurface = max(in.radiance, vec3<f32>(0.0)) * exit_lobe(cos_o) + single;
    var l = (1.0 - fresnel_dielectric(cos_o, eta)) * subsurface * albedo;

    // Highlight: normalised Blinn-Phong lobe weighted by the Fresnel reflectance at the
    // half vector (the light the surface reflects is the light it does not transmit).
    if (u.params.y > 0.0 && cos_o > 0.0) {
        l = add_highlight(l, in.world, n, v, eta);
    }

    // Environment reflection hook, weighted by F_r(eta, w_o) like the paper's reflection map.
    let env = u.params.w;
    if (env > 0.0 && cos_o > 0.0) {
        let r = reflect(-v, n);
        let c = textureSampleLevel(env_map, env_sampler, equirect_uv(r), 0.0).rgb;
        l += env * fresnel_dielectric(cos_o, eta) * c;
    }
    return vec4<f32>(l, 1.0);
}

// Background: a full-screen triangle showing the environment map along each pixel's view ray
// (drawn first, without depth, so the mesh covers it). Alpha 1: tone mapped like the mesh.
struct BackgroundOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) ndc: vec2<f32>,
};

@vertex
fn vs_background(@builtin(vertex_index) i: u32) -> BackgroundOut {
    let xy = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u)) * 2.0 - 1.0;
    var o: BackgroundOut;
    o.clip = vec4<f32>(xy, 0.0, 1.0);
    o.ndc = xy;
    return o;
}

@fragment
fn fs_background(in: BackgroundOut) -> @location(0) vec4<f32> {
    let near = u.inv_view_proj * vec4<f32>(in.ndc, 0.0, 1.0);
    let far = u.inv_view_proj * vec4<f32>(in.ndc, 1.0, 1.0);
    let d = normalize(far.xyz / far.w - near.xyz / near.w);
    let c = textureSampleLevel(env_map, env_sampler, equirect_uv(d), 0.0).rgb;
    return vec4<f32>(u.background.x * c, 1.0);
}
