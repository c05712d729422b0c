//! The local limit at the vertices (`session::local_limit`, issue 51): where transport is far
//! below the faces, the session follows the irradiance to the vertices instead of splitting the
//! faces, and agrees there with the solve of the split mesh (the reference `refine = 2` made);
//! where it is not, the image is the face solve's, bit for bit.

use glam::Vec3;
use lucent_core::Rgb;
use lucent_core::bssrdf::Material;
use lucent_core::irradiance::{Light, SceneLight};
use lucent_core::mesh::refine::{mean_face_is_local, split_midpoints};
use lucent_core::mesh::{Mesh, generate};
use lucent_core::session::{FrameSession, FrameSettings, Transport};
use lucent_core::shading::diffuse_radiance;
use lucent_core::solver::local::Locality;

/// A point light 0.6 units above the cube's +z side, off its centre: the irradiance changes by
/// a factor of about five across that side's faces.
fn near_light() -> Vec<SceneLight> {
    vec![SceneLight::from(Light::Point { position: Vec3::new(0.3, 0.2, 1.6), intensity: Vec3::splat(1.0) })]
}

/// Per-vertex radiance of `mesh` in `transport` under [`near_light`], no eye, no bounces.
fn vertex_radiance(mesh: Mesh, transport: &Transport) -> (Vec<Rgb>, Vec<Rgb>) {
    let mut s = FrameSession::new(mesh, None, transport.clone(), FrameSettings::default());
    s.set_lights(near_light());
    let solved = s.solve();
    (solved.vertex_radiance.clone(), solved.face_b.clone())
}

/// Vertices strictly inside the cube's +z side (every face around them shares its normal).
fn inside_top(mesh: &Mesh) -> Vec<usize> {
    (0..mesh.positions.len())
        .filter(|&v| {
            let p = mesh.positions[v];
            p.z > 0.999 && p.x.abs() < 0.999 && p.y.abs() < 0.999
        })
        .collect()
}

/// sigma_s' = sigma_a = 100 mm^-1 (the dense material) on a 5 cm cube of 12.5 mm
/// faces: every face is local, `refine = auto` would not split it, and at the vertices inside
/// the lit side the session's radiance is within 3% of the split mesh's faces' `B` averaged
/// into its vertices (`refine = 2`, as `auto` made it before), against 5% or more for the
/// coarse faces' `B` averaged into the vertices.
#[test]
fn dense_vertices_follow_the_split_solve() {
    let m = Material::custom("dense", [100.0; 3], [100.0; 3], 1.3).unwrap();
    let transport = Transport::new(m, 0.05);
    let cube = generate::cube(4);
    let reach = Locality::of(&transport.profile_at(cube.extent())).reach;
    assert!(mean_face_is_local(&cube, reach as f64));
    let (coarse, coarse_b) = vertex_radiance(cube.clone(), &transport);
    // The reference: the split mesh's faces' B averaged into its vertices (the split faces
    // are local too, so the session's own per-vertex radiance there would be the limit again),
    // at the original vertices, which the split keeps first.
    let profile = transport.profile_at(cube.extent());
    let fine = split_midpoints(&cube, 2);
    let (_, fine_b) = vertex_radiance(fine.clone(), &transport);
    let split = diffuse_radiance(&fine.face_to_vertex(&fine_b), &profile);
    // Without the local limit at the vertices: the faces' B averaged into them.
    let plain = diffuse_radiance(&cube.face_to_vertex(&coarse_b), &profile);
    let rel = |a: &[Rgb]| -> Vec<f32> {
        let mut r: Vec<f32> =
            inside_top(&cube).iter().map(|&v| ((a[v] - split[v]).abs() / split[v]).max_element()).collect();
        r.sort_by(f32::total_cmp);
        r
    };
    let (with, without) = (rel(&coarse), rel(&plain));
    assert_eq!(with.len(), 9);
    let worst = |r: &[f32]| r[r.len() - 1];
    eprintln!(
        "against the split solve, worst of 9 vertices: {} with, {} without",
        worst(&with),
        worst(&without)
    );
    assert!(worst(&with) < 0.03, "with the local limit at the vertices: {with:?}");
    assert!(worst(&without) > 0.05, "the faces' B alone: {without:?}");
}

/// Marble at 5 cm: no face of the icosphere is local, and the session's per-vertex radiance is
/// the faces' `B` averaged into the vertices, bit for bit.
#[test]
fn materials_that_are_not_local_keep_the_face_solve() {
    let transport = Transport::new(Material::by_name("marble").unwrap(), 0.05);
    let mesh = generate::icosphere(2);
    let profile = transport.profile_at(mesh.extent());
    assert!(!mean_face_is_local(&mesh, Locality::of(&profile).reach as f64));
    let (radiance, face_b) = vertex_radiance(mesh.clone(), &transport);
    assert_eq!(radiance, diffuse_radiance(&mesh.face_to_vertex(&face_b), &profile));
}
