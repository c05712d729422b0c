//! Spherical-harmonic environment irradiance (Ramamoorthi & Hanrahan 2001; Mertens §5.3)
//! against closed forms and against brute-force integration over the texels of real HDR probes.

use glam::{Quat, Vec3};
use lucent_core::Rgb;
use lucent_core::bssrdf::{fresnel_diffuse_reflectance, fresnel_transmittance};
use lucent_core::irradiance::{
    BandWeights, EnvMap, EnvMapError, Environment, Sh9, equirect_direction, equirect_uv,
};
use std::f32::consts::PI;
use std::path::PathBuf;

fn asset(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../assets").join(name)
}

/// Unit directions spread over the sphere (Fibonacci lattice) plus the six axes.
fn normals(n: usize) -> Vec<Vec3> {
    let golden = PI * (3.0 - 5f32.sqrt());
    let mut v: Vec<Vec3> = (0..n)
        .map(|i| {
            let y = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let r = (1.0 - y * y).sqrt();
            let phi = golden * i as f32;
            Vec3::new(r * phi.cos(), y, r * phi.sin())
        })
        .collect();
    v.extend([Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z]);
    v
}

/// `∫ L(ω) K(n·ω) dω` by summing over every texel with its exact solid angle.
fn brute_force(map: &EnvMap, n: Vec3, kernel: impl Fn(f32) -> f32) -> Rgb {
    let mut e = [0.0f64; 3];
    for j in 0..map.height {
        let dw = map.texel_solid_angle(j) as f64;
        for i in 0..map.width {
            let k = kernel(n.dot(map.texel_direction(i, j))) as f64;
            if k != 0.0 {
                let l = map.texel(i, j);
                for c in 0..3 {
                    e[c] += l[c] as f64 * k * dw;
                }
            }
        }
    }
    Rgb::new(e[0] as f32, e[1] as f32, e[2] as f32)
}

fn cosine(mu: f32) -> f32 {
    mu.max(0.0)
}

fn rel(a: Rgb, b: Rgb) -> f32 {
    ((a - b).abs() / b.abs().max(Rgb::splat(1e-12))).max_element()
}

#[test]
fn equirect_mapping_round_trips_and_follows_the_documented_axes() {
    // Documented convention: top row +Y, centre -Z, u = 3/4 +X, u = 1/4 -X.
    assert!((equirect_direction(0.5, 0.0) - Vec3::Y).length() < 1e-6);
    assert!((equirect_direction(0.5, 0.5) + Vec3::Z).length() < 1e-6);
    assert!((equirect_direction(0.75, 0.5) - Vec3::X).length() < 1e-6);
    assert!((equirect_direction(0.25, 0.5) + Vec3::X).length() < 1e-6);
    for n in normals(200) {
        let (u, v) = equirect_uv(n);
        assert!((equirect_direction(u, v) - n).length() < 1e-5, "{n}");
    }
}

#[test]
fn texel_solid_angles_sum_to_four_pi() {
    let map = EnvMap::from_fn(64, 32, |_| Rgb::ONE);
    let total: f64 = (0..32).map(|j| map.texel_solid_angle(j) as f64 * 64.0).sum();
    assert!((total - 4.0 * std::f64::consts::PI).abs() < 1e-5, "{total}");
}

#[test]
fn constant_radiance_gives_pi_l_for_every_normal() {
    // E = ∫_hemisphere L cos dω = π L, whatever the normal.
    let l = Rgb::new(1.0, 0.5, 2.0);
    let env = Environment::from_map(&EnvMap::from_fn(128, 64, |_| l));
    for n in normals(64) {
        let e = env.irradiance(n);
        assert!(rel(e, PI * l) < 0.005, "n={n}: {e} vs {}", PI * l);
    }
}

#[test]
fn linear_radiance_has_the_closed_form_irradiance() {
    // L(ω) = a + b (k·ω) lies in bands 0 and 1, so the 9-term formula is exact:
    // E(n) = π a + (2π/3) b (n·k) (Funk–Hecke with A_0 = π, A_1 = 2π/3).
    let k = Vec3::new(0.3, 0.8, -0.5).normalize();
    let (a, b) = (1.0f32, 0.6f32);
    let env = Environment::from_map(&EnvMap::from_fn(256, 128, |d| Rgb::splat(a + b * k.dot(d))));
    for n in normals(64) {
        let want = PI * a + 2.0 * PI / 3.0 * b * n.dot(k);
        let got = env.irradiance(n).x;
        assert!((got - want).abs() < 2e-3 * PI * a, "n={n}: {got} vs {want}");
    }
}

#[test]
fn l22_term_is_weighted_by_c1_not_c3() {
    // L(ω) = x² − y² is pure Y22 (= 0.546274 (x² − y²)), so E(n) = A_2 (n_x² − n_y²) with
    // A_2 = π/4. Weighting L22 by c3 (a typo in public copies) would be 1.73x too large.
    let map = EnvMap::from_fn(256, 128, |d| Rgb::splat(d.x * d.x - d.y * d.y));
    let sh = map.project_sh();
    for (i, c) in sh.coeffs.iter().enumerate() {
        if i != 8 {
            assert!(c.abs().max_element() < 1e-3, "L[{i}] = {c}");
        }
    }
    for n in normals(64) {
        let want = PI / 4.0 * (n.x * n.x - n.y * n.y);
        let got = sh.irradiance(n).x;
        assert!((got - want).abs() < 2e-3, "n={n}: {got} vs {want}");
        // And against brute force over the texels.
        let bf = brute_force(&map, n, cosine).x;
        assert!((got - bf).abs() < 5e-3, "n={n}: {got} vs brute force {bf}");
    }
}

/// Grace Cathedral light probe coefficients, Ramamoorthi & Hanrahan 2001, table 1 (to 5
/// digits as reprinted with the paper's shader; the paper prints 2 digits, which these round to).
const GRACE: [[f32; 3]; 9] = [
    [0.78908, 0.43710, 0.54161],    // L00
    [0.39499, 0.34989, 0.60488],    // L1-1
    [-0.33974, -0.18236, -0.26940], // L10
    [-0.29213, -0.05562, 0.00944],  // L11
    [-0.11141, -0.05090, -0.12231], // L2-2
    [-0.26240, -0.22401, -0.47479], // L2-1
    [-0.15570, -0.09471, -0.14733], // L20
    [0.56014, 0.21444, 0.13915],    // L21
    [0.21205, -0.05432, -0.30374],  // L22
];

/// R&H 2001 eq. 12, the matrix form `E(n) = nᵀ M n` with `n = (x, y, z, 1)`: a third,
/// independently written evaluation.
fn rh_matrix_form(sh: &Sh9, n: Vec3) -> Rgb {
    use lucent_core::irradiance::sh::{C1, C2, C3, C4, C5};
    let l = &sh.coeffs;
    let m = [
        [l[8] * C1, l[4] * C1, l[7] * C1, l[3] * C2],
        [l[4] * C1, -l[8] * C1, l[5] * C1, l[1] * C2],
        [l[7] * C1, l[5] * C1, l[6] * C3, l[2] * C2],
        [l[3] * C2, l[1] * C2, l[2] * C2, l[0] * C4 - l[6] * C5],
    ];
    let v = [n.x, n.y, n.z, 1.0];
    let mut e = Rgb::ZERO;
    for i in 0..4 {
        for j in 0..4 {
            e += m[i][j] * v[i] * v[j];
        }
    }
    e
}

#[test]
fn rh_formula_equals_matrix_form_and_band_weighted_convolution() {
    // Three evaluations of E(n) for the Grace Cathedral fixture: R&H's quadratic polynomial
    // (eq. 13), their matrix form (eq. 12) and Σ A_l L_lm Y_lm(n).
    let sh = Sh9::from_array(GRACE);
    for n in normals(64) {
        let a = sh.irradiance(n);
        let b = rh_matrix_form(&sh, n);
        let c = sh.convolve(n, &BandWeights::COSINE);
        assert!((a - b).abs().max_element() < 1e-5, "n={n}: {a} vs {b}");
        assert!((a - c).abs().max_element() < 1e-5, "n={n}: {a} vs {c}");
    }
}

#[test]
fn projection_recovers_known_coefficients() {
    // A radiance built from given coefficients projects back onto them.
    let want =
        Sh9::from_array(std::array::from_fn(|i| [1.0 / (1.0 + i as f32), 0.2 * (i as f32).cos(), 0.1]));
    let got = EnvMap::from_fn(512, 256, |d| want.radiance(d)).project_sh();
    for (g, w) in got.coeffs.iter().zip(want.coeffs) {
        assert!((*g - w).abs().max_element() < 1e-3, "{g} vs {w}");
    }
}

/// Loads a probe and reduces it to 128 x 64 (box filter) so brute force stays quick.
fn probe(name: &str) -> EnvMap {
    EnvMap::load(&asset(name)).unwrap_or_else(|e| panic!("{e}")).downsampled(128, 64)
}

/// Error of the 9-coefficient irradiance against brute force over the probe's texels, for 70
/// normals spread over the sphere.
struct ShError {
    /// Mean over normals and channels of |E_sh − E| / E_peak (E_peak: the brightest irradiance
    /// of that channel over the normals).
    mean_of_peak: f32,
    /// Worst over normals and channels of |E_sh − E| / E_peak.
    worst_of_peak: f32,
    /// Mean of |E_sh − E| / E (large where E is small: normals facing dark ground).
    mean_relative: f32,
}

fn sh_error(map: &EnvMap, kernel: impl Fn(f32) -> f32 + Copy, eta: Option<f64>) -> ShError {
    let env = Environment::from_map(map);
    let entry = eta.map(lucent_core::bssrdf::Entry::fresnel);
    let pairs: Vec<(Rgb, Rgb)> = normals(64)
        .into_iter()
        .map(|n| {
            let sh = match &entry {
                Some(w) => env.transmitted_irradiance(n, w),
                None => env.irradiance(n),
            };
            (sh, brute_force(map, n, kernel))
        })
        .collect();
    let peak = pairs.iter().fold(Rgb::ZERO, |m, (_, b)| m.max(*b));
    let count = pairs.len() as f32;
    let mut e = ShError { mean_of_peak: 0.0, worst_of_peak: 0.0, mean_relative: 0.0 };
    for (a, b) in &pairs {
        let err = (*a - *b).abs();
        e.mean_of_peak += (err / peak).element_sum() / 3.0 / count;
        e.worst_of_peak = e.worst_of_peak.max((err / peak).max_element());
        e.mean_relative += (err / *b).element_sum() / 3.0 / count;
    }
    e
}

/// The bounds of Ramamoorthi & Hanrahan 2001 (§3): the 9-term approximation of the clamped
/// cosine errs by about 3% on average and at most about 9% for any lighting, both relative to
/// the peak irradiance. The worst case is a single directional light: at the horizon the
/// truncated kernel gives (1/4π)(π − (5π/4)(1/2)) = 3/32 ≈ 0.094 of the peak instead of 0.
fn check_rh_bounds(what: &str, e: &ShError) {
    println!(
        "{what}: mean {:.4} worst {:.4} of peak; mean relative {:.4}",
        e.mean_of_peak, e.worst_of_peak, e.mean_relative
    );
    assert!(e.mean_of_peak < 0.03, "{what}: mean error {}", e.mean_of_peak);
    assert!(e.worst_of_peak < 3.0 / 32.0, "{what}: worst error {}", e.worst_of_peak);
}

#[test]
fn courtyard_sh_irradiance_matches_brute_force() {
    // Measured on courtyard.exr at 128 x 64 (run with --nocapture for the figures).
    let map = probe("courtyard.exr");
    check_rh_bounds("courtyard cosine", &sh_error(&map, cosine, None));
}

#[test]
fn forest_sh_irradiance_matches_brute_force() {
    let map = probe("forest.exr");
    check_rh_bounds("forest cosine", &sh_error(&map, cosine, None));
}

#[test]
fn fresnel_transmitted_sh_irradiance_matches_brute_force() {
    // The kernel F_t(eta, μ) max(0, μ) is zonal, so per-band weights give the transmitted
    // irradiance with a truncation error of the same kind as plain irradiance.
    let eta = 1.3;
    let map = probe("courtyard.exr");
    let kernel = |mu: f32| {
        if mu > 0.0 { mu * fresnel_transmittance(mu as f64, eta) as f32 } else { 0.0 }
    };
    check_rh_bounds("courtyard Fresnel", &sh_error(&map, kernel, Some(eta)));
}

#[test]
fn fresnel_band_zero_matches_the_diffuse_reflectance_fit() {
    // A_0^t / π = 2 ∫ F_t μ dμ = 1 − F_dr,ext (light from outside). Jensen's F_dr fit is the
    // *internal* diffuse reflectance; the two are tied by 1 − F_dr,int = (1 − F_dr,ext) / eta²
    // (reciprocity with the eta² radiance scaling across the boundary). The fit is quoted as
    // good to about 1% over eta 1..2, hence the tolerance.
    for eta in [1.1, 1.3, 1.5] {
        let a0 = BandWeights::fresnel_cosine(eta).0[0] as f64 / std::f64::consts::PI;
        let fit = eta * eta * (1.0 - fresnel_diffuse_reflectance(eta));
        assert!((a0 - fit).abs() < 0.01, "eta {eta}: {a0} vs {fit}");
    }
}

#[test]
fn rotating_the_map_equals_rotating_the_normal() {
    let map = probe("courtyard.exr");
    let env = Environment::from_map(&map);
    // Rotating the pixels by 90° (a whole number of columns) ...
    let rotated = Environment::from_map(&map.rotated(90.0));
    // ... equals keeping the coefficients and rotating by the Environment's angle ...
    let turned = Environment { rotation_deg: 90.0, ..env };
    let r = Quat::from_rotation_y(-90f32.to_radians());
    let scale = env.irradiance(Vec3::Y).max_element();
    for n in normals(64) {
        let a = rotated.irradiance(n);
        let b = turned.irradiance(n);
        // ... equals evaluating the unrotated environment at R_y(-90°) n.
        let c = env.irradiance(r * n);
        assert!((a - b).abs().max_element() < 1e-3 * scale, "n={n}: {a} vs {b}");
        assert!((a - c).abs().max_element() < 1e-3 * scale, "n={n}: {a} vs {c}");
    }
}

#[test]
fn downsampling_preserves_the_integral() {
    let full = EnvMap::load(&asset("courtyard.exr")).unwrap();
    assert_eq!((full.width, full.height), (1024, 512));
    let small = full.downsampled(256, 128);
    let a = full.project_sh().coeffs[0];
    let b = small.project_sh().coeffs[0];
    assert!(rel(b, a) < 1e-4, "{b} vs {a}");
}

#[test]
fn hdr_files_load_like_exr() {
    // Write a small RGBE file and read it back (RGBE keeps 8 mantissa bits: ~1% precision).
    let map = EnvMap::from_fn(16, 8, |d| Rgb::new(1.0 + d.x, 2.0 + d.y, 0.5 + 0.25 * d.z));
    let dir = std::env::temp_dir().join(format!("lucent-envmap-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("test.hdr");
    let file = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
    let pixels: Vec<image::Rgb<f32>> = map.texels.iter().map(|t| image::Rgb(t.to_array())).collect();
    image::codecs::hdr::HdrEncoder::new(file).encode(&pixels, 16, 8).unwrap();
    let loaded = EnvMap::load(&path).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    assert_eq!((loaded.width, loaded.height), (16, 8));
    for (a, b) in loaded.texels.iter().zip(&map.texels) {
        // RGBE shares one exponent, so the error is relative to the brightest channel.
        assert!((*a - *b).abs().max_element() < 0.01 * b.max_element(), "{a} vs {b}");
    }
}

#[test]
fn bad_files_give_errors_naming_the_file() {
    let missing = asset("no-such-probe.exr");
    let err = EnvMap::load(&missing).unwrap_err();
    assert!(matches!(err, EnvMapError::Read { .. }));
    assert!(err.to_string().contains("no-such-probe.exr"), "{err}");

    let dir = std::env::temp_dir().join(format!("lucent-badmap-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let obj = dir.join("scene.obj");
    std::fs::write(&obj, b"v 0 0 0").unwrap();
    let err = EnvMap::load(&obj).unwrap_err();
    assert!(matches!(err, EnvMapError::Format { .. }), "{err}");
    assert!(err.to_string().contains("scene.obj"), "{err}");

    for name in ["garbage.exr", "garbage.hdr"] {
        let path = dir.join(name);
        std::fs::write(&path, b"this is not an image").unwrap();
        let err = EnvMap::load(&path).unwrap_err();
        assert!(err.to_string().contains(name), "{err}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The probes compiled into the binary decode to exactly the files in `assets/`.
#[test]
fn builtin_probes_equal_the_asset_files() {
    for name in ["courtyard", "forest"] {
        let builtin = EnvMap::builtin(&name.to_ascii_uppercase()).expect("a built-in name").unwrap();
        let file = EnvMap::load(&asset(&format!("{name}.exr"))).unwrap();
        assert_eq!((builtin.width, builtin.height), (file.width, file.height));
        assert!(builtin.texels == file.texels, "{name}: texels differ");
    }
    assert!(EnvMap::builtin("studio").is_none());
}
