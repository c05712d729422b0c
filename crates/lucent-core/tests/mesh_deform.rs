//! Deformers against closed forms: twist is a rotation about the axis, bump is local, noise is
//! a pure function of the offset; string parsing.

use glam::Vec3;
use lucent_core::mesh::deform::*;
use lucent_core::mesh::generate::{cube, icosphere, uv_sphere};

/// Distance of `p` to the line through `o` along unit `d`.
fn axis_distance(p: Vec3, o: Vec3, d: Vec3) -> f32 {
    let r = p - o;
    (r - r.dot(d) * d).length()
}

#[test]
fn twist_is_a_rotation_about_the_axis() {
    let rest = cube(4);
    let (o, dir) = (Vec3::new(0.2, -0.1, 0.3), Vec3::new(1.0, 2.0, 0.5));
    let d = dir.normalize();
    let k = 0.7; // radians per unit
    let mut out = Vec::new();
    twist(o, dir, k).apply(&rest, &mut out);
    assert_eq!(out.len(), rest.positions.len());
    for (p, q) in rest.positions.iter().zip(&out) {
        // Same distance to the axis and the same coordinate along it.
        assert!((axis_distance(*p, o, d) - axis_distance(*q, o, d)).abs() < 1e-5);
        assert!(((*p - o).dot(d) - (*q - o).dot(d)).abs() < 1e-5);
        // The rotation angle about the axis is k * s (closed form via the perpendicular parts).
        let (rp, rq) = (*p - o, *q - o);
        let (pp, pq) = (rp - rp.dot(d) * d, rq - rq.dot(d) * d);
        if pp.length() > 1e-3 {
            let angle = pp.cross(pq).dot(d).atan2(pp.dot(pq));
            let want = k * rp.dot(d);
            let diff = (angle - want + std::f32::consts::PI).rem_euclid(std::f32::consts::TAU)
                - std::f32::consts::PI;
            assert!(diff.abs() < 1e-4, "{angle} vs {want}");
        }
    }
}

#[test]
fn bump_moves_only_vertices_within_radius() {
    let rest = uv_sphere(48, 24);
    let (center, radius, height) = (Vec3::Y, 0.5, 0.2);
    let mut out = Vec::new();
    bump(center, radius, height).apply(&rest, &mut out);
    let normals = rest.vertex_normals();
    let mut moved = 0;
    for ((p, q), n) in rest.positions.iter().zip(&out).zip(&normals) {
        let d = p.distance(center);
        if d >= radius {
            assert_eq!(p, q, "vertex at distance {d} moved");
        } else {
            // Along the normal by height * (1 - (d/r)^2)^2.
            let w = (1.0 - (d / radius).powi(2)).powi(2);
            assert!((*q - (*p + height * w * *n)).length() < 1e-6);
            moved += 1;
        }
    }
    assert!(moved > 10);
    // The pole sits at the centre, with the normal +y by symmetry: moved by the full height.
    let pole = rest.positions.iter().position(|p| *p == Vec3::Y).unwrap();
    assert!((out[pole] - Vec3::new(0.0, 1.0 + height, 0.0)).length() < 1e-5);
    // A dent moves inward.
    bump(center, radius, -height).apply(&rest, &mut out);
    assert!((out[pole].y - (1.0 - height)).abs() < 1e-5);
}

#[test]
fn noise_is_deterministic_and_bounded() {
    let rest = icosphere(3);
    let n = noise(0.05, 3.0, Vec3::new(0.25, 0.5, 0.75));
    let (mut a, mut b) = (Vec::new(), Vec::new());
    n.apply(&rest, &mut a);
    n.apply(&rest, &mut b);
    assert_eq!(a, b);
    // Applying from the rest pose again after another offset gives the same result: no drift.
    noise(0.05, 3.0, Vec3::splat(9.0)).apply(&rest, &mut b);
    assert_ne!(a, b);
    n.apply(&rest, &mut b);
    assert_eq!(a, b);
    let normals = rest.vertex_normals();
    for ((p, q), nrm) in rest.positions.iter().zip(&a).zip(&normals) {
        let d = *q - *p;
        // Along the normal, within the amplitude (Perlin values lie in [-1, 1]).
        assert!(d.cross(*nrm).length() < 1e-6);
        assert!(d.length() <= 0.05 + 1e-6);
    }
    assert!(a.iter().zip(&rest.positions).any(|(q, p)| q.distance(*p) > 0.005));
}

#[test]
fn deformation_strings() {
    assert_eq!("twist:90".parse(), Ok(Deformation::Twist { degrees: 90.0 }));
    assert_eq!("bump:0,1,0,0.5,-0.1".parse(), Ok(Deformation::Bump(bump(Vec3::Y, 0.5, -0.1))));
    assert_eq!("noise:0.02, 4".parse(), Ok(Deformation::Noise { amplitude: 0.02, frequency: 4.0 }));
    for s in ["twist:90", "bump:1,2,3,0.5,0.25", "noise:0.5,2"] {
        let d: Deformation = s.parse().unwrap();
        assert_eq!(d.to_string(), s);
    }
    for (s, why) in [
        ("twist", "missing ':'"),
        ("twist:abc", "'abc' is not a finite number"),
        ("twist:1,2", "twist takes 1 number, got 2"),
        ("bump:0,0,0,1", "bump takes 5 numbers, got 4"),
        ("bump:0,0,0,0,1", "radius must be > 0"),
        ("noise:1,0", "frequency must be > 0"),
        ("noise:nan,1", "not a finite number"),
        ("spin:3", "unknown deformation kind 'spin'"),
    ] {
        let e = s.parse::<Deformation>().unwrap_err().to_string();
        assert!(e.contains(why) && e.contains(s), "{s}: {e}");
    }
}

#[test]
fn animated_deformation_starts_at_rest() {
    let rest = cube(3);
    let mut out = Vec::new();
    for s in ["twist:120", "bump:1,1,1,0.8,0.3"] {
        let d: Deformation = s.parse().unwrap();
        d.apply(&rest, 0.0, &mut out);
        for (p, q) in rest.positions.iter().zip(&out) {
            assert!(p.distance(*q) < 1e-6, "{s}");
        }
        d.apply(&rest, 1.0, &mut out);
        assert!(rest.positions.iter().zip(&out).any(|(p, q)| p.distance(*q) > 0.1), "{s}");
    }
    // twist:DEG turns the top of the bounding box by DEG/2 (and the bottom by -DEG/2) about the
    // vertical axis through the box centre, right-handed about +y.
    let d: Deformation = "twist:120".parse().unwrap();
    d.apply(&rest, 1.0, &mut out);
    let i = rest.positions.iter().position(|p| *p == Vec3::ONE).unwrap();
    let want = glam::Quat::from_rotation_y(60f32.to_radians()) * Vec3::ONE;
    assert!((out[i] - want).length() < 1e-5, "{:?} vs {want:?}", out[i]);
}
