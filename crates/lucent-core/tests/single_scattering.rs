//! View-ray single scattering (`shading::single_scattering`) against Hanrahan & Krueger's
//! closed form on a half-space, the same with the environment's closed form, and shadowing.

use glam::Vec3;
use lucent_core::Rgb;
use lucent_core::bssrdf::{Dipole, Material, ProfileKind, fresnel_transmittance};
use lucent_core::irradiance::sh::Sh9;
use lucent_core::irradiance::{Environment, Light, SceneLight};
use lucent_core::mesh::bvh::Bvh;
use lucent_core::mesh::{Mesh, generate};
use lucent_core::shading::SingleScattering;
use lucent_core::shading::single_scattering::{NEIGHBOUR_FLOOR, ViewRayScene, view_ray_radiance};

/// A cube 2 units wide of a material with a mean free path of a thousandth of a unit: a
/// half-space seen from the middle of a face. Albedos 0.3, 0.9, 0.99.
fn half_space(eta: f64) -> (Mesh, Dipole) {
    let sigma_s = [3.0, 9.0, 9.9];
    let sigma_a = [7.0, 1.0, 0.1];
    let m = Material::custom("test", sigma_s, sigma_a, eta).unwrap();
    // 10 mm^-1 total, 100 mm per unit: σ_t = 1000 per unit.
    (generate::cube(8), Dipole::with_profile(&m, 100.0, ProfileKind::Pbd, false))
}

/// The top face's centre vertex (0, 1, 0).
fn top_centre(mesh: &Mesh) -> usize {
    mesh.positions.iter().position(|p| p.distance(Vec3::Y) < 1e-6).unwrap()
}

/// Hanrahan & Krueger's half-space single scattering before the exit Fresnel factor, for
/// irradiance 1 arriving at outside cosine `mu_i` and seen at outside cosine `mu_o`.
fn closed_form(d: &Dipole, mu_i: f64, mu_o: f64) -> [f64; 3] {
    let eta = d.eta;
    let refracted = |mu: f64| (1.0 - (1.0 - mu * mu) / (eta * eta)).sqrt();
    std::array::from_fn(|c| {
        d.alpha_prime[c] * fresnel_transmittance(mu_i, eta) * mu_i
            / (4.0 * std::f64::consts::PI * eta * eta * (refracted(mu_i) + refracted(mu_o)))
    })
}

fn radiance_at(mesh: &Mesh, d: &Dipole, lights: &[SceneLight], env: Option<&Environment>, eye: Vec3) -> Rgb {
    let normals = mesh.vertex_normals();
    let bvh = Bvh::build(mesh);
    let scene = ViewRayScene {
        mesh,
        normals: &normals,
        bvh: &bvh,
        offset: 1e-5,
        dipole: d,
        lights,
        environment: env,
    };
    view_ray_radiance(&scene, eye)[top_centre(mesh)]
}

/// Unit direction in the x-y plane at cosine `mu` to +Y, on side `sign` of the normal.
fn at_cosine(mu: f32, sign: f32) -> Vec3 {
    Vec3::new(sign * (1.0 - mu * mu).sqrt(), mu, 0.0)
}

#[test]
fn a_half_space_gives_hanrahan_and_krueger_at_any_angle() {
    for eta in [1.0, 1.3] {
        let (mesh, d) = half_space(eta);
        for (mu_i, mu_o) in [(1.0, 1.0), (0.6, 0.8), (0.1, 0.9), (0.9, 0.15)] {
            let light = Light::Directional { direction: -at_cosine(mu_i, -1.0), irradiance: Rgb::ONE };
            let eye = Vec3::Y + at_cosine(mu_o, 1.0) * 1e4;
            let got = radiance_at(&mesh, &d, &[SceneLight { light, shadows: true }], None, eye);
            let want = closed_form(&d, mu_i as f64, mu_o as f64);
            for c in 0..3 {
                let rel = (got[c] as f64 - want[c]) / want[c];
                assert!(
                    rel.abs() < 0.01,
                    "eta {eta}, mu_i {mu_i}, mu_o {mu_o}, channel {c}: {} vs {}",
                    got[c],
                    want[c]
                );
            }
        }
    }
}

#[test]
fn a_shadowed_entry_point_sends_nothing() {
    let (mut mesh, d) = half_space(1.0);
    // A small roof just above the top face's centre, facing it, shadows the light from above.
    let base = mesh.positions.len() as u32;
    mesh.positions.extend([
        Vec3::new(-0.2, 1.01, -0.2),
        Vec3::new(0.2, 1.01, -0.2),
        Vec3::new(0.0, 1.01, 0.3),
    ]);
    mesh.triangles.push([base, base + 1, base + 2]);
    let light = Light::Directional { direction: -Vec3::Y, irradiance: Rgb::ONE };
    let eye = Vec3::Y + at_cosine(0.9, 1.0) * 1e4;
    let shadowed = radiance_at(&mesh, &d, &[SceneLight { light, shadows: true }], None, eye);
    let unshadowed = radiance_at(&mesh, &d, &[SceneLight { light, shadows: false }], None, eye);
    assert!(unshadowed.min_element() > 0.0);
    // Nothing of its own: only the floor share of a neighbour's (each at most the unshadowed
    // half-space's value), which keeps the mesh pass's geometric blend finite.
    let most = unshadowed * (NEIGHBOUR_FLOOR * 1.001);
    assert!(shadowed.cmple(most).all(), "{shadowed} against at most {most}");
}

#[test]
fn a_constant_sky_gives_the_closed_form_integrated_over_the_hemisphere() {
    for eta in [1.0, 1.3] {
        let (mesh, d) = half_space(eta);
        let mut sh = Sh9::ZERO;
        // Constant radiance 1: L_00 = sqrt(4π).
        sh.coeffs[0] = Rgb::splat((4.0 * std::f32::consts::PI).sqrt());
        let env = Environment { sh, rotation_deg: 0.0, intensity: 1.0 };
        for mu_o in [1.0f32, 0.5] {
            let eye = Vec3::Y + at_cosine(mu_o, 1.0) * 1e4;
            let got = radiance_at(&mesh, &d, &[], Some(&env), eye);
            // ∫ f dω over the upper hemisphere (radiance 1 from every direction), by the midpoint rule.
            let n = 4000;
            let mut want = [0.0f64; 3];
            for k in 0..n {
                let mu_i = (k as f64 + 0.5) / n as f64;
                let f = closed_form(&d, mu_i, mu_o as f64);
                for c in 0..3 {
                    want[c] += 2.0 * std::f64::consts::PI * f[c] / n as f64;
                }
            }
            for c in 0..3 {
                let rel = (got[c] as f64 - want[c]) / want[c];
                // Nine SH coefficients of a zonal kernel: the truncation is the error.
                assert!(rel.abs() < 0.03, "eta {eta}, mu_o {mu_o}, channel {c}: {} vs {}", got[c], want[c]);
            }
        }
    }
}

#[test]
fn modes_parse_by_name_and_only_the_profile_mode_is_in_the_profile() {
    for (s, m) in [
        ("view", SingleScattering::ViewRay),
        ("on", SingleScattering::ViewRay),
        ("Profile", SingleScattering::Profile),
        ("off", SingleScattering::Off),
    ] {
        assert_eq!(s.parse::<SingleScattering>().unwrap(), m);
        assert_eq!(m.in_profile(), m == SingleScattering::Profile);
    }
    let e = "sideways".parse::<SingleScattering>().unwrap_err().to_string();
    assert!(e.contains("sideways") && e.contains("view") && e.contains("profile"), "{e}");
}

/// Only vertices of triangles facing the eye cast rays: the cube's top centre seen from above
/// has single scattering, seen from below (where only back faces hold it) none.
#[test]
fn vertices_of_back_faces_only_cast_no_rays() {
    let (mesh, d) = half_space(1.0);
    let light = Light::Directional { direction: -Vec3::Y, irradiance: Rgb::ONE };
    let lights = [SceneLight { light, shadows: true }];
    let above = radiance_at(&mesh, &d, &lights, None, Vec3::new(0.0, 1e4, 0.0));
    let below = radiance_at(&mesh, &d, &lights, None, Vec3::new(0.0, -1e4, 0.0));
    assert!(above.min_element() > 0.0, "{above}");
    assert_eq!(below, Rgb::ZERO);
    // Seen from the side (+X, below the top face's plane) and lit from there: the +X face's
    // centre has single scattering, the top centre, on back faces only, none.
    let side = [SceneLight {
        light: Light::Directional { direction: -Vec3::X, irradiance: Rgb::ONE },
        shadows: true,
    }];
    let normals = mesh.vertex_normals();
    let bvh = Bvh::build(&mesh);
    let scene = ViewRayScene {
        mesh: &mesh,
        normals: &normals,
        bvh: &bvh,
        offset: 1e-5,
        dipole: &d,
        lights: &side,
        environment: None,
    };
    let ss = view_ray_radiance(&scene, Vec3::new(1e4, 0.5, 0.0));
    let side_centre = mesh.positions.iter().position(|p| p.distance(Vec3::X) < 1e-6).unwrap();
    assert_eq!(ss[top_centre(&mesh)], Rgb::ZERO);
    assert!(ss[side_centre].min_element() > 0.0, "{}", ss[side_centre]);
}
