//! A camera move with the split view terms (`shading::view_basis`, issue 51 item 3): the eye
//! turns 10° about the vertical and the session re-evaluates the closed forms per face, on
//! the embedded bunny and, when `LUCENT_BENCH_MESH` names a mesh file (e.g. the 203K dragon
//! `scripts/fetch_dragon.sh` fetches), on that mesh too. Marble at 10 cm, one shadowing point
//! light, the session's defaults otherwise.
//!
//! `LUCENT_BENCH_MESH=target/meshes/dragon_203k.ply cargo bench -p lucent-core --bench view`

use criterion::{Criterion, criterion_group, criterion_main};
use glam::{Quat, Vec3};
use lucent_core::bssrdf::Material;
use lucent_core::irradiance::{Light, SceneLight};
use lucent_core::mesh::Mesh;
use lucent_core::session::{FrameSession, FrameSettings, SolveMode, Transport, ViewTerms};
use std::time::Duration;

/// A session on `mesh` with the split view terms, solved once with a camera move after it
/// (the eye-independent part made), and the eye's orbit centre.
fn session(mesh: &Mesh) -> (FrameSession, Vec3, Vec3) {
    let (lo, hi) = mesh.bounds();
    let (centre, ext) = (0.5 * (lo + hi), mesh.extent());
    let transport = Transport::new(Material::by_name("marble").expect("preset"), 0.1);
    let settings = FrameSettings { mode: SolveMode::Render, ..Default::default() };
    let mut s = FrameSession::new(mesh.clone(), None, transport, settings);
    let light = Light::Point {
        position: centre + Vec3::new(1.0, 1.5, 0.8) * ext,
        intensity: Vec3::splat(4.0 * ext * ext),
    };
    s.set_lights(vec![SceneLight { light, shadows: true }]);
    let eye = centre + Vec3::new(0.0, 0.3, 2.5) * ext;
    s.set_eye(Some(eye));
    s.set_view_terms(ViewTerms::Split);
    s.solve();
    (s, centre, eye)
}

fn camera(c: &mut Criterion) {
    let mut meshes = vec![("bunny".to_string(), lucent_core::mesh::embedded::bunny())];
    if let Ok(path) = std::env::var("LUCENT_BENCH_MESH") {
        let mesh = lucent_core::mesh::load_mesh(std::path::Path::new(&path))
            .unwrap_or_else(|e| panic!("LUCENT_BENCH_MESH={path}: {e}"));
        meshes.push((path, mesh));
    }
    let mut g = c.benchmark_group("camera_split");
    g.sample_size(20).measurement_time(Duration::from_secs(8));
    for (name, mesh) in meshes {
        let (mut s, centre, mut eye) = session(&mesh);
        let turn = Quat::from_rotation_y(10f32.to_radians());
        // The first move makes the eye-independent part; the bench times the later ones.
        eye = centre + turn * (eye - centre);
        s.set_eye(Some(eye));
        s.solve();
        g.bench_function(format!("{name} ({} faces)", mesh.triangles.len()), |b| {
            b.iter(|| {
                eye = centre + turn * (eye - centre);
                s.set_eye(Some(eye));
                s.solve().timings.single_scattering_ms
            })
        });
    }
    g.finish();
}

criterion_group!(benches, camera);
criterion_main!(benches);
