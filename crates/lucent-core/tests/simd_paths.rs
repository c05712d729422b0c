//! The hierarchical solve (Mertens et al. 2003, §5.5) on the portable path against the widest
//! instruction set this CPU has ([`lucent_core::simd::Isa`]): `B` per face, on the fly and in
//! render mode, for every profile (with its single scattering where it has one). The path is
//! chosen once per process, so the test runs itself again with `LUCENT_SIMD=scalar` and
//! compares (relative to the face's `B`, or a thousandth of the largest where that is smaller).

use glam::Vec3;
use lucent_core::bssrdf::{Material, Profile, ProfileKind};
use lucent_core::hierarchy::subdivision::{butterfly, octahedron};
use lucent_core::irradiance::{Light, face_irradiance};
use lucent_core::simd::Isa;
use lucent_core::solver::{HierarchicalSolver, Oracle};

const DUMP: &str = "LUCENT_SIMD_TEST_DUMP";

/// `B` per face and channel: on the fly, then render mode, for each profile (the normal-placed
/// and the distance-form kernels both).
fn solve() -> Vec<f32> {
    let sub = butterfly(&octahedron(Vec3::new(1.0, 1.25, 0.9)), 4).expect("closed base mesh");
    let marble = Material::by_name("marble").unwrap();
    let mut out = vec![];
    for kind in ProfileKind::ALL {
        let mesh = sub.mesh.clone();
        let single = kind.has_single_scattering();
        let d = Profile::at_model_scale(&marble, mesh.extent() as f64, 0.025, kind, single);
        let light = [Light::Point { position: Vec3::new(2.0, 3.0, 1.6), intensity: Vec3::splat(10.0) }];
        let e = face_irradiance(&mesh, &light, &d.entry);
        let mut s = HierarchicalSolver::new(mesh, sub.hierarchy.clone(), d, Oracle::default());
        let otf = s.solve_on_the_fly(&e).face_b;
        let render = s.solve_render(&e).face_b;
        out.extend(otf.iter().chain(&render).flat_map(|b| b.to_array()));
    }
    out
}

#[test]
fn solve_matches_across_instruction_sets() {
    if let Ok(path) = std::env::var(DUMP) {
        let text: Vec<String> = solve().iter().map(|v| v.to_bits().to_string()).collect();
        std::fs::write(path, text.join("\n")).unwrap();
        return;
    }
    if Isa::best() == Isa::Scalar {
        return; // one path only: nothing to compare
    }
    let path = std::env::temp_dir().join(format!("lucent-simd-paths-{}.txt", std::process::id()));
    let status = std::process::Command::new(std::env::current_exe().unwrap())
        .args(["--exact", "solve_matches_across_instruction_sets", "--test-threads=1"])
        .env("LUCENT_SIMD", "scalar")
        .env(DUMP, &path)
        .status()
        .unwrap();
    assert!(status.success());
    let text = std::fs::read_to_string(&path).unwrap();
    let _ = std::fs::remove_file(&path);
    let scalar: Vec<f32> = text.lines().map(|l| f32::from_bits(l.parse().unwrap())).collect();
    let wide = solve();
    assert_eq!(scalar.len(), wide.len());
    let peak = scalar.iter().copied().fold(0.0f32, f32::max);
    let mut rel: Vec<f64> =
        scalar.iter().zip(&wide).map(|(a, b)| ((a - b).abs() / a.abs().max(1e-3 * peak)) as f64).collect();
    rel.sort_by(f64::total_cmp);
    let (median, worst) = (rel[rel.len() / 2], rel[rel.len() - 1]);
    eprintln!("{:?} against scalar: median {median:e}, worst {worst:e} relative", Isa::best());
    // Faces differ by the estimates' few ulp (AVX-512's Newton-step reciprocal square root,
    // fused multiply-adds), a half float's rounding of a stored coefficient (at most 4.9e-4 of
    // it) or a threshold decided the other way. Measured on a Zen 4: AVX2 median 0, worst
    // 6.4e-5; AVX-512 median 6.4e-8, worst 6.4e-5.
    assert!(median <= 1e-6 && worst <= 2e-4, "median {median:e}, worst {worst:e}");
}
