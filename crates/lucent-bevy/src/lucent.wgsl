// lucent's exit term in Bevy's pipeline (Mertens 2003 §5.4, the mesh pass of lucent-gpu,
// `crates/lucent-gpu/src/shaders/mesh.wgsl`): per pixel
//   L = F_t(eta, w_o) (T(mu_o) B / (c pi) + L_single) + Fresnel-weighted Blinn-Phong highlight,
// with B / (c pi) and L_single per vertex from lucent's frame session (a storage buffer indexed
// by the vertex), Gouraud-interpolated (single scattering geometrically, as lucent's mesh pass),
// then multiplied by Bevy's camera exposure like every Bevy light (and tone mapped here where
// the camera tone maps in the material shaders, as Bevy's own materials do). Lights are in world units,
// already mapped from Bevy's lumens and lux (see `lights.rs`). lucent-gpu's spot.wgsl,
// fresnel.wgsl and exit.wgsl are appended to this file when the plugin builds the shader.

#import bevy_pbr::{
    mesh_bindings::mesh,
    mesh_functions,
    mesh_view_bindings::view,
    view_transformations::position_world_to_clip,
}
#ifdef TONEMAP_IN_SHADER
#import bevy_core_pipeline::tonemapping::tone_mapping
#endif

const PI: f32 = 3.14159265358979;
const MAX_LIGHTS: u32 = 8u;
const EXIT_SAMPLES: u32 = 33u;
const SINGLE_FLOOR: f32 = 1e-30;

struct LucentLight {
    // xyz: world position when w = 1; the direction the light travels when w = 0.
    position: vec4<f32>,
    // rgb: intensity (point, spot on its axis: cd) or illuminance (directional: lux);
    // w: a spot's soft-edge fraction (0..1).
    intensity: vec4<f32>,
    // xyz: a spot's unit axis in the world; w: cone half-angle, radians (> pi: no cone).
    spot: vec4<f32>,
};

struct LucentShading {
    // x: eta, y: specular strength (0 = none), z: Blinn-Phong exponent, w: unused.
    params: vec4<f32>,
    // x: lights in use (<= MAX_LIGHTS); y: 1 to blend single scattering linearly.
    counts: vec4<u32>,
    lights: array<LucentLight, 8>,
    // rgb: the exit lobe T(mu_o) at mu_o = k / (EXIT_SAMPLES - 1).
    exit_lobe: array<vec4<f32>, 33>,
};

// One record per vertex of the Bevy mesh: rgb of B / (c pi) and of single scattering, before
// the exit Fresnel factor (lucent_core::session::Solved).
struct VertexRadiance {
    radiance: vec4<f32>,
    single: vec4<f32>,
};

// `u`, as lucent's mesh pass names its uniform: exit.wgsl reads it.
@group(#{MATERIAL_BIND_GROUP}) @binding(0) var<uniform> u: LucentShading;
@group(#{MATERIAL_BIND_GROUP}) @binding(1) var<storage, read> per_vertex: array<VertexRadiance>;

struct Vertex {
    @builtin(instance_index) instance_index: u32,
    @builtin(vertex_index) index: u32,
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
};

struct VertexOutput {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) radiance: vec3<f32>,
    @location(3) @interpolate(perspective, centroid) log_single: vec3<f32>,
    @location(4) single: vec3<f32>,
};

@vertex
fn vertex(v: Vertex) -> VertexOutput {
    var o: VertexOutput;
    let world_from_local = mesh_functions::get_world_from_local(v.instance_index);
    let world = mesh_functions::mesh_position_local_to_world(world_from_local, vec4<f32>(v.position, 1.0));
    o.world = world.xyz;
    o.clip = position_world_to_clip(world.xyz);
    o.normal = mesh_functions::mesh_normal_local_to_world(v.normal, v.instance_index);
    // Bevy packs meshes into shared buffers: the index within this mesh.
    let i = v.index - mesh[v.instance_index].first_vertex_index;
    var r = VertexRadiance(vec4<f32>(0.0), vec4<f32>(0.0));
    if (i < arrayLength(&per_vertex)) {
        r = per_vertex[i];
    }
    o.radiance = r.radiance.rgb;
    o.log_single = log(max(r.single.rgb, vec3<f32>(SINGLE_FLOOR)));
    o.single = r.single.rgb;
    return o;
}

// fresnel_dielectric (fresnel.wgsl), exit_lobe and add_highlight (exit.wgsl, which reads the
// uniform `u`): appended.

@fragment
fn fragment(in: VertexOutput, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    let eta = u.params.x;
    let v = normalize(view.world_position - in.world);
    // The side seen: flipped only where the winding and the normal both say it is the back.
    var n = normalize(in.normal);
    if (!front && dot(n, v) < 0.0) {
        n = -n;
    }
    let cos_o = dot(n, v);
    var single = exp(in.log_single);
    if (u.counts.y == 1u) {
        single = max(in.single, vec3<f32>(0.0));
    }
    let subsurface = max(in.radiance, vec3<f32>(0.0)) * exit_lobe(cos_o) + single;
    var l = (1.0 - fresnel_dielectric(cos_o, eta)) * subsurface;
    if (u.params.y > 0.0 && cos_o > 0.0) {
        l = add_highlight(l, in.world, n, v, eta);
    }
    var out = vec4<f32>(l * view.exposure, 1.0);
#ifdef TONEMAP_IN_SHADER
    // A camera without HDR tone maps in each material's shader, as Bevy's own do.
    out = tone_mapping(out, view.color_grading);
#endif
    return out;
}
