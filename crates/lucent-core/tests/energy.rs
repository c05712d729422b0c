//! The energy bound (`solver::energy`): under irradiance 1 on every face, a face's `B` is the
//! share of the light entering there that leaves anywhere, which cannot exceed 1. Checked on
//! the bunny, a thin slab and two touching spheres, for the exact solve and the hierarchical
//! solve in its three modes, against Mertens' unbounded dipole, which breaks it.

use glam::Vec3;
use lucent_core::Rgb;
use lucent_core::bssrdf::{Material, Profile, ProfileKind};
use lucent_core::formfactor::FormFactorOptions;
use lucent_core::hierarchy::face_cluster;
use lucent_core::mesh::Mesh;
use lucent_core::mesh::generate::{cube, icosphere};
use lucent_core::solver::{HierarchicalSolver, Oracle, exact};

/// A 20 mm x 20 mm slab 0.5 mm thick (at 20 mm model scale): thinner than marble's diffusion
/// length, so light entering one side leaves by both.
fn thin_slab() -> Mesh {
    let c = cube(12);
    let pos = c.positions.iter().map(|p| Vec3::new(p.x, p.y, 0.025 * p.z)).collect();
    Mesh::new(pos, c.triangles.clone())
}

/// Two unit spheres touching at the origin (a gap of 1e-3 of their radius).
fn touching_spheres() -> Mesh {
    let s = icosphere(3);
    let n = s.positions.len() as u32;
    let mut pos: Vec<Vec3> = s.positions.iter().map(|p| *p - Vec3::new(1.0005, 0.0, 0.0)).collect();
    pos.extend(s.positions.iter().map(|p| *p + Vec3::new(1.0005, 0.0, 0.0)));
    let mut tris = s.triangles.clone();
    tris.extend(s.triangles.iter().map(|t| t.map(|v| v + n)));
    Mesh::new(pos, tris)
}

fn max_channel(b: &[Rgb]) -> f32 {
    b.iter().map(|v| v.max_element()).fold(0.0, f32::max)
}

fn cases() -> Vec<(&'static str, Mesh, f64)> {
    vec![
        ("bunny", lucent_core::mesh::embedded::bunny(), 0.01),
        ("thin slab", thin_slab(), 0.02),
        ("touching spheres", touching_spheres(), 0.02),
    ]
}

#[test]
fn uniform_irradiance_gives_at_most_one_for_the_bounded_profiles() {
    let marble = Material::by_name("marble").unwrap();
    for (name, mesh, scale) in cases() {
        let ones = vec![Rgb::ONE; mesh.triangles.len()];
        let h = face_cluster::build(&mesh);
        let mertens = Profile::for_model_scale(&marble, mesh.extent() as f64, scale);
        let unbounded = max_channel(&exact::solve(&mesh, &mertens, &ones, &FormFactorOptions::default()));
        for kind in [ProfileKind::Dipole, ProfileKind::Pbd] {
            let d = Profile::at_model_scale(&marble, mesh.extent() as f64, scale, kind, true);
            let want = exact::solve(&mesh, &d, &ones, &FormFactorOptions::default());
            let mut s =
                HierarchicalSolver::new(mesh.clone(), h.clone(), d.clone(), Oracle::for_profile(kind));
            let otf = s.solve_on_the_fly(&ones).face_b;
            let render = s.solve_render(&ones).face_b;
            let flat = d.total_diffuse_reflectance().into_iter().fold(0.0, f64::max) as f32;
            println!(
                "{name}, marble at {scale} m, {kind}: max B under E = 1: exact {:.4}, on the fly {:.4}, render {:.4} \
                 (flat total {flat:.3}; Mertens unbounded {unbounded:.3})",
                max_channel(&want),
                max_channel(&otf),
                max_channel(&render)
            );
            assert!(max_channel(&want) <= 1.0 + 1e-5, "{name} {kind}: exact {}", max_channel(&want));
            assert!(max_channel(&otf) <= 1.01 && max_channel(&render) <= 1.01, "{name} {kind}");
            // Thick, flat regions keep the flat total: the bound touches only what exceeds 1.
            assert!(max_channel(&want) >= 0.95 * flat.min(1.0), "{name} {kind}: the bound removed too much");
        }
        if name != "bunny" {
            // Without the bound the thin and touching parts exceed 1 (the problem it solves).
            assert!(unbounded > 1.05, "{name}: Mertens' dipole gives only {unbounded}");
        }
    }
}

/// Incremental updates re-derive the bound from the updated links.
#[test]
fn the_bound_follows_an_incremental_update() {
    use lucent_core::mesh::deform::{Deformer, twist};
    let mesh = thin_slab();
    let marble = Material::by_name("marble").unwrap();
    let d = Profile::at_model_scale(&marble, mesh.extent() as f64, 0.02, ProfileKind::Pbd, true);
    let h = face_cluster::build(&mesh);
    let mut s = HierarchicalSolver::new(mesh.clone(), h, d.clone(), Oracle::for_profile(ProfileKind::Pbd));
    let ones = vec![Rgb::ONE; mesh.triangles.len()];
    s.solve_render(&ones);
    let twisted = twist(Vec3::ZERO, Vec3::X, 0.8).deformed(&mesh);
    s.update_incremental(&twisted.positions, None);
    let got = s.solve_render(&ones).face_b;
    let want = exact::solve(&twisted, &d, &ones, &FormFactorOptions::default());
    assert!(max_channel(&got) <= 1.01, "{}", max_channel(&got));
    let err: f32 = got.iter().zip(&want).map(|(a, b)| (*a - *b).length()).fold(0.0, f32::max);
    assert!(err < 0.05, "incremental bound vs exact: largest difference {err}");
}

/// `lucent bench energy`'s figures: the thin slab breaks energy without the bound (both sides
/// gather) and keeps it with the bound.
#[test]
fn uniform_report_measures_before_and_after_the_bound() {
    let mesh = thin_slab();
    let marble = Material::by_name("marble").unwrap();
    let d = Profile::at_model_scale(&marble, mesh.extent() as f64, 0.02, ProfileKind::Dipole, true);
    let r = lucent_core::solver::energy::uniform_report(&mesh, &d, Oracle::for_profile(ProfileKind::Dipole));
    println!("{r:?}");
    assert_eq!(r.faces, mesh.triangles.len());
    assert!(r.max_b_unbounded > 1.05, "{r:?}");
    assert!(r.max_b_uniform <= 1.0 + 1e-6, "{r:?}");
    assert!(r.faces_bounded > 0 && r.faces_bounded < r.faces && r.links > 0, "{r:?}");
}
