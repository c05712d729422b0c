// HTSM pass 1 (Shopf 2007 §4.3, fig. 4.2): the mesh seen from the light, into three reference
// images. Alpha is coverage (1 on the mesh, 0 where the clear colour remains), so the mip pass
// can average the texture coordinate and normal over covered texels only.

struct LightVarying {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
}

struct ReferenceTexel {
    // Irradiance transmitted through the surface (Fresnel, Schlick) times the light colour.
    @location(0) irradiance: vec4<f32>,
    // 3D texture coordinate of the lit surface.
    @location(1) texcoord: vec4<f32>,
    // Unit surface normal.
    @location(2) normal: vec4<f32>,
}

@vertex
fn vs_light(v: VertexIn) -> LightVarying {
    var out: LightVarying;
    out.clip = g.light_view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.normal = v.normal;
    return out;
}

@fragment
fn fs_light(in: LightVarying) -> ReferenceTexel {
    var n = normalize(in.normal);
    let l = light_at(in.world);
    // The nearest surface along a light ray faces the light on a closed mesh; interpolated
    // normals can still tilt slightly away at the silhouette, so clamp rather than flip.
    let cos_i = max(dot(n, l.to_light), 0.0);
    let transmitted = 1.0 - fresnel_schlick(cos_i, g.kernel.y);
    var out: ReferenceTexel;
    out.irradiance = vec4<f32>(l.irradiance * cos_i * transmitted, 1.0);
    out.texcoord = vec4<f32>(texcoord_of(in.world), 1.0);
    out.normal = vec4<f32>(n, 1.0);
    return out;
}
