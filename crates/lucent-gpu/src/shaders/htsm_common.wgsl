// Shared declarations of the HTSM passes (Shopf 2007, §4.3). Prepended to every HTSM shader
// except the mip pass. Lengths called "object units" are mesh units divided by the rest mesh's
// largest bounding-box side.

// Per frame: camera, volume box, material, and the environment's surface terms.
struct Frame {
    // Camera: world (mesh units) -> clip.
    view_proj: mat4x4<f32>,
    // xyz: minimum corner of the rest mesh's bounding box (mesh units).
    box_min: vec4<f32>,
    // xyz: size of the rest bounding box (mesh units); w: 1 / largest side (mesh -> object units).
    box_size: vec4<f32>,
    // xyz: camera position (mesh units).
    eye: vec4<f32>,
    // rgb: transport colour T_c; w: transport distance T_d (object units).
    transport: vec4<f32>,
    // The medium (htsm/medium.rs), 1 / object units: the ray cast integrates
    // sigma_tr(rho) = sqrt(3 a (a + s)) with a = sigma.rgb + rho * density_absorption.rgb and
    // s = scatter.rgb. rgb: base absorption; w: unused.
    sigma: vec4<f32>,
    // rgb: reduced scattering sigma_s'; w: unused.
    scatter: vec4<f32>,
    // rgb: absorption added at density 1; w: unused.
    density_absorption: vec4<f32>,
    // x: Schlick F0; y: shadow bias (object units); z: largest mip level of the density volume;
    // w: 1 when the mesh is deformed, 0 at rest (every deformation offset is then zero).
    material: vec4<f32>,
    // x: diffuse weight; y: specular weight; z: Blinn-Phong exponent; w: unused.
    shading: vec4<f32>,
    // x: samples n (1, 5, 9, 13); y: steps K; z: model (0 thesis, 1 Beer-Lambert, 2 diffusion);
    // w: largest side of the density volume (voxels).
    counts: vec4<f32>,
    // Environment (see htsm/environment.rs): x, y: cos and sin of the rotation taking world
    // directions to the map's frame (about +y); z: 1 when there is an environment; w: unused.
    env_frame: vec4<f32>,
    // rgb: SH coefficients of the Fresnel-transmitted irradiance (band weights of Schlick's
    // transmitted cosine times the radiance coefficients times the intensity).
    env_irradiance: array<vec4<f32>, 9>,
    // rgb: SH coefficients of the radiance times the intensity (glossy reflection).
    env_radiance: array<vec4<f32>, 9>,
    // The diffusion model (htsm/diffusion.rs; zeros for the other models), object units.
    // xyz: the annuli's boundaries r1/2, 1.5 r1, 3 r1; w: index of the outermost ring present.
    rings: vec4<f32>,
    // x: the boundary's A (z_b = 2 A / (3 sigma_t')); yzw: unused.
    boundary: vec4<f32>,
    // rgb at density d / 8 and incidence cosine k / 8 (entry 9 d + k): the half-space's albedo.
    albedo: array<vec4<f32>, 81>,
    // rgb at density d / 8 and diffusion optical depth x = (k / 8)^2 (entry 33 d + k): the
    // slab's transmittance times e^x.
    slab: array<vec4<f32>, 297>,
}

// Per light pass (a dynamic offset selects the light).
struct LightPass {
    // World -> light clip; its NDC xy maps to the reference images.
    view_proj: mat4x4<f32>,
    // w = 1: point or spot light at xyz (mesh units); w = 0: distant light travelling along xyz
    // (unit).
    position: vec4<f32>,
    // rgb: light colour (point, spot: intensity, irradiance per mesh unit^2 at distance 1;
    // distant: irradiance); w: the spot's soft-edge fraction (0..1).
    colour: vec4<f32>,
    // xyz: the spot's unit axis (the way it shines); w: the cone's half-angle in radians, 0 when
    // the light is not a spot.
    spot: vec4<f32>,
    // x: ring-1 radius (level-0 texels of the reference images); y: 1 when this light adds the
    // lit side's diffuse and specular terms (0 for the environment's directions); z: 1 when this
    // pass adds the environment's surface terms (the first pass of a frame); w: unused.
    flags: vec4<f32>,
}

@group(0) @binding(0) var<uniform> g: Frame;
@group(0) @binding(1) var<uniform> light: LightPass;

struct VertexIn {
    // Deformed position (mesh units).
    @location(0) position: vec3<f32>,
    // Deformed unit normal.
    @location(1) normal: vec3<f32>,
    // Rest position (mesh units): the 3D texture coordinate before the rest box's affine map.
    @location(2) rest: vec3<f32>,
}

// Position in the volume's [0,1]^3 box: the 3D texture coordinate of §4.3.2, of a rest position.
fn texcoord_of(p: vec3<f32>) -> vec3<f32> {
    return (p - g.box_min.xyz) / g.box_size.xyz;
}

// A texture-coordinate difference as a vector in object units (the box need not be a cube).
fn tc_to_object(d: vec3<f32>) -> vec3<f32> {
    return d * g.box_size.xyz * g.box_size.w;
}

// How far deformation moved a point: deformed minus rest position, object units. Exactly zero
// on an undeformed mesh, so rest renders do not depend on it.
fn deformation_of(world: vec3<f32>, rest: vec3<f32>) -> vec3<f32> {
    return (world - rest) * g.box_size.w;
}

// Schlick's approximation of the dielectric Fresnel reflectance.
fn fresnel_schlick(cos_theta: f32, f0: f32) -> f32 {
    let m = 1.0 - clamp(cos_theta, 0.0, 1.0);
    return f0 + (1.0 - f0) * m * m * m * m * m;
}

// spot_falloff: spot.wgsl, prepended.

// Unit direction from p towards the light, and the light's irradiance on a surface facing it.
struct LightAt {
    to_light: vec3<f32>,
    irradiance: vec3<f32>,
}

fn light_at(p: vec3<f32>) -> LightAt {
    var out: LightAt;
    if (light.position.w > 0.5) {
        let d = light.position.xyz - p;
        let d2 = max(dot(d, d), 1e-12);
        out.to_light = d * inverseSqrt(d2);
        out.irradiance = light.colour.rgb / d2;
        if (light.spot.w > 0.0) {
            out.irradiance = out.irradiance * spot_falloff(dot(light.spot.xyz, -out.to_light), light.spot.w, light.colour.w);
        }
    } else {
        out.to_light = -light.position.xyz;
        out.irradiance = light.colour.rgb;
    }
    return out;
}
