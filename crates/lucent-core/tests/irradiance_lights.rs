//! Lights at the leaves (Mertens §5.3): spot cone falloff, the spot light's footprint on a
//! plane, and the combined entry point against the unshadowed one.

mod irradiance_util;

use glam::Vec3;
use irradiance_util::{plane, uv_sphere};
use lucent_core::Rgb;
use lucent_core::bssrdf::Entry;
use lucent_core::bssrdf::fresnel_transmittance;
use lucent_core::irradiance::{
    BandWeights, EnvMap, Environment, Light, SceneLight, ShadowCaster, face_irradiance,
    face_irradiance_shadowed, light_irradiance, spot_falloff,
};

const ETA: f64 = 1.3;

#[test]
fn spot_falloff_is_one_inside_zero_outside_and_a_smoothstep_between() {
    let (cone, soft) = (30f32.to_radians(), 0.4);
    let inner = cone * (1.0 - soft);
    let f = |deg: f32| spot_falloff(deg.to_radians().cos(), cone, soft);
    assert_eq!(f(0.0), 1.0);
    assert_eq!(f(inner.to_degrees() - 0.5), 1.0);
    assert_eq!(f(30.5), 0.0);
    assert_eq!(f(120.0), 0.0);
    // Halfway through the soft band the smoothstep is exactly 1/2; at a quarter from the outer
    // edge it is 3(1/4)² − 2(1/4)³ = 5/32.
    let mid = 0.5 * (inner + cone);
    assert!((spot_falloff(mid.cos(), cone, soft) - 0.5).abs() < 1e-4);
    let q = cone - 0.25 * (cone - inner);
    assert!((spot_falloff(q.cos(), cone, soft) - 5.0 / 32.0).abs() < 1e-4);
    // Monotone in angle.
    let mut last = 1.0;
    for i in 0..=300 {
        let v = f(i as f32 * 0.1);
        assert!(v <= last);
        last = v;
    }
    // A hard edge.
    assert_eq!(spot_falloff(29.9f32.to_radians().cos(), cone, 0.0), 1.0);
    assert_eq!(spot_falloff(30.1f32.to_radians().cos(), cone, 0.0), 0.0);
}

#[test]
fn spot_light_lights_a_disc_and_matches_a_point_light_inside_its_cone() {
    let mesh = plane(4.0, 100);
    let (h, cone) = (2.0f32, 25f32.to_radians());
    let position = Vec3::new(0.0, h, 0.0);
    let intensity = Rgb::new(3.0, 2.0, 1.0);
    let spot = Light::Spot { position, direction: -Vec3::Y, intensity, cone_angle: cone, soft_edge: 0.0 };
    let point = Light::Point { position, intensity };
    let e_spot = face_irradiance(&mesh, &[spot], &Entry::fresnel(ETA));
    let e_point = face_irradiance(&mesh, &[point], &Entry::fresnel(ETA));
    // The cone meets the plane in a disc of radius h tan(cone).
    let radius = h * cone.tan();
    for f in 0..mesh.triangles.len() {
        let rho = mesh.face_centroid(f).length();
        if rho < radius - 1e-3 {
            let diff = (e_spot[f] - e_point[f]).abs().max_element();
            assert!(diff <= 1e-6 * e_point[f].max_element(), "{} vs {}", e_spot[f], e_point[f]);
        } else if rho > radius + 1e-3 {
            assert_eq!(e_spot[f], Rgb::ZERO);
        }
    }
    // Directly below: E = I / h² times F_t at normal incidence.
    let below = light_irradiance(&spot, Vec3::ZERO, Vec3::Y, &Entry::fresnel(ETA));
    let want = intensity / (h * h) * fresnel_transmittance(1.0, ETA) as f32;
    assert!((below - want).abs().max_element() < 1e-6, "{below} vs {want}");
}

#[test]
fn shadowed_entry_point_without_caster_equals_the_plain_one() {
    let mesh = uv_sphere(Vec3::ZERO, 1.0, 32, 16);
    let lights = [
        Light::Point { position: Vec3::new(0.0, 2.0, -3.0), intensity: Rgb::splat(5.0) },
        Light::Directional { direction: Vec3::new(1.0, -1.0, 0.0), irradiance: Rgb::new(0.2, 0.3, 0.4) },
        Light::Spot {
            position: Vec3::new(2.0, 0.0, 0.0),
            direction: -Vec3::X,
            intensity: Rgb::ONE,
            cone_angle: 0.4,
            soft_edge: 0.3,
        },
    ];
    let plain = face_irradiance(&mesh, &lights, &Entry::fresnel(ETA));
    let scene: Vec<SceneLight> = lights.iter().map(|&l| l.into()).collect();
    let same = face_irradiance_shadowed(&mesh, &scene, None, &Entry::fresnel(ETA), None);
    assert_eq!(plain, same);
    // A convex mesh does not shadow itself: with a caster, nothing changes either.
    let caster = ShadowCaster::new(&mesh);
    let shadowed = face_irradiance_shadowed(&mesh, &scene, None, &Entry::fresnel(ETA), Some(&caster));
    assert_eq!(plain, shadowed);
}

#[test]
fn constant_environment_gives_the_hemispherical_fresnel_average_on_every_face() {
    // L constant: E_t = L ∫ F_t cos dω = L A_0^t, the same for every face.
    let mesh = uv_sphere(Vec3::ZERO, 1.0, 32, 16);
    let l = Rgb::new(0.5, 1.0, 2.0);
    let env = Environment::from_map(&EnvMap::from_fn(128, 64, |_| l));
    let want = l * BandWeights::fresnel_cosine(ETA).0[0];
    let e = face_irradiance_shadowed(&mesh, &[], Some(&env), &Entry::fresnel(ETA), None);
    for v in e {
        assert!((v - want).abs().max_element() < 2e-3 * want.max_element(), "{v} vs {want}");
    }
}
