//! Photon beam diffusion (`bssrdf::beam_diffusion`) against references nobody here derived for
//! it: a closed form for single scattering, pbrt-v3's polynomial fits of the Fresnel moments,
//! and an analog Monte Carlo random walk in a half-space, with and without a refracting
//! boundary, which also checks the exact half-space albedo the `pbd` profile is calibrated to.

use lucent_core::bssrdf::beam_diffusion::{EffectiveAlbedo, calibrated_albedo, effective_albedo};
use lucent_core::bssrdf::halfspace::HalfSpace;
use lucent_core::bssrdf::tables::channel_tables;
use lucent_core::bssrdf::{fresnel_dielectric, fresnel_moment1, fresnel_moment2};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

/// pbrt-v3's published fits (Fresnel moments of the dielectric reflectance), good to ~1%.
fn pbrt_fm1(eta: f64) -> f64 {
    let e = [1.0, eta, eta * eta, eta.powi(3), eta.powi(4), eta.powi(5)];
    let c: [f64; 6] = if eta < 1.0 {
        [0.45966, -1.73965, 3.37668, -3.904945, 2.49277, -0.68441]
    } else {
        [-4.61686, 11.1136, -10.4646, 5.11455, -1.27198, 0.12746]
    };
    (0..6).map(|i| c[i] * e[i]).sum()
}

#[test]
fn fresnel_moments_match_pbrts_fits_and_vanish_at_eta_one() {
    for eta in [1.0 / 1.5, 1.0 / 1.3, 1.3, 1.5] {
        let (ours, fit) = (fresnel_moment1(eta), pbrt_fm1(eta));
        println!("FM1({eta:.3}) = {ours:.5} (pbrt fit {fit:.5})");
        assert!((ours - fit).abs() < 0.01 * fit.max(0.05), "FM1({eta}): {ours} vs {fit}");
    }
    assert!(fresnel_moment1(1.0).abs() < 1e-12 && fresnel_moment2(1.0).abs() < 1e-12);
    // Total internal reflection past the critical angle: the internal moment exceeds its share.
    let mu_c2 = 1.0 - 1.0 / (1.3f64 * 1.3);
    assert!(fresnel_moment1(1.3) > 0.5 * mu_c2);
}

/// Single scattering of a normally incident beam into an index-matched half-space with
/// isotropic phase: `ρ/2 (1 - ln 2)` leaves.
#[test]
fn single_scattering_total_matches_the_closed_form() {
    for rho in [0.1, 0.5, 0.9, 0.99] {
        let got = effective_albedo(rho, 1.0).single;
        let want = 0.5 * rho * (1.0 - std::f64::consts::LN_2);
        println!("rho {rho}: single-scattering albedo {got:.5} (closed form {want:.5})");
        assert!((got / want - 1.0).abs() < 0.01, "rho {rho}: {got} vs {want}");
    }
}

/// Analog random walk into a half-space (σ_t = 1) with isotropic scattering of albedo `rho`,
/// entering with refracted direction cosine `mu_t`, below a smooth boundary of relative index
/// `eta` (light reaching it from inside is reflected with Fresnel's probability, then collides
/// where its flight ends). Returns (escaped after one scattering, escaped after more).
fn random_walk(rho: f64, eta: f64, mu_t: f64, photons: usize, seed: u64) -> (f64, f64) {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let (mut single, mut multiple) = (0usize, 0usize);
    for _ in 0..photons {
        let (mut z, mut dz) = (0.0f64, mu_t);
        let mut bounces = 0;
        loop {
            let s = -(1.0 - rng.random::<f64>()).ln();
            z += s * dz;
            if z < 0.0 {
                if rng.random::<f64>() < fresnel_dielectric(-dz, 1.0 / eta) {
                    // Mirrored into the medium; the collision there resamples the direction.
                    z = -z;
                } else {
                    if bounces == 1 {
                        single += 1;
                    } else if bounces > 1 {
                        multiple += 1;
                    }
                    break;
                }
            }
            if rng.random::<f64>() >= rho {
                break;
            }
            bounces += 1;
            dz = 2.0 * rng.random::<f64>() - 1.0;
        }
    }
    (single as f64 / photons as f64, multiple as f64 / photons as f64)
}

/// The exact half-space albedo (Chandrasekhar's H function with all orders of internal
/// reflection) against the random walk, at oblique incidence and through a refracting boundary.
#[test]
fn half_space_albedo_matches_a_random_walk() {
    let photons = 200_000;
    let mut seed = 100;
    for (rho, eta, mu_t) in
        [(0.8, 1.0, 1.0), (0.99, 1.0, 0.6), (0.9, 1.3, 1.0), (0.99, 1.3, 0.8), (0.95, 1.6, 1.0)]
    {
        seed += 1;
        let (s, m) = random_walk(rho, eta, mu_t, photons, seed);
        let mc = s + m;
        let noise = (mc * (1.0 - mc) / photons as f64).sqrt();
        let exact = HalfSpace::new(rho, eta).albedo(mu_t);
        println!("rho {rho} eta {eta} mu_t {mu_t}: exact {exact:.4}, random walk {mc:.4} ± {noise:.4}");
        assert!((exact - mc).abs() < 4.0 * noise, "rho {rho} eta {eta} mu_t {mu_t}: {exact} vs {mc}");
    }
}

/// The calibrated `pbd` tables integrate to the exact half-space albedo, single scattering kept
/// as photon beam diffusion computes it (exact for a half-space).
#[test]
fn calibrated_tables_integrate_to_the_exact_albedo() {
    for eta in [1.0, 1.3, 2.0] {
        let rho = [0.3, 0.9, 0.999];
        let tables = channel_tables(&rho, &[1.0; 3], eta, true, true);
        for (channel, &rho) in tables.channels.iter().zip(&rho) {
            let (total, exact) = (channel.total(), HalfSpace::new(rho, eta).albedo(1.0));
            let raw = effective_albedo(rho, eta).total();
            println!("eta {eta} rho {rho}: calibrated {total:.5}, exact {exact:.5}, uncalibrated {raw:.5}");
            assert!((total - exact).abs() < 1e-6, "eta {eta} rho {rho}: {total} vs {exact}");
            // Diffusion overestimates at eta up to 1.3; at eta 2 it can fall short (0.125 against
            // 0.133 at rho 0.9): the error is not one factor, hence a calibration per material.
            if eta <= 1.3 {
                assert!(raw > exact, "diffusion overestimates: {raw} vs {exact}");
            }
        }
    }
}

#[test]
fn effective_albedo_near_a_random_walk() {
    let photons = 400_000;
    for (k, rho) in [0.3, 0.8, 0.99].into_iter().enumerate() {
        let (mc_single, mc_multiple) = random_walk(rho, 1.0, 1.0, photons, 7 + k as u64);
        let mc = mc_single + mc_multiple;
        let noise = (mc * (1.0 - mc) / photons as f64).sqrt();
        let pbd = effective_albedo(rho, 1.0);
        println!(
            "rho {rho}: PBD total {:.4} (single {:.4}, multiple {:.4}); random walk {mc:.4} ± {noise:.4} \
             (single {mc_single:.4}, multiple {mc_multiple:.4})",
            pbd.total(),
            pbd.single,
            pbd.multiple
        );
        // Single scattering is exact in PBD: within the walk's noise.
        let single_noise = (mc_single * (1.0 - mc_single) / photons as f64).sqrt();
        assert!((pbd.single - mc_single).abs() < 5.0 * single_noise + 2e-3, "rho {rho} single");
        // Diffusion is an approximation. Measured (400K photons): PBD in pbrt-v3's form gives
        // 8.7%, 14% and 12% more than the walk at rho = 0.3, 0.8, 0.99 (its multiple part is
        // 15-40% high, single scattering exact); the classic dipole's multiple scattering alone
        // is 24% high at 0.99. This is why the profile lucent renders with is calibrated
        // (`calibrated_tables_integrate_to_the_exact_albedo`); the bound pins the raw figure.
        assert!(
            pbd.total() > mc && pbd.total() < 1.15 * mc + 5.0 * noise,
            "rho {rho}: {} vs {mc}",
            pbd.total()
        );
    }
}

#[test]
fn effective_albedo_table_is_monotone_and_inverts() {
    let t = EffectiveAlbedo::new(1.3);
    assert!(t.rho_eff.windows(2).all(|w| w[0] <= w[1]), "{:?}", t.rho_eff);
    // The calibrated albedo stays below 1 and reaches it at rho = 1 (the last row, rho = 1 - 1e-9).
    assert!(t.rho_eff[0] == 0.0 && t.rho_eff.iter().all(|&a| a < 1.0), "{:?}", &t.rho_eff[90..]);
    assert!(t.rho_eff[99] > 0.9998, "{}", t.rho_eff[99]);
    for target in [0.1, 0.5, 0.8] {
        let rho = t.invert(target).unwrap();
        let back = calibrated_albedo(rho, 1.3);
        assert!((back - target).abs() < 0.01, "{target}: rho {rho} gives {back}");
    }
    assert!(t.invert(1.5).is_none());
}
