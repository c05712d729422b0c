//! The diffusion profiles (`bssrdf::profile`) through every consumer: the semi-analytic form
//! factor and its cubature short cut against adaptive cubature of `R` itself, one-point `f32`
//! estimates against the `f64` profile, tables against the analytic functions they tabulate,
//! and the plane integral against each profile's total diffuse reflectance.

use glam::{DVec3, Vec3};
use lucent_core::bssrdf::tables::{RadialTable, TABLE_SIZE};
use lucent_core::bssrdf::{Material, Profile, ProfileKind};
use lucent_core::formfactor::montecarlo::adaptive_cubature;
use lucent_core::formfactor::{FormFactorOptions, form_factor};
use lucent_core::solver::oracle::{ProfileF32, ReceiverSources};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

const DISTANCE_FORM: [(ProfileKind, bool); 3] =
    [(ProfileKind::Dipole, false), (ProfileKind::Dipole, true), (ProfileKind::Pbd, true)];

/// Every profile, with and without single scattering where it has it.
fn every_profile() -> impl Iterator<Item = (ProfileKind, bool)> {
    ProfileKind::ALL
        .into_iter()
        .flat_map(|kind| [(kind, false), (kind, true)])
        .filter(|&(kind, single)| !single || kind.has_single_scattering())
}

fn profile(name: &str, mm_per_unit: f64, kind: ProfileKind, single: bool) -> Profile {
    Profile::of_kind(&Material::by_name(name).unwrap(), mm_per_unit, kind, single)
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-300)
}

/// Random triangles and receivers around a few mean free paths, including receivers in the
/// triangle's plane and over its interior, where the distance-form profiles stay finite.
#[test]
fn form_factor_matches_adaptive_cubature_for_every_distance_profile() {
    let mut rng = Pcg64Mcg::seed_from_u64(2013);
    let materials = ["skimmilk", "marble", "ketchup", "skin1"];
    let mut worst = 0.0f64;
    for case in 0..48 {
        let (kind, single) = DISTANCE_FORM[case % 3];
        let name = materials[case % materials.len()];
        let mm_per_unit = 10f64.powf(rng.random_range(-1.0..1.0));
        let d = profile(name, mm_per_unit, kind, single);
        let size = 4.0 * d.z_v[1];
        let tri: [DVec3; 3] = std::array::from_fn(|_| {
            DVec3::new(
                rng.random_range(-size..size),
                rng.random_range(-size..size),
                rng.random_range(-size..size),
            )
        });
        let n_p = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
        if n_p.length() < 0.05 * size * size {
            continue;
        }
        // Every fourth receiver lies in the triangle's plane, over its interior.
        let x_o = if case % 4 == 0 {
            (tri[0] + tri[1] + tri[2]) / 3.0 + 0.2 * (tri[1] - tri[0])
        } else {
            DVec3::new(
                rng.random_range(-size..size),
                rng.random_range(-size..size),
                rng.random_range(-size..size),
            )
        };
        let n_o = DVec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), 1.0).normalize();
        let f = form_factor(&tri, x_o, n_o, &d, &FormFactorOptions::default());
        // Tables are piecewise linear: adaptive cubature converges slowly at their kinks.
        let tol = if d.tables.is_some() { 1e-5 } else { 1e-10 };
        let want = adaptive_cubature(&tri, x_o, n_o, &d, tol);
        let total = d.total_diffuse_reflectance();
        for c in 0..3 {
            // Transport below 1e-6 of the plane's total is invisible; there the tables' cut
            // tail (1e-8 of Q(0)) dominates the relative error.
            if want[c] < 1e-6 * total[c] {
                assert!(f[c] < 2e-6 * total[c], "{kind} {name}: {f:?} vs {want:?}");
                continue;
            }
            let e = rel(f[c], want[c]);
            worst = worst.max(e);
            assert!(e < 5e-3, "case {case} {kind} ss={single} {name} c={c}: {} vs {}", f[c], want[c]);
        }
    }
    println!("worst relative error of the form factor against adaptive cubature: {worst:.2e}");
}

/// A polygon much larger than the diffusion length, under a receiver on it: `∫ R dA` over the
/// plane, the profile's total diffuse reflectance (a closed form for the dipoles, the table's
/// effective albedo for PBD).
#[test]
fn huge_polygon_gives_each_profiles_total_reflectance() {
    for (kind, single) in DISTANCE_FORM {
        for name in ["marble", "skimmilk", "ketchup"] {
            let d = profile(name, 1.0, kind, single);
            let reach = (0..3).map(|c| 60.0 / d.sigma_tr[c]).fold(0.0, f64::max).max(300.0 * d.z_r[0]);
            let quad = [
                DVec3::new(-reach, -reach, 0.0),
                DVec3::new(reach, -reach, 0.0),
                DVec3::new(reach, reach, 0.0),
                DVec3::new(-reach, reach, 0.0),
            ];
            let f = form_factor(&quad, DVec3::ZERO, DVec3::Z, &d, &FormFactorOptions::default());
            let total = d.total_diffuse_reflectance();
            for c in 0..3 {
                assert!(total[c] > 0.0 && total[c] < 1.0, "{kind} {name}: total {total:?}");
                assert!(
                    rel(f[c], total[c]) < 2e-3,
                    "{kind} ss={single} {name} c={c}: {} vs {}",
                    f[c],
                    total[c]
                );
            }
        }
    }
}

/// The batched `f32` estimates the solver uses equal the `f64` profile, for every profile.
#[test]
fn one_point_estimates_match_the_f64_profile() {
    for (kind, single) in every_profile() {
        let d = profile("skimmilk", 0.5, kind, single);
        let d32 = ProfileF32::new(&d);
        let x_o = Vec3::new(0.1, -0.2, 0.05);
        let n_o = Vec3::new(0.3, 0.4, 0.866).normalize();
        let src = ReceiverSources::new(&d32, x_o, n_o);
        let p = [
            Vec3::new(3.0, 1.0, 0.0),
            Vec3::new(-2.0, 0.0, 1.0),
            Vec3::new(1.0, -1.5, 0.5),
            Vec3::new(0.3, 0.2, 0.1),
        ];
        let area = [0.01f32, 0.02, 0.003, 0.05];
        let got = src.point_samples(&d32, &p, &area);
        for j in 0..4 {
            let want = d.rd(x_o.as_dvec3(), n_o.as_dvec3(), p[j].as_dvec3());
            for c in 0..3 {
                let w = want[c] * area[j] as f64;
                assert!(
                    rel(got[j][c] as f64, w) < 2e-3,
                    "{kind} ss={single} point {j} c={c}: {} vs {w}",
                    got[j][c]
                );
            }
            assert_eq!(
                src.point_sample(&d32, p[j], area[j]),
                got[j],
                "scalar and batched forms agree exactly"
            );
        }
    }
}

/// A table of the distance-form dipole's own pole (in optical units) reproduces it: the grid
/// and the interpolation are accurate where the profile matters.
#[test]
fn radial_table_reproduces_an_analytic_profile() {
    // One pole with z = 1 (optical units) and sigma_tr = 0.2: R = z (1 + σ d) e^{-σ d} / d³ / 4π.
    let (z, sigma) = (1.0f64, 0.2f64);
    let d_of = |r: f64| (r * r + z * z).sqrt();
    let radial = |r: f64| {
        z * (1.0 + sigma * d_of(r)) * (-sigma * d_of(r)).exp()
            / d_of(r).powi(3)
            / (4.0 * std::f64::consts::PI)
    };
    let tail = |r: f64| z * (-sigma * d_of(r)).exp() / d_of(r) / (4.0 * std::f64::consts::PI);
    let sigma_t = 2.5; // per mesh unit
    let t = RadialTable::from_optical(sigma_t, 400.0, radial, tail);
    assert_eq!(t.r_radial.len(), TABLE_SIZE + 1);
    for r_opt in [0.0, 0.01, 0.3, 1.0, 3.0, 10.0, 40.0] {
        let r = r_opt / sigma_t;
        let want_r = sigma_t * sigma_t * radial(r_opt);
        let want_q = tail(r_opt);
        if r_opt > 0.0 {
            assert!(rel(t.radial(r), want_r) < 2e-3, "R({r_opt}): {} vs {want_r}", t.radial(r));
        }
        assert!(rel(t.tail(r), want_q) < 1e-4, "Q({r_opt}): {} vs {want_q}", t.tail(r));
    }
    assert!(rel(t.total(), std::f64::consts::TAU * tail(0.0)) < 1e-12);
    assert_eq!(t.tail(2.0 * t.r_max), 0.0);
}

#[test]
fn profile_names_parse_and_bad_names_are_one_line_errors() {
    for k in ProfileKind::ALL {
        assert_eq!(k.name().parse::<ProfileKind>().unwrap(), k);
    }
    assert_eq!(" PBD ".parse::<ProfileKind>().unwrap(), ProfileKind::Pbd);
    let e = "jensen".parse::<ProfileKind>().unwrap_err().to_string();
    assert!(e.contains("'jensen'") && e.contains("mertens, dipole, pbd") && !e.contains('\n'), "{e}");
}
