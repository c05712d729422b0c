// HTSM camera pass (Shopf 2007 §4.3.1-§4.3.5): the camera view, once per light. For each
// visible point, sample the reference images in the hierarchical pattern of fig. 4.3, ray cast
// the density volume from the point to each sample's lit surface (§4.3.2), weight by the phase
// function (§4.3.4) and sum with table 4.1's light transport approximation, then add surface
// shading on the lit side. The first light's pass writes the HDR target, later ones add to it.
//
// Deformation: the ray cast marches between rest texture coordinates (the density follows the
// mesh) while D_i is the length of the same ray on the deformed mesh (rest vector plus the
// difference of the two ends' deformation offsets).

@group(1) @binding(0) var ref_irradiance: texture_2d<f32>;
@group(1) @binding(1) var ref_texcoord: texture_2d<f32>;
@group(1) @binding(2) var ref_normal: texture_2d<f32>;
@group(1) @binding(3) var ref_sampler: sampler;
@group(1) @binding(4) var density: texture_3d<f32>;
@group(1) @binding(5) var density_sampler: sampler;
// Henyey-Greenstein phase table indexed by cos(theta) * 0.5 + 0.5 (a 256x1 2D texture: GLES,
// one of our backends, has no 1D textures).
@group(1) @binding(6) var phase_table: texture_2d<f32>;
// Deformed minus rest position of the lit surface (object units), premultiplied by coverage.
@group(1) @binding(7) var ref_deformation: texture_2d<f32>;

struct CameraVarying {
    // Invariant: later lights' passes test depth for equality with the first pass's.
    @invariant @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) rest: vec3<f32>,
}

@vertex
fn vs_camera(v: VertexIn) -> CameraVarying {
    var out: CameraVarying;
    out.clip = g.view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.normal = v.normal;
    out.rest = v.rest;
    return out;
}

// Offset (in units of the ring-1 radius) and mip-level increment of sample i of fig. 4.3: the
// centre at level 0, then rings of 4 at radius 1, 2, 4 and one level coarser per ring, each
// ring turned against the previous one so that the 13 samples do not line up.
fn pattern(i: i32) -> vec3<f32> {
    if (i == 0) {
        return vec3<f32>(0.0, 0.0, -1.0);
    }
    let ring = (i - 1) / 4;
    let k = f32((i - 1) % 4);
    let turn = select(select(0.392699082, 0.785398163, ring == 1), 0.0, ring == 0);
    let a = turn + k * 1.570796327;
    let radius = f32(1 << u32(ring));
    return vec3<f32>(radius * cos(a), radius * sin(a), f32(ring));
}

// Light-space position of world point p: reference-image uv in [0,1]^2.
fn light_uv(p: vec3<f32>) -> vec2<f32> {
    let c = light.view_proj * vec4<f32>(p, 1.0);
    let ndc = c.xy / c.w;
    return vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
}

@fragment
fn fs_camera(in: CameraVarying, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    // The side seen, chosen as mesh.wgsl does: flipped only where the winding and the shading
    // normal both say it is the back (the inside of a far wall through a hole), so faces a
    // decimation folded over keep their vertices' side.
    var n = normalize(in.normal);
    if (!front && dot(n, g.eye.xyz - in.world) < 0.0) {
        n = -n;
    }
    let tc = texcoord_of(in.rest);
    let moved = deformation_of(in.world, in.rest);
    let uv = light_uv(in.world);
    let map_size = vec2<f32>(textureDimensions(ref_irradiance, 0));
    let levels = f32(textureNumLevels(ref_irradiance));
    let samples = i32(g.counts.x);
    let steps = i32(g.counts.y);
    let beer_lambert = g.counts.z > 0.5;
    let diffusion = g.counts.z > 1.5;
    let t_d = g.transport.w;
    // Whether the light reaches this point (it is the lit surface the reference image holds):
    // the diffusion model's kernel is then the lit side's, else the light crossed the body.
    let l = light_at(in.world);
    let cos_i = dot(n, l.to_light);
    let ref_tc = textureSampleLevel(ref_texcoord, ref_sampler, uv, 0.0);
    let seen = ref_tc.a > 0.5 && length(tc_to_object(ref_tc.xyz / ref_tc.a - tc)) < g.material.y;
    let lit = cos_i > 0.0 && seen;

    // The diffusion model where the light crosses the body: the kernel spreads about as wide as
    // the body is deep below this point (the centre sample's depth h_0), so the pattern widens
    // to keep the kernel's middle inside its rings (ring 2 at h_0): the samples then see how
    // far the lit surface really extends (htsm/diffusion.rs).
    var spread = 1.0;
    // The chord from this point back along the light to the lit surface (object units).
    var chord = 0.0;
    if (diffusion && !lit && ref_tc.a > 1e-3) {
        let to_lit = tc_to_object(ref_tc.xyz / ref_tc.a - tc);
        let h_0 = dot(to_lit, -n);
        chord = length(to_lit);
        spread = max(1.0, 0.25 * h_0 / g.rings.x);
    }
    var transport = vec3<f32>(0.0);
    // The mean density along the centre sample's ray (the chord's medium) and its first step's
    // (next to this point: the view ray's medium).
    var rho_chord = 0.0;
    var rho_view = 0.0;
    for (var i = 0; i < samples; i = i + 1) {
        let s = pattern(i);
        let radius_texels = light.flags.x * spread;
        let offset = s.xy * radius_texels / map_size;
        // Ring r covers cells about as wide as its radius: level log2(radius in texels).
        var level = 0.0;
        if (s.z >= 0.0) {
            level = clamp(log2(max(radius_texels, 1.0)) + s.z, 0.0, levels - 1.0);
        }
        let suv = uv + offset;
        let irr = textureSampleLevel(ref_irradiance, ref_sampler, suv, level);
        // The centre sample (level 0 at uv) is the texel the lit test read.
        var tcc = ref_tc;
        if (i != 0) {
            tcc = textureSampleLevel(ref_texcoord, ref_sampler, suv, level);
        }
        // No lit surface under this sample (outside the silhouette): it brings no light.
        if (tcc.a < 1e-3) {
            continue;
        }
        let end = tcc.xyz / tcc.a;
        let dir = end - tc;
        // The ray on the deformed mesh, object units: its rest vector plus how much farther
        // deformation moved its end than its start (zero without deformation, where the
        // offset image holds zeros and is not read).
        var end_moved = vec3<f32>(0.0);
        if (g.material.w > 0.5) {
            end_moved = textureSampleLevel(ref_deformation, ref_sampler, suv, level).xyz / tcc.a;
        }
        let ray = tc_to_object(dir) + (end_moved - moved);
        let d_i = length(ray);

        // Fixed-step ray cast through the density volume (§4.3.2) in rest texture space, midpoint
        // rule, each step D_i / K long on the deformed mesh. The mip level follows the step
        // length so a coarse march averages, rather than aliases, fine detail (the 3D mip
        // filtering the thesis could not have, §5.1).
        let step_voxels = length(dir) * g.counts.w / f32(steps);
        let lod = clamp(log2(max(step_voxels, 1.0)), 0.0, g.material.z);
        let a0 = g.sigma.rgb;
        let s0 = g.scatter.rgb;
        let sigma0 = sqrt(3.0 * a0 * (a0 + s0));
        var sum = vec3<f32>(0.0);
        var rho_sum = 0.0;
        for (var j = 0; j < steps; j = j + 1) {
            let t = (f32(j) + 0.5) / f32(steps);
            let rho = textureSampleLevel(density, density_sampler, tc + dir * t, lod).r;
            if (i == 0 && j == 0) {
                rho_view = rho;
            }
            let a = a0 + rho * g.density_absorption.rgb;
            sum = sum + sqrt(3.0 * a * (a + s0));
            rho_sum = rho_sum + rho;
        }
        // Optical depth along the ray (the medium's sigma_tr integrated, htsm/medium.rs), and
        // alpha_i, the density's part of it (eq. 4.1's extra absorption).
        let tau = sum * d_i / f32(steps);
        let alpha_i = max(tau - sigma0 * d_i, vec3<f32>(0.0));

        // theta_i: between the sample ray and -N (§4.3.4).
        var cos_theta = 1.0;
        if (d_i > 1e-6) {
            cos_theta = dot(ray / d_i, -n);
        }
        if (i == 0) {
            rho_chord = rho_sum / f32(steps);
        }
        if (diffusion) {
            // htsm/diffusion.rs: the kernel of the medium along the ray (its mean density, its
            // mean sigma_tr) integrated over the sample's annulus, times its total: the
            // half-space's albedo on the lit side, else the slab's transmittance.
            let ring = i32(s.z) + 1;
            let rho_mean = rho_sum / f32(steps);
            let m = medium_at(rho_mean);
            let sigma_mean = sum / f32(steps);
            if (lit) {
                let share = annulus_share(ring, 1.0, m.z_r, m.z_b, sigma_mean);
                transport = transport + irr.rgb * share * albedo_at(rho_mean, cos_i);
            } else {
                // The kernel's source lies at the depth h below this point's tangent plane.
                let h = max(d_i * cos_theta, 0.0);
                let share = annulus_share(ring, spread, max(vec3<f32>(h), m.z_r), m.z_b, sigma_mean);
                // The ray is the sample's light-view offset, whose attenuation the annulus share
                // already weighs, plus its extent along the light: the slab is that extent thick
                // (the whole ray counted the offset twice).
                let crossed = max(dot(ray, l.to_light), 0.0);
                transport = transport + irr.rgb * share * slab_transmittance(rho_mean, sigma_mean * crossed);
            }
        } else if (beer_lambert) {
            // Transmittance exp(-sigma D_i - alpha_i): the optical depth of the medium's
            // transport coefficient along the ray.
            transport = transport + irr.rgb * exp(-tau) * phase_at(cos_theta);
        } else {
            // Table 4.1. The printed equation has no irradiance term, yet light that reaches a
            // lit surface must scale what comes out: each ray carries its sample's irradiance.
            // The bracket is negative once D_i + alpha_i > 2 T_d, which would subtract light,
            // so it is clamped at zero: paths that long transmit nothing.
            let bracket = max((2.0 * t_d - (d_i + alpha_i)) / t_d, vec3<f32>(0.0));
            transport = transport + irr.rgb * bracket * phase_at(cos_theta);
        }
    }
    if (!diffusion) {
        transport = transport / f32(samples);
    }
    if (!beer_lambert) {
        transport = transport * g.transport.rgb;
    }
    // Exitant radiance of a Lambertian exit: irradiance / pi.
    var radiance = transport / 3.14159265;
    // Light that crossed the body leaves forward-peaked: diffusion's exit lobe at an
    // index-matched boundary, (1 + 1.5 mu_o) / 2 of a Lambertian exit's radiance (a walked
    // slab 6.6 mean free paths thick: 1.21 and 0.83 at mu_o 0.95 and 0.45, this 1.21 and 0.84).
    if (diffusion && !lit) {
        let mu_o = clamp(dot(n, normalize(g.eye.xyz - in.world)), 0.0, 1.0);
        radiance = radiance * (0.5 + 0.75 * mu_o);
    }
    // The slab's table holds multiple scattering only: where the light crossed the body, the
    // light scattered once along the view ray comes on top (the lit side's albedo includes it).
    if (diffusion && !lit && ref_tc.a > 1e-3) {
        radiance = radiance + view_single_scattering(in.world, in.rest, chord, rho_chord, rho_view, l);
    }

    // Surface shading where the surface faces the light and is not occluded: the lit surface
    // seen by the light at this point's light-space position must be this point itself.
    // Compared in rest texture space: a surface point's rest coordinate identifies it whatever the
    // deformation.
    if (lit && light.flags.y > 0.5) {
        let v = normalize(g.eye.xyz - in.world);
        let h = normalize(v + l.to_light);
        let e = l.irradiance * cos_i;
        let diffuse = g.shading.x * g.transport.rgb * e * (1.0 - fresnel_schlick(cos_i, g.material.x)) / 3.14159265;
        // Normalised Blinn-Phong with Schlick's Fresnel at the half vector.
        let shininess = g.shading.z;
        let spec = g.shading.y * fresnel_schlick(dot(v, h), g.material.x) * (shininess + 8.0) / (8.0 * 3.14159265) * pow(max(dot(n, h), 0.0), shininess);
        radiance = radiance + diffuse + spec * e;
    }
    if (light.flags.z > 0.5) {
        radiance = radiance + environment_surface(in.world, n);
    }
    return vec4<f32>(radiance, 1.0);
}

// Radiance scattered once along the view ray where the light crossed the body (the slab's
// transmittance counts multiple scattering only): L = E / (4 pi) integral sigma_s e^(-f(s)) ds
// with f(s) = sigma_t s + sigma_t c(s), over the depth s (object units) along the view ray,
// c(s) the chord from the point at depth s back along the light to the lit surface (the
// reference image's texel above it), E the light's irradiance across its beam, isotropic
// scattering (the medium's sigma_s = sigma_s'). c(0) = c_0, the centre sample's ray; c is read
// at depths of 0.5 and 2 mean free paths and taken linear between and beyond them (f is then
// linear and each piece's integral exact; a slab's chords are linear). The view ray's medium is
// the density next to the point (rho_view, the centre ray's first step), the chord's the
// centre ray's mean (rho_chord). Chords are rest-pose lengths (a deformation's stretch is not
// in them). Unrefracted, no Fresnel factors: exact at eta = 1 (the validation's), an
// approximation otherwise.
fn view_single_scattering(world: vec3<f32>, rest: vec3<f32>, c_0: f32, rho_chord: f32, rho_view: f32, l: LightAt) -> vec3<f32> {
    let t_view = g.sigma.rgb + rho_view * g.density_absorption.rgb + g.scatter.rgb;
    let t_chord = g.sigma.rgb + rho_chord * g.density_absorption.rgb + g.scatter.rgb;
    let t_mean = (t_view.x + t_view.y + t_view.z) / 3.0;
    // Into the body along the view ray, mesh units per object unit of depth.
    let into = normalize(world - g.eye.xyz) / g.box_size.w;
    var s_a = 0.0;
    var c_a = c_0;
    var sum = vec3<f32>(0.0);
    for (var k = 0; k < 2; k = k + 1) {
        let s_b = select(2.0, 0.5, k == 0) / t_mean;
        let p = world + into * s_b;
        let lit_tc = textureSampleLevel(ref_texcoord, ref_sampler, light_uv(p), 0.0);
        if (lit_tc.a < 0.5) {
            // No lit surface above this depth: the view ray has left the body.
            return l.irradiance * g.scatter.rgb * sum / (4.0 * 3.14159265);
        }
        let c_b = length(tc_to_object(lit_tc.xyz / lit_tc.a - texcoord_of(rest + into * s_b)));
        sum = sum + exp_segment(t_view * s_a + t_chord * c_a, t_view * s_b + t_chord * c_b, s_b - s_a);
        if (k == 1) {
            // Beyond the last depth the chord goes on linearly: where it shrinks, the view
            // ray leaves through the lit face when it reaches zero (exact for a slab).
            let dc = (c_b - c_a) / (s_b - s_a);
            let f_b = t_view * s_b + t_chord * c_b;
            if (dc < 0.0) {
                let len = c_b / -dc;
                sum = sum + exp_segment(f_b, f_b + t_view * len - t_chord * c_b, len);
            } else {
                sum = sum + exp(-f_b) / (t_view + t_chord * dc);
            }
        }
        s_a = s_b;
        c_a = c_b;
    }
    return l.irradiance * g.scatter.rgb * sum / (4.0 * 3.14159265);
}

// The integral of e^(-f) over a segment `len` long on which f goes linearly from f_a to f_b.
fn exp_segment(f_a: vec3<f32>, f_b: vec3<f32>, len: f32) -> vec3<f32> {
    let df = f_b - f_a;
    let flat = abs(df) < vec3<f32>(1e-4);
    let mean = (exp(-f_a) - exp(-f_b)) / select(df, vec3<f32>(1.0), flat);
    return len * select(mean, exp(-f_a), flat);
}

// The phase function f(theta_i) of §4.3.4 from its table (the thesis and Beer-Lambert models
// weigh each sample by it; the diffusion kernel is isotropic and does not read it).
fn phase_at(cos_theta: f32) -> f32 {
    return textureSampleLevel(phase_table, ref_sampler, vec2<f32>(cos_theta * 0.5 + 0.5, 0.5), 0.0).r;
}

// The medium at density rho (htsm/medium.rs), object units: the dipole's source depth z_r = 1 / sigma_t' and extrapolation distance z_b = 2 A / (3 sigma_t').
struct LocalMedium {
    z_r: vec3<f32>,
    z_b: vec3<f32>,
}

fn medium_at(rho: f32) -> LocalMedium {
    let t = max(g.sigma.rgb + rho * g.density_absorption.rgb + g.scatter.rgb, vec3<f32>(1e-12));
    var m: LocalMedium;
    m.z_r = 1.0 / t;
    m.z_b = 2.0 * g.boundary.x / (3.0 * t);
    return m;
}

// Bilinear lookup position in a table over density (9 levels) and a second coordinate x in
// entry units (`count` entries): the two density rows' first entries and the weights.
struct TableAt {
    row0: u32,
    row1: u32,
    fd: f32,
    i: u32,
    fx: f32,
}

fn table_at(rho: f32, x: f32, count: u32) -> TableAt {
    var t: TableAt;
    let d = clamp(rho, 0.0, 1.0) * 8.0;
    let d0 = min(u32(d), 7u);
    t.row0 = d0 * count;
    t.row1 = (d0 + 1u) * count;
    t.fd = d - f32(d0);
    let xc = clamp(x, 0.0, f32(count - 1u));
    t.i = min(u32(xc), count - 2u);
    t.fx = xc - f32(t.i);
    return t;
}

// The half-space's albedo at density rho and incidence cosine c (htsm/diffusion.rs's table).
fn albedo_at(rho: f32, c: f32) -> vec3<f32> {
    let t = table_at(rho, clamp(c, 0.0, 1.0) * 8.0, 9u);
    let a0 = mix(g.albedo[t.row0 + t.i].rgb, g.albedo[t.row0 + t.i + 1u].rgb, t.fx);
    let a1 = mix(g.albedo[t.row1 + t.i].rgb, g.albedo[t.row1 + t.i + 1u].rgb, t.fx);
    return mix(a0, a1, t.fd);
}

// The slab's multiple-scattering transmittance at density rho and diffusion optical depth x per
// channel (htsm/diffusion.rs's table of T e^x at x = (k / 8)^2; its last entry beyond it).
fn slab_transmittance(rho: f32, x: vec3<f32>) -> vec3<f32> {
    var out = vec3<f32>(0.0);
    for (var c = 0; c < 3; c = c + 1) {
        let t = table_at(rho, sqrt(max(x[c], 0.0)) * 8.0, 33u);
        let s0 = mix(g.slab[t.row0 + t.i][c], g.slab[t.row0 + t.i + 1u][c], t.fx);
        let s1 = mix(g.slab[t.row1 + t.i][c], g.slab[t.row1 + t.i + 1u][c], t.fx);
        out[c] = mix(s0, s1, t.fd);
    }
    return out * exp(-x);
}

// F(b) of htsm/diffusion.rs: the share of a dipole term with source depth z lying beyond the
// lateral distance b, for transport coefficient s.
fn kernel_share(b: f32, z: vec3<f32>, s: vec3<f32>) -> vec3<f32> {
    let d = sqrt(b * b + z * z);
    return z / max(d, vec3<f32>(1e-12)) * exp(-s * (d - z));
}

// The share of the dipole kernel (source at depth z, image at z + 2 z_b) in ring `ring`'s
// annulus (0: the centre), per sample of the ring, the pattern widened `spread` times; the
// outermost ring's reaches infinity. Zero for rings beyond the outermost.
fn annulus_share(ring: i32, spread: f32, z: vec3<f32>, z_b: vec3<f32>, s: vec3<f32>) -> vec3<f32> {
    if (f32(ring) > g.rings.w) {
        return vec3<f32>(0.0);
    }
    let zv = z + 2.0 * z_b;
    // The two terms' totals are e^(-s z) and e^(-s zv): their ratio needs no exponent of z.
    let w_v = exp(-2.0 * s * z_b);
    var inner = vec3<f32>(1.0 + w_v);
    if (ring > 0) {
        let b = g.rings[ring - 1] * spread;
        inner = kernel_share(b, z, s) + w_v * kernel_share(b, zv, s);
    }
    var outer = vec3<f32>(0.0);
    if (f32(ring) < g.rings.w) {
        let b = g.rings[ring] * spread;
        outer = kernel_share(b, z, s) + w_v * kernel_share(b, zv, s);
    }
    let per_sample = select(0.25, 1.0, ring == 0);
    return (inner - outer) / (1.0 + w_v) * per_sample;
}

// The environment in the map's frame: world directions turned about +y.
fn to_map_frame(d: vec3<f32>) -> vec3<f32> {
    let c = g.env_frame.x;
    let s = g.env_frame.y;
    return vec3<f32>(c * d.x + s * d.z, d.y, -s * d.x + c * d.z);
}

// sum_lm c_lm Y_lm(d) (lucent_core::irradiance::sh::sh_basis's order and constants).
fn sh_eval(c: array<vec4<f32>, 9>, d: vec3<f32>) -> vec3<f32> {
    let x = d.x;
    let y = d.y;
    let z = d.z;
    return c[0].rgb * 0.282095 + c[1].rgb * (0.488603 * y) + c[2].rgb * (0.488603 * z)
        + c[3].rgb * (0.488603 * x) + c[4].rgb * (1.092548 * x * y) + c[5].rgb * (1.092548 * y * z)
        + c[6].rgb * (0.315392 * (3.0 * z * z - 1.0)) + c[7].rgb * (1.092548 * x * z)
        + c[8].rgb * (0.546274 * (x * x - y * y));
}

// The environment's lit-side surface terms, from all nine SH coefficients (the subsurface part
// comes from its directional lights, htsm/environment.rs): the diffuse term with the
// Fresnel-transmitted SH irradiance instead of one light's, and the glossy reflection as the
// band-limited radiance in the mirror direction times Schlick's Fresnel. Unshadowed.
fn environment_surface(p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let v = normalize(g.eye.xyz - p);
    let e_t = max(sh_eval(g.env_irradiance, to_map_frame(n)), vec3<f32>(0.0));
    let diffuse = g.shading.x * g.transport.rgb * e_t / 3.14159265;
    let r = reflect(-v, n);
    let l_r = max(sh_eval(g.env_radiance, to_map_frame(r)), vec3<f32>(0.0));
    let spec = g.shading.y * fresnel_schlick(dot(n, v), g.material.x) * l_r;
    return diffuse + spec;
}
