//! The view ray's light paths with fewer rays (`shading::single_scattering::light_paths`) against every path
//! traced (`shading::single_scattering::view_ray_radiance`): exact where the shortcut is a
//! closed form of the same integrand (a half-space), nothing where the body hides the light,
//! and within a bound on the embedded bunny, what the mesh pass draws, lights in front, at the
//! side and behind.

mod view_ray_util;

use glam::Vec3;
use lucent_core::Rgb;
use lucent_core::bssrdf::{Material, Profile};
use lucent_core::irradiance::{Light, SceneLight};
use lucent_core::mesh::{Mesh, embedded};
use lucent_core::session::{Ablations, FrameSession, FrameSettings, Solved, Transport};
use lucent_core::shading::single_scattering::{view_ray_radiance, view_ray_radiance_with};
use view_ray_util::{half_space, with_scene};

/// `(traced, shortcut)` single scattering at every vertex of `mesh` seen from `eye`, with a
/// drawn diffuse radiance of 1 everywhere.
fn both(mesh: &Mesh, d: &Profile, lights: &[SceneLight], eye: Vec3) -> (Vec<Rgb>, Vec<Rgb>) {
    let diffuse = vec![Rgb::ONE; mesh.positions.len()];
    with_scene(mesh, d, lights, None, |scene| {
        (view_ray_radiance(scene, eye), view_ray_radiance_with(scene, eye, Some(&diffuse)))
    })
}

/// On a flat face lit from any angle the half-space's closed form is the traced paths' sum.
#[test]
fn a_lit_flat_face_takes_the_half_space_closed_form() {
    let (mesh, d) = half_space(1.3);
    let top = mesh.positions.iter().position(|p| p.distance(Vec3::Y) < 1e-6).unwrap();
    for mu_i in [1.0f32, 0.7, 0.3] {
        let to_light = Vec3::new((1.0 - mu_i * mu_i).sqrt(), mu_i, 0.0);
        let light = Light::Directional { direction: -to_light, irradiance: Rgb::ONE };
        let eye = Vec3::new(-0.3, 1.0, 0.2) * 1e4;
        let (traced, fast) = both(&mesh, &d, &[SceneLight { light, shadows: true }], eye);
        let (t, f) = (traced[top], fast[top]);
        assert!(t.min_element() > 0.0);
        let rel = ((f - t) / t).abs().max_element();
        assert!(rel < 1e-4, "mu_i {mu_i}: {f} vs traced {t}");
    }
}

/// Under a face turned away from the light, across a body two thousand mean free paths
/// thick, nothing arrives: the shortcut leaves it out, as tracing finds.
#[test]
fn a_face_behind_a_thick_body_gets_nothing() {
    let (mesh, d) = half_space(1.3);
    let light = Light::Directional { direction: Vec3::Y, irradiance: Rgb::ONE };
    let eye = Vec3::new(0.2, 1.0, 0.1) * 1e4;
    let (traced, fast) = both(&mesh, &d, &[SceneLight { light, shadows: true }], eye);
    let top = mesh.positions.iter().position(|p| p.distance(Vec3::Y) < 1e-6).unwrap();
    assert!(traced[top].max_element() < 1e-30, "{}", traced[top]);
    assert_eq!(fast[top], Rgb::ZERO);
}

/// The embedded bunny, marble at 10 cm and skim milk at 5 cm, lights in front, at the side
/// and behind: what the mesh pass draws (`radiance + single`) per vertex with the shortcut
/// against every path traced, and `B` unchanged (only the view stage differs).
#[test]
fn the_bunny_draws_within_a_bound_of_every_path_traced() {
    let mesh = embedded::bunny();
    let (lo, hi) = mesh.bounds();
    let (centre, ext) = (0.5 * (lo + hi), mesh.extent());
    let eye = centre + Vec3::new(0.0, 0.3, 2.5) * ext;
    for (material, scale) in [("marble", 0.1), ("skimmilk", 0.05)] {
        for (name, dir) in
            [("front", Vec3::new(0.5, 0.6, 1.0)), ("side", Vec3::X), ("back", Vec3::new(-0.5, 0.6, -1.0))]
        {
            let position = centre + dir.normalize() * 2.5 * ext;
            let light = Light::Point { position, intensity: Vec3::splat(ext * ext * 4.0) };
            let transport = Transport::new(Material::by_name(material).unwrap(), scale);
            let mut s = FrameSession::new(mesh.clone(), None, transport, FrameSettings::default());
            s.set_lights(vec![SceneLight::from(light)]);
            s.set_eye(Some(eye));
            let fast = s.solve().clone();
            let settings = FrameSettings {
                ablate: Ablations { light_paths: true, ..Default::default() },
                ..FrameSettings::default()
            };
            s.set_settings(settings);
            let traced = s.solve().clone();
            assert_eq!(fast.face_b, traced.face_b, "{material} {name}: only the view stage differs");
            let (median, p99) = spread(&fast, &traced);
            println!("{material} {name}: drawn median {:.4}%, p99 {:.3}%", 100.0 * median, 100.0 * p99);
            assert!(median < 1e-3 && p99 < 0.02, "{material} {name}: median {median}, p99 {p99}");
        }
    }
}

/// Median and 99th percentile of the relative difference of the drawn radiance per vertex.
fn spread(a: &Solved, b: &Solved) -> (f64, f64) {
    let drawn = |x: &Solved, i: usize| {
        let v = x.vertex_radiance[i] + x.vertex_single.get(i).copied().unwrap_or(Rgb::ZERO);
        (v.x + v.y + v.z) as f64
    };
    let mut e: Vec<f64> = (0..a.vertex_radiance.len())
        .filter(|&i| drawn(b, i) > 1e-12)
        .map(|i| (drawn(a, i) - drawn(b, i)).abs() / drawn(b, i))
        .collect();
    assert!(!e.is_empty());
    e.sort_by(f64::total_cmp);
    let at = |q: f64| e[((e.len() - 1) as f64 * q).round() as usize];
    (at(0.5), at(0.99))
}
