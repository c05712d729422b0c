// HTSM pass 1 (Shopf 2007 §4.3, fig. 4.2): the mesh seen from one light, into the reference
// images. Alpha is coverage (1 on the mesh, 0 where the clear colour remains), so the mip pass
// can average the other channels over covered texels only. A fourth image, not in the thesis,
// holds how far deformation moved the lit surface, so that the camera pass can measure the
// deformed ray length D_i while it marches in rest texture space.

struct LightVarying {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) rest: vec3<f32>,
}

struct ReferenceTexel {
    // Irradiance transmitted through the surface (Fresnel, Schlick) times the light colour
    // (and the spot's falloff).
    @location(0) irradiance: vec4<f32>,
    // 3D texture coordinate of the lit surface's rest position.
    @location(1) texcoord: vec4<f32>,
    // Unit surface normal (deformed).
    @location(2) normal: vec4<f32>,
    // Deformed minus rest position of the lit surface, object units.
    @location(3) deformation: vec4<f32>,
}

@vertex
fn vs_light(v: VertexIn) -> LightVarying {
    var out: LightVarying;
    out.clip = light.view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.normal = v.normal;
    out.rest = v.rest;
    return out;
}

@fragment
fn fs_light(in: LightVarying) -> ReferenceTexel {
    var n = normalize(in.normal);
    let l = light_at(in.world);
    // The nearest surface along a light ray faces the light on a closed mesh; interpolated
    // normals can still tilt slightly away at the silhouette, so clamp rather than flip.
    let cos_i = max(dot(n, l.to_light), 0.0);
    let transmitted = 1.0 - fresnel_schlick(cos_i, g.material.x);
    var out: ReferenceTexel;
    out.irradiance = vec4<f32>(l.irradiance * cos_i * transmitted, 1.0);
    out.texcoord = vec4<f32>(texcoord_of(in.rest), 1.0);
    out.normal = vec4<f32>(n, 1.0);
    out.deformation = vec4<f32>(deformation_of(in.world, in.rest), 1.0);
    return out;
}
