//! Ray-cast shadows at the leaves (Mertens §5.3): analytic shadow discs of a sphere over a plane,
//! shadows that follow a deforming mesh after a refit, and the BVH against brute force.

mod irradiance_util;

use glam::Vec3;
use irradiance_util::{merge, plane, torus, twist, uv_sphere};
use lucent_core::bssrdf::Entry;
use lucent_core::irradiance::{
    Light, SceneLight, ShadowCaster, Update, face_irradiance, face_irradiance_shadowed,
};
use lucent_core::mesh::{Bvh, Mesh};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

const PLANE_SIZE: f32 = 4.0;
const PLANE_CELLS: u32 = 120;
const RADIUS: f32 = 0.5;
const ETA: f64 = 1.3;

/// A plane (faces first) with a sphere of radius `RADIUS` floating at `center` above it.
fn scene(center: Vec3) -> (Mesh, usize) {
    let p = plane(PLANE_SIZE, PLANE_CELLS);
    let n = p.triangles.len();
    let m = merge(&p, &uv_sphere(center, RADIUS, 96, 48));
    // The generators' winding (outward normals) is what the light's cosine relies on.
    for f in n..m.triangles.len() {
        assert!(m.face_normal(f).dot(m.face_centroid(f) - center) > 0.0);
    }
    (m, n)
}

/// Compares which plane faces the shadow caster leaves unlit against `in_shadow(centroid)`,
/// skipping faces whose centroid lies within `band` of the predicted edge (`edge_distance`),
/// where the faceted sphere and the analytic one may disagree. Returns the number of shadowed
/// faces and the largest distance of a shadowed centroid from `axis_point`.
fn check_disc(
    mesh: &Mesh,
    plane_faces: usize,
    light: Light,
    caster: &ShadowCaster,
    disc_center: Vec3,
    disc_radius: f32,
    band: f32,
) -> (usize, f32) {
    let lit =
        face_irradiance_shadowed(mesh, &[SceneLight::from(light)], None, &Entry::fresnel(ETA), Some(caster));
    let unshadowed = face_irradiance(mesh, &[light], &Entry::fresnel(ETA));
    let (mut shadowed, mut reach) = (0, 0.0f32);
    for f in 0..plane_faces {
        assert!(unshadowed[f].x > 0.0, "every plane face faces the light");
        let c = mesh.face_centroid(f);
        let rho = (c - disc_center).length();
        let dark = lit[f].x == 0.0;
        if dark {
            shadowed += 1;
            reach = reach.max(rho);
        } else {
            assert_eq!(lit[f], unshadowed[f], "lit faces get the full light");
        }
        if (rho - disc_radius).abs() > band {
            assert_eq!(
                dark,
                rho < disc_radius,
                "face {f} at distance {rho} from the disc centre (radius {disc_radius})"
            );
        }
    }
    (shadowed, reach)
}

#[test]
fn sphere_casts_a_disc_of_its_radius_under_a_directional_light() {
    let center = Vec3::new(0.0, 1.0, 0.0);
    let (mesh, n) = scene(center);
    let caster = ShadowCaster::new(&mesh);
    let light = Light::Directional { direction: -Vec3::Y, irradiance: Vec3::ONE };
    // Parallel light: the shadow is the sphere's silhouette, a disc of radius r below it. The
    // 96-gon silhouette is within r (1 - cos(π/96)) = 0.0003 of the circle.
    let cell = PLANE_SIZE / PLANE_CELLS as f32;
    let (count, reach) = check_disc(&mesh, n, light, &caster, Vec3::ZERO, RADIUS, 0.002);
    let expected = std::f32::consts::PI * RADIUS * RADIUS / (cell * cell / 2.0);
    println!("directional: {count} faces shadowed (disc area predicts {expected:.0}), reach {reach}");
    assert!((count as f32 - expected).abs() < 0.03 * expected);
    assert!(reach < RADIUS && reach > RADIUS - cell);
}

#[test]
fn sphere_casts_the_cone_shadow_of_a_point_light() {
    let (h, light_height) = (1.0, 3.0);
    let center = Vec3::new(0.0, h, 0.0);
    let (mesh, n) = scene(center);
    let caster = ShadowCaster::new(&mesh);
    let light = Light::Point { position: Vec3::new(0.0, light_height, 0.0), intensity: Vec3::ONE };
    // The tangent cone from the light has half-angle asin(r / (H - h)); it meets the plane in a
    // disc of radius H tan(that angle).
    let alpha = (RADIUS / (light_height - h)).asin();
    let radius = light_height * alpha.tan();
    let (count, reach) = check_disc(&mesh, n, light, &caster, Vec3::ZERO, radius, 0.005);
    println!("point: {count} faces shadowed, predicted radius {radius}, reach {reach}");
    assert!(count > 1000);
}

#[test]
fn shadow_follows_the_mesh_after_a_refit() {
    let (mut mesh, n) = scene(Vec3::new(0.0, 1.0, 0.0));
    let mut caster = ShadowCaster::new(&mesh);
    caster.rebuild_ratio = f32::INFINITY; // exercise the refit path
    let light = Light::Directional { direction: Vec3::new(0.3, -1.0, 0.2), irradiance: Vec3::ONE };
    let dir = Vec3::new(0.3, -1.0, 0.2).normalize();
    for step in 1..=3 {
        // Move the sphere (its vertices only: a deformation of the whole mesh, same topology).
        let offset = Vec3::new(0.25 * step as f32, 0.1 * step as f32, -0.2 * step as f32);
        let (before, _) = scene(Vec3::new(0.0, 1.0, 0.0));
        for (p, q) in mesh
            .positions
            .iter_mut()
            .zip(&before.positions)
            .skip(((PLANE_CELLS + 1) * (PLANE_CELLS + 1)) as usize)
        {
            *p = *q + offset;
        }
        assert_eq!(caster.update(&mesh), Update::Refit);
        let center = Vec3::new(0.0, 1.0, 0.0) + offset;
        // A tilted parallel light: the shadow is an ellipse around where the axis through the
        // centre meets the plane. Check membership exactly with the ray-sphere test instead.
        let hit = center - dir * (center.y / -dir.y);
        let lit = face_irradiance_shadowed(
            &mesh,
            &[SceneLight::from(light)],
            None,
            &Entry::fresnel(ETA),
            Some(&caster),
        );
        let mut shadowed = 0;
        for (f, e) in lit.iter().enumerate().take(n) {
            let c = mesh.face_centroid(f);
            // Distance from the ray c - t dir (towards the light) to the sphere's centre.
            let to_center = center - c;
            let along = to_center.dot(-dir);
            let miss = (to_center - (-dir) * along).length();
            if (miss - RADIUS).abs() > 0.002 {
                assert_eq!(e.x == 0.0, miss < RADIUS, "step {step}, face {f}");
            }
            shadowed += (e.x == 0.0) as usize;
        }
        assert!(shadowed > 500, "step {step}: shadow near {hit}");
    }
}

/// Möller–Trumbore in `f64`, both sides: the reference for the tree's answers.
fn hits(o: Vec3, d: Vec3, t: [Vec3; 3], t_max: f32) -> bool {
    let (o, d) = (o.as_dvec3(), d.as_dvec3());
    let [a, b, c] = t.map(|v| v.as_dvec3());
    let (e1, e2) = (b - a, c - a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-300 {
        return false;
    }
    let s = o - a;
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    let tt = e2.dot(q) / det;
    u >= 0.0 && v >= 0.0 && u + v <= 1.0 && tt > 0.0 && tt < t_max as f64
}

/// Random rays inside and around the mesh: the tree's any-hit answer equals brute force over
/// all triangles. Returns the number of occluded rays.
fn compare_with_brute_force(mesh: &Mesh, bvh: &Bvh, seed: u64) -> usize {
    let mut rng = Pcg64::seed_from_u64(seed);
    let (lo, hi) = mesh.bounds();
    let (mut occluded, mut disagree) = (0, 0);
    for _ in 0..2000 {
        let o = lo + (hi - lo) * Vec3::new(rng.random(), rng.random(), rng.random()) * 1.2 - (hi - lo) * 0.1;
        let d =
            Vec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
        let t_max = rng.random_range(0.05..2.0f32);
        let want = (0..mesh.triangles.len()).any(|f| hits(o, d, mesh.corners(f), t_max));
        let got = bvh.occluded(o, d, 0.0, t_max);
        occluded += got as usize;
        // f32 and f64 may differ for a ray through an edge or vertex; such rays are rare enough
        // for random directions that any disagreement here is a traversal bug.
        disagree += (want != got) as usize;
    }
    assert_eq!(disagree, 0);
    occluded
}

#[test]
fn bvh_answers_like_brute_force_after_build_refit_and_rebuild() {
    let mut mesh = torus(1.0, 0.35, 48);
    for f in 0..mesh.triangles.len() {
        let c = mesh.face_centroid(f);
        let ring = Vec3::new(c.x, 0.0, c.z).normalize() * 1.0;
        assert!(mesh.face_normal(f).dot(c - ring) > 0.0, "torus winding");
    }
    let mut caster = ShadowCaster::new(&mesh);
    assert!(compare_with_brute_force(&mesh, caster.bvh(), 1) > 100);

    // Twist (a Mertens fig. 6.7 style deformation) and refit.
    twist(&mut mesh, 2.0);
    caster.rebuild_ratio = f32::INFINITY;
    assert_eq!(caster.update(&mesh), Update::Refit);
    assert!(compare_with_brute_force(&mesh, caster.bvh(), 2) > 100);

    // Scramble the vertices: refitting now inflates the boxes (SAH cost up several times), so
    // the caster rebuilds; answers stay exact either way.
    let mut rng = Pcg64::seed_from_u64(3);
    for i in (1..mesh.positions.len()).rev() {
        let j = rng.random_range(0..=i);
        mesh.positions.swap(i, j);
    }
    let mut refit_only = caster.clone();
    refit_only.update(&mesh);
    let ratio = refit_only.bvh().sah_cost() / refit_only.bvh().built_cost();
    assert!(ratio > 2.0, "SAH cost ratio after scrambling: {ratio}");
    compare_with_brute_force(&mesh, refit_only.bvh(), 4);
    caster.rebuild_ratio = 2.0;
    assert_eq!(caster.update(&mesh), Update::Rebuild);
    compare_with_brute_force(&mesh, caster.bvh(), 5);
}

#[test]
fn empty_mesh_casts_no_shadow() {
    let caster = ShadowCaster::new(&Mesh::default());
    assert!(!caster.bvh().occluded(Vec3::ZERO, Vec3::X, 0.0, f32::INFINITY));
}
