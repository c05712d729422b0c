//! Generators: closed, manifold, genus 0, outward; counts and volumes against closed forms.

use lucent_core::mesh::Mesh;
use lucent_core::mesh::generate::*;
use std::f64::consts::PI;

/// Every edge shared by exactly two oppositely directed faces, one component, V - E + F = 2,
/// no degenerate face, positive enclosed volume.
fn assert_closed_genus0(name: &str, m: &Mesh) {
    let t = m.topology();
    assert!(t.is_closed_manifold(), "{name}: {t}");
    assert_eq!(t.components, 1, "{name}");
    assert_eq!(t.euler_characteristic, 2, "{name}");
    assert_eq!(t.unreferenced_vertices, 0, "{name}");
    let (_, r) = lucent_core::mesh::validate::validate(m.clone(), name).unwrap();
    assert_eq!(r.degenerate_faces, 0, "{name}");
    assert!(m.signed_volume() > 0.0, "{name}: faces point inward");
}

/// For star-shaped meshes around `center`: every face normal points away from it.
fn assert_faces_outward(name: &str, m: &Mesh, center: glam::Vec3) {
    for f in 0..m.triangles.len() {
        assert!(m.face_normal(f).dot(m.face_centroid(f) - center) > 0.0, "{name}: face {f}");
    }
}

#[test]
fn base_meshes() {
    let ico = icosahedron();
    assert_eq!((ico.positions.len(), ico.triangles.len()), (12, 20));
    assert_closed_genus0("icosahedron", &ico);
    assert_faces_outward("icosahedron", &ico, glam::Vec3::ZERO);
    // Regular icosahedron with circumradius 1: edge a = 4 / sqrt(10 + 2 sqrt 5),
    // volume 5 (3 + sqrt 5) a^3 / 12.
    let a = 4.0 / (10.0 + 2.0 * 5f64.sqrt()).sqrt();
    assert!((ico.signed_volume() - 5.0 * (3.0 + 5f64.sqrt()) * a.powi(3) / 12.0).abs() < 1e-5);

    let cube = cube_base();
    assert_eq!((cube.positions.len(), cube.triangles.len()), (8, 12));
    assert_closed_genus0("cube_base", &cube);
    assert_faces_outward("cube_base", &cube, glam::Vec3::ZERO);
    assert!((cube.signed_volume() - 8.0).abs() < 1e-9);

    let candle = candle_base();
    assert_eq!((candle.positions.len(), candle.triangles.len()), (32, 60));
    assert_closed_genus0("candle_base", &candle);
}

#[test]
fn icosphere_counts_and_volume() {
    for n in 0..5 {
        let m = icosphere(n);
        let k = 4usize.pow(n);
        assert_eq!(m.triangles.len(), 20 * k);
        assert_eq!(m.positions.len(), 10 * k + 2);
        assert_closed_genus0("icosphere", &m);
        assert_faces_outward("icosphere", &m, glam::Vec3::ZERO);
        assert!(m.positions.iter().all(|p| (p.length() - 1.0).abs() < 1e-6));
    }
    // Inscribed polyhedra converge to the ball volume 4 pi / 3 from below.
    let v = icosphere(5).signed_volume();
    assert!(v < 4.0 * PI / 3.0 && v > 0.995 * 4.0 * PI / 3.0, "{v}");
}

#[test]
fn uv_sphere_counts() {
    for (s, r) in [(3, 2), (8, 5), (32, 16)] {
        let m = uv_sphere(s, r);
        assert_eq!(m.positions.len() as u32, s * (r - 1) + 2);
        assert_eq!(m.triangles.len() as u32, 2 * s * (r - 1));
        assert_closed_genus0("uv_sphere", &m);
        assert_faces_outward("uv_sphere", &m, glam::Vec3::ZERO);
    }
}

#[test]
fn subdivided_cube() {
    for n in 1..6u32 {
        let m = cube(n);
        assert_eq!(m.positions.len() as u32, 6 * n * n + 2);
        assert_eq!(m.triangles.len() as u32, 12 * n * n);
        assert_closed_genus0("cube", &m);
        assert_faces_outward("cube", &m, glam::Vec3::ZERO);
        assert!((m.signed_volume() - 8.0).abs() < 1e-5);
        assert!((m.area() - 24.0).abs() < 1e-4);
    }
}

#[test]
fn candle_shapes() {
    let p = CandleParams::default();
    let m = candle(&p);
    assert_closed_genus0("candle", &m);
    let (lo, hi) = m.bounds();
    assert!((lo.y - 0.0).abs() < 1e-6);
    assert!((hi.y - (p.height + p.wick_height + p.wick_radius)).abs() < 1e-6);
    // Flat top, sharp edge, no wick: a regular s-gon prism, V = s/2 r^2 sin(2 pi / s) h.
    let plain = CandleParams { bevel: 0.0, wick_radius: 0.0, ..p };
    let s = plain.segments as f64;
    let (r, h) = (plain.radius as f64, plain.height as f64);
    let prism = 0.5 * s * r * r * (2.0 * PI / s).sin() * h;
    let m = candle(&plain);
    assert_closed_genus0("candle without wick", &m);
    assert!((m.signed_volume() - prism).abs() < 1e-5 * prism);
    // The bevel and wick change the volume by less than the bevel ring plus the wick cylinder.
    let full = candle(&p).signed_volume();
    assert!(full < prism + PI * (p.wick_radius as f64).powi(2) * (p.wick_height + p.wick_radius) as f64);
    assert!(full > prism - 2.0 * PI * r * (p.bevel as f64).powi(2));
    // Extreme parameters are clamped into a valid closed shape.
    for q in [
        CandleParams { bevel: 10.0, ..p },
        CandleParams { wick_radius: 5.0, ..p },
        CandleParams { segments: 0, side_rings: 0, bevel_steps: 0, ..p },
    ] {
        assert_closed_genus0("clamped candle", &candle(&q));
    }
}
