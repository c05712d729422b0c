// Shared declarations of the HTSM passes (Shopf 2007, §4.3). Prepended to every HTSM shader.
// Lengths called "object units" are mesh units divided by the mesh's largest bounding-box side.

struct Globals {
    // Camera: world (mesh units) -> clip.
    view_proj: mat4x4<f32>,
    // Light: world -> light clip; its NDC xy maps to the reference images.
    light_view_proj: mat4x4<f32>,
    // xyz: minimum corner of the bounding box (mesh units).
    box_min: vec4<f32>,
    // xyz: size of the bounding box (mesh units); w: 1 / largest side (mesh -> object units).
    box_size: vec4<f32>,
    // xyz: camera position (mesh units).
    eye: vec4<f32>,
    // w = 1: point light at xyz (mesh units); w = 0: distant light travelling along xyz (unit).
    light: vec4<f32>,
    // rgb: light colour (point: intensity per mesh unit^2 at distance 1; distant: irradiance).
    light_colour: vec4<f32>,
    // rgb: transport colour T_c; w: transport distance T_d (object units).
    transport: vec4<f32>,
    // rgb: Beer-Lambert attenuation sigma = -ln(T_c) / T_d (1 / object units); w: density scale
    // (extra absorption of density 1, 1 / object units).
    sigma: vec4<f32>,
    // x: ring-1 radius (level-0 texels of the reference images); y: Schlick F0;
    // z: shadow bias (object units); w: largest mip level of the density volume.
    kernel: vec4<f32>,
    // x: diffuse weight; y: specular weight; z: Blinn-Phong exponent; w: unused.
    shading: vec4<f32>,
    // x: samples n (1, 5, 9, 13); y: steps K; z: model (0 thesis, 1 Beer-Lambert);
    // w: largest side of the density volume (voxels).
    counts: vec4<f32>,
}

@group(0) @binding(0) var<uniform> g: Globals;

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
}

// Position in the volume's [0,1]^3 box: the 3D texture coordinate of §4.3.2.
fn texcoord_of(p: vec3<f32>) -> vec3<f32> {
    return (p - g.box_min.xyz) / g.box_size.xyz;
}

// A texture-coordinate difference as a vector in object units (the box need not be a cube).
fn tc_to_object(d: vec3<f32>) -> vec3<f32> {
    return d * g.box_size.xyz * g.box_size.w;
}

// Schlick's approximation of the dielectric Fresnel reflectance.
fn fresnel_schlick(cos_theta: f32, f0: f32) -> f32 {
    let m = 1.0 - clamp(cos_theta, 0.0, 1.0);
    return f0 + (1.0 - f0) * m * m * m * m * m;
}

// Unit direction from p towards the light, and the light's irradiance on a surface facing it.
struct LightAt {
    to_light: vec3<f32>,
    irradiance: vec3<f32>,
}

fn light_at(p: vec3<f32>) -> LightAt {
    var out: LightAt;
    if (g.light.w > 0.5) {
        let d = g.light.xyz - p;
        let d2 = max(dot(d, d), 1e-12);
        out.to_light = d * inverseSqrt(d2);
        out.irradiance = g.light_colour.rgb / d2;
    } else {
        out.to_light = -g.light.xyz;
        out.irradiance = g.light_colour.rgb;
    }
    return out;
}
