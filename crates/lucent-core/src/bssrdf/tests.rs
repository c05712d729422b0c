use super::*;
use std::f64::consts::PI;

/// Integrate R_d over the plane numerically (radial, substitution r = t/(1-t) on [0,1)).
fn integrate_rd_plane(d: &Profile) -> [f64; 3] {
    let n = 400_000;
    let mut sum = [0.0; 3];
    for i in 0..n {
        // midpoint rule in u = ln(r): dense near r = 0 where R_d peaks
        let u0 = -14.0;
        let u1 = 8.0;
        let u = u0 + (u1 - u0) * (i as f64 + 0.5) / n as f64;
        let r = u.exp();
        let du = (u1 - u0) / n as f64;
        let rd = d.rd_planar(r);
        for c in 0..3 {
            sum[c] += rd[c] * 2.0 * PI * r * r * du;
        }
    }
    sum
}

#[test]
fn total_diffuse_reflectance_matches_numerical_integral() {
    for name in ["marble", "skimmilk", "ketchup", "skin1", "wax"] {
        let m = Material::by_name(name).unwrap();
        let d = Profile::new(&m, 1.0);
        let closed = d.total_diffuse_reflectance();
        let num = integrate_rd_plane(&d);
        for c in 0..3 {
            let rel = (num[c] - closed[c]).abs() / closed[c];
            assert!(rel < 1e-4, "{name} channel {c}: numeric {} vs closed {}", num[c], closed[c]);
        }
    }
}

#[test]
fn total_diffuse_reflectance_limits() {
    // No scattering: alpha' -> 0 gives R_d -> 0; no absorption: alpha' -> 1 gives R_d -> 1.
    let dark = Material::custom("dark", [1e-6; 3], [10.0; 3], 1.3).unwrap();
    let white = Material::custom("white", [10.0; 3], [1e-9; 3], 1.3).unwrap();
    for c in 0..3 {
        assert!(Profile::new(&dark, 1.0).total_diffuse_reflectance()[c] < 1e-6);
        assert!((Profile::new(&white, 1.0).total_diffuse_reflectance()[c] - 1.0).abs() < 1e-3);
    }
    // Scale-invariant: R_d_total depends on alpha' only.
    let m = Material::by_name("marble").unwrap();
    let a = Profile::new(&m, 1.0).total_diffuse_reflectance();
    let b = Profile::new(&m, 37.0).total_diffuse_reflectance();
    for c in 0..3 {
        assert!((a[c] - b[c]).abs() < 1e-12);
    }
}

#[test]
fn rd_is_reciprocal_in_the_planar_case() {
    let d = Profile::new(&Material::by_name("skin2").unwrap(), 1.0);
    let n = glam::DVec3::Z;
    let x = glam::DVec3::new(0.3, -1.2, 0.0);
    let y = glam::DVec3::new(-2.0, 0.7, 0.0);
    let (a, b) = (d.rd(x, n, y), d.rd(y, n, x));
    for c in 0..3 {
        assert!((a[c] - b[c]).abs() <= 1e-14 * a[c].abs());
        assert!((a[c] - d.rd_planar((x - y).length())[c]).abs() <= 1e-12 * a[c]);
    }
}

#[test]
fn scale_converts_mm_to_mesh_units() {
    // A 1-unit mesh at 10 cm: one unit is 100 mm, so sigma_tr per unit is 100x sigma_tr per mm.
    let m = Material::by_name("Marble").unwrap();
    let per_mm = Profile::new(&m, 1.0);
    let per_unit = Profile::for_model_scale(&m, 1.0, 0.1);
    for c in 0..3 {
        assert!((per_unit.sigma_tr[c] - 100.0 * per_mm.sigma_tr[c]).abs() < 1e-9);
        assert!((per_unit.z_r[c] - per_mm.z_r[c] / 100.0).abs() < 1e-12);
    }
}

#[test]
fn fresnel_limits() {
    // Normal incidence: ((eta-1)/(eta+1))^2.
    let eta: f64 = 1.3;
    let r0 = ((eta - 1.0) / (eta + 1.0)).powi(2);
    assert!((fresnel_dielectric(1.0, eta) - r0).abs() < 1e-12);
    assert!((fresnel_dielectric(0.0, eta) - 1.0).abs() < 1e-12);
    assert!((fresnel_transmittance(1.0, eta) - (1.0 - r0)).abs() < 1e-12);
    // Total internal reflection from inside (eta < 1) beyond the critical angle.
    assert_eq!(fresnel_dielectric(0.1, 1.0 / 1.5), 1.0);
}

/// Jensen's polynomial fit for F_dr against the quantity it fits: the cosine-weighted hemispherical
/// average of the exact Fresnel reflectance for light arriving from inside the medium,
/// 2 * integral_0^1 F_r(mu, 1/eta) mu dmu (midpoint rule, converged to ~1e-9).
#[test]
fn fresnel_diffuse_reflectance_matches_hemispherical_integral() {
    for eta in [1.1, 1.2, 1.3, 1.4, 1.5] {
        let n = 100_000;
        let integral: f64 = (0..n)
            .map(|i| {
                let mu = (i as f64 + 0.5) / n as f64;
                2.0 * fresnel_dielectric(mu, 1.0 / eta) * mu
            })
            .sum::<f64>()
            / n as f64;
        let fit = fresnel_diffuse_reflectance(eta);
        assert!((fit - integral).abs() < 2e-3, "eta {eta}: fit {fit} vs integral {integral}");
    }
}

#[test]
fn materials_by_name() {
    assert_eq!(Material::by_name("SKIMMILK").unwrap().name, "Skimmilk");
    assert_eq!(Material::by_name("candle-wax").unwrap().name, "Wax");
    let err = Material::by_name("unobtainium").unwrap_err().to_string();
    assert!(err.contains("unobtainium") && err.contains("Marble"));
    assert!(Material::custom("x", [1.0, 0.0, 1.0], [1.0; 3], 1.3).is_err());
    assert!(Material::custom("x", [1.0; 3], [1.0; 3], f64::NAN).is_err());
}

/// `plane_reflectance(t)` is the profile integrated over a plane `t` away (numerically, in
/// `ln s` from `s = t`, as `R` depends on distance only): equal to the total at 0, falling
/// with `t`, for both distance-form profiles.
#[test]
fn plane_reflectance_is_the_profile_over_a_parallel_plane() {
    let m = Material::by_name("skimmilk").unwrap();
    for kind in [ProfileKind::Pbd, ProfileKind::Dipole] {
        let d = Profile::of_kind(&m, 1.0, kind, false);
        let total = d.total_diffuse_reflectance();
        let at0 = d.plane_reflectance(0.0);
        for c in 0..3 {
            assert!(
                (at0[c] / total[c] - 1.0).abs() < 1e-9,
                "{kind:?} channel {c}: {} vs {}",
                at0[c],
                total[c]
            );
        }
        let mut last = at0;
        for t in [0.3f64, 1.0, 3.0, 10.0] {
            // 2π ∫_t^∞ R(s) s ds, in u = ln s.
            let n = 200_000;
            let (u0, u1) = (t.ln(), 9.0f64);
            let du = (u1 - u0) / n as f64;
            let mut want = [0.0; 3];
            for i in 0..n {
                let s = (u0 + (i as f64 + 0.5) * du).exp();
                let rd = d.rd_planar(s);
                (0..3).for_each(|c| want[c] += 2.0 * PI * rd[c] * s * s * du);
            }
            let got = d.plane_reflectance(t);
            for c in 0..3 {
                assert!(got[c] <= last[c], "{kind:?} not falling at {t}");
                assert!(
                    (got[c] - want[c]).abs() < 2e-3 * total[c],
                    "{kind:?} at {t} mm, channel {c}: {} vs {}",
                    got[c],
                    want[c]
                );
            }
            last = got;
        }
    }
}
