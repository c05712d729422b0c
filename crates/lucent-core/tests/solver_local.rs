//! The local limit of the hierarchical solve (`solver::local`): where the profile's reach is
//! below a face, `B = R_d_total E` with one link per face, and it agrees with the exact solve.

use glam::Vec3;
use lucent_core::bssrdf::{Material, Profile, ProfileKind};
use lucent_core::formfactor::FormFactorOptions;
use lucent_core::hierarchy::face_cluster;
use lucent_core::irradiance::{Light, face_irradiance};
use lucent_core::solver::exact::rel_rmse;
use lucent_core::solver::local::Locality;
use lucent_core::solver::{HierarchicalSolver, Oracle, exact};

/// The case: sigma_s' = sigma_a = 100 mm^-1 on the bunny at 10 cm (transport reaches
/// hundredths of a millimetre, faces are millimetres): almost every face takes the local
/// limit, there are about as many links as faces, and on the fly, render mode and the exact
/// solve agree within 1%, for each profile.
#[test]
fn dense_bunny_takes_the_local_limit_and_matches_exact() {
    let mesh = lucent_core::mesh::embedded::bunny();
    let n = mesh.triangles.len();
    let h = face_cluster::build(&mesh);
    let (lo, hi) = mesh.bounds();
    let ext = mesh.extent();
    let light = [Light::Point {
        position: 0.5 * (lo + hi) + Vec3::new(1.0, 1.5, 0.8) * ext,
        intensity: Vec3::splat(ext * ext * 4.0),
    }];
    let m = Material::custom("dense", [100.0; 3], [100.0; 3], 1.3).unwrap();
    // Every profile, with and without single scattering where it has it.
    let every = ProfileKind::ALL.into_iter().flat_map(|kind| [(kind, false), (kind, true)]);
    for (kind, single) in every.filter(|&(kind, single)| !single || kind.has_single_scattering()) {
        let d = Profile::at_model_scale(&m, ext as f64, 0.1, kind, single);
        let loc = Locality::of(&d);
        let reach_mm = loc.reach as f64 * d.mm_per_unit;
        // The numerical `∫ R dA` of the local limit is the closed form's.
        let closed = d.total_diffuse_reflectance();
        for c in 0..3 {
            assert!(
                (loc.r_total[c] as f64 / closed[c] - 1.0).abs() < 2e-3,
                "{kind} ss={single}: {loc:?} vs {closed:?}"
            );
        }
        let e = face_irradiance(&mesh, &light, &d.entry);
        let want = exact::solve(&mesh, &d, &e, &FormFactorOptions::default());
        let mut s = HierarchicalSolver::new(mesh.clone(), h.clone(), d.clone(), Oracle::for_profile(kind));
        let otf = s.solve_on_the_fly(&e);
        let link = s.link();
        let render = s.solve_render(&e);
        let (err, err_render) = (rel_rmse(&want, &otf.face_b), rel_rmse(&want, &render.face_b));
        println!(
            "{kind} ss={single}: reach {reach_mm:.4} mm, {} local faces of {n}, {} links, rel RMSE {:.4}% (render {:.4}%)",
            otf.stats.local_faces,
            link.links,
            100.0 * err,
            100.0 * err_render
        );
        assert!(reach_mm < 0.1, "{kind} ss={single}: reach {reach_mm} mm");
        assert!(
            otf.stats.local_faces >= n * 9 / 10,
            "{kind} ss={single}: {} local faces",
            otf.stats.local_faces
        );
        assert!(link.links <= 2 * n, "{kind} ss={single}: {} links", link.links);
        assert!(err <= 0.01 && err_render <= 0.01, "{kind} ss={single}: {err} / {err_render}");
    }
}

/// The reach grows with the diffusion length: marble at 10 cm reaches across the bunny, and no
/// face of it is local.
#[test]
fn translucent_bunny_has_no_local_face() {
    let mesh = lucent_core::mesh::embedded::bunny();
    let h = face_cluster::build(&mesh);
    let d = Profile::at_model_scale(
        &Material::by_name("marble").unwrap(),
        mesh.extent() as f64,
        0.1,
        ProfileKind::Pbd,
        true,
    );
    let loc = Locality::of(&d);
    assert!(loc.reach as f64 * d.mm_per_unit > 10.0, "reach {} mm", loc.reach as f64 * d.mm_per_unit);
    assert!(loc.local_clusters(&h, &mesh).iter().all(|&l| !l));
}
