//! The exact albedo of a semi-infinite medium: the reference the `pbd` profile is calibrated to.
//!
//! Diffusion (the dipole, photon beam diffusion) overestimates how much light a thick,
//! bright medium returns: against an analog random walk in a half-space, photon beam diffusion's
//! multiple scattering is 12-15% too bright at albedo 0.99 (more at lower albedos), and its error
//! depends on `eta`. Radiative transfer in a half-space with isotropic scattering (lucent's
//! similarity-reduced materials) has an exact solution, which this module evaluates:
//!
//! * Chandrasekhar's `H` function (*Radiative Transfer*, 1950, §39), by its closed-form integral
//!   `ln H(μ) = -(1/π) ∫_0^{π/2} ln(1 - ω φ cot φ) dv`, `φ = atan(tan v / μ)`
//!   (the textbook form after the substitution `tan θ = tan v / μ`, which removes the peak of
//!   the original integrand at small `μ`);
//! * the half-space's diffuse reflection (Chandrasekhar eq. 39.31): a beam with direction cosine
//!   `μ_0` returns the intensity `ω/(4π) H(μ) H(μ_0) / (μ + μ_0)` per unit incident flux;
//! * the smooth dielectric boundary of relative index `eta`: upward light reaching it from
//!   inside is reflected back with Fresnel's `F(μ)` (totally below the critical cosine) and the
//!   half-space reflects it again. On Gauss-Legendre nodes, split at the critical cosine, the
//!   upward intensity solves `(I - K F) u = u_1` (`K` the half-space's reflection operator,
//!   `u_1` the first return), and the albedo is the flux that leaves, `2π ∫ (1 - F) u μ dμ`.
//!
//! At `eta = 1` this is `1 - H(μ_0) √(1 - ω)` (Chandrasekhar eq. 39.33); at `ω = 1` it is 1 for
//! every `eta`; both are tests, and so is an analog random walk with Fresnel reflection.

use super::fresnel::fresnel_dielectric;
use std::f64::consts::PI;

/// Gauss-Legendre nodes per side of the critical cosine (or on `[0, 1]` at `eta = 1`).
const NODES: usize = 24;

/// `n`-point Gauss-Legendre nodes and weights on `[a, b]` (Newton's method on `P_n`).
pub(crate) fn gauss_legendre(n: usize, a: f64, b: f64) -> Vec<(f64, f64)> {
    (0..n)
        .map(|i| {
            let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                // P_n(x) and P_n'(x) by the three-term recurrence.
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=n {
                    let k = k as f64;
                    (p0, p1) = (p1, ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k);
                }
                dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                let dx = p1 / dp;
                x -= dx;
                if dx.abs() < 1e-15 {
                    break;
                }
            }
            let w = 2.0 / ((1.0 - x * x) * dp * dp);
            (0.5 * (a + b) + 0.5 * (b - a) * x, 0.5 * (b - a) * w)
        })
        .collect()
}

/// Chandrasekhar's `H(μ)` for isotropic scattering with single-scattering albedo `omega`
/// (0..=1) at direction cosine `mu` (0..=1). `H(0) = 1`; `H(1) = 2.9078` at `omega = 1`.
pub fn chandrasekhar_h(omega: f64, mu: f64) -> f64 {
    if mu <= 0.0 || omega <= 0.0 {
        return 1.0;
    }
    let f = |v: f64| {
        let phi = (v.tan() / mu).atan();
        let phi_cot = if phi < 1e-8 { 1.0 - phi * phi / 3.0 } else { phi / phi.tan() };
        (1.0 - omega * phi_cot).max(f64::MIN_POSITIVE).ln()
    };
    // Near v = 0 the integrand has a log singularity (omega = 1) or a dip of width
    // ~ √(1 - omega): panels grow geometrically from there.
    let integral = super::quadrature::integrate_geometric(1e-7, 0.5 * PI, 1.6, true, f);
    (-integral / PI).exp()
}

/// The albedo of a half-space (isotropic scattering with albedo `omega`, a smooth boundary of
/// relative index `eta`) for light that has entered it with direction cosine `mu_t`
/// (refracted, inside the medium), by parts.
#[derive(Clone, Debug)]
pub struct HalfSpace {
    omega: f64,
    /// Quadrature nodes `(μ, w)` on `[0, 1]`.
    nodes: Vec<(f64, f64)>,
    /// `H` at the nodes.
    h: Vec<f64>,
    /// Fresnel reflectance from inside at the nodes.
    fresnel: Vec<f64>,
    /// LU-free inverse of `I - K F` (`NODES`-sized, dense).
    inverse: Vec<f64>,
}

impl HalfSpace {
    /// The half-space for albedo `omega` (0..=1) and relative index `eta` (>= 1).
    pub fn new(omega: f64, eta: f64) -> Self {
        let omega = omega.clamp(0.0, 1.0);
        let mu_c = if eta > 1.0 { (1.0 - 1.0 / (eta * eta)).sqrt() } else { 0.0 };
        let mut nodes = Vec::new();
        if mu_c > 0.0 {
            nodes.extend(gauss_legendre(NODES, 0.0, mu_c));
        }
        nodes.extend(gauss_legendre(NODES, mu_c, 1.0));
        let h: Vec<f64> = nodes.iter().map(|&(mu, _)| chandrasekhar_h(omega, mu)).collect();
        let fresnel: Vec<f64> = nodes.iter().map(|&(mu, _)| fresnel_dielectric(mu, 1.0 / eta)).collect();
        let n = nodes.len();
        // K_ij = (ω/2) H(μ_i) H(μ_j) μ_j / (μ_i + μ_j) w_j maps a downward intensity at the
        // nodes to the upward intensity the half-space returns.
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                let (mu_i, mu_j, w_j) = (nodes[i].0, nodes[j].0, nodes[j].1);
                let k = 0.5 * omega * h[i] * h[j] * mu_j / (mu_i + mu_j) * w_j;
                a[i * n + j] = f64::from(u8::from(i == j)) - k * fresnel[j];
            }
        }
        let inverse = invert(a, n);
        HalfSpace { omega, nodes, h, fresnel, inverse }
    }

    /// The single-scattering part of [`HalfSpace::albedo`] that leaves directly (no internal
    /// reflection before or after the one scattering): Hanrahan & Krueger's
    /// `ω/(4π) μ_t/(μ_t + μ)` radiance, through the boundary, per unit entering flux. This is
    /// what `shading::single_scattering` computes along the view ray.
    pub fn single_albedo(&self, mu_t: f64) -> f64 {
        let mu_t = mu_t.clamp(1e-6, 1.0);
        self.nodes
            .iter()
            .zip(&self.fresnel)
            .map(|(&(mu, w), f)| 2.0 * PI * w * mu * (1.0 - f) * self.omega / (4.0 * PI) / (mu + mu_t))
            .sum()
    }

    /// The intensity the half-space sends up to the boundary from inside, in direction cosines
    /// `mus` (inside, 0..=1), per unit flux entering with refracted cosine `mu_t`: all orders
    /// of internal reflection, with or without the light scattered once on its first way up
    /// (`with_single`). The nodes' solve is interpolated by its own equation (Nyström).
    pub fn returned_intensity(&self, mu_t: f64, mus: &[f64], with_single: bool) -> Vec<f64> {
        let mu_t = mu_t.clamp(1e-6, 1.0);
        let h_t = chandrasekhar_h(self.omega, mu_t);
        let n = self.nodes.len();
        let c = self.omega / (4.0 * PI);
        let first: Vec<f64> = (0..n).map(|i| c * self.h[i] * h_t / (self.nodes[i].0 + mu_t)).collect();
        // The light internal reflection sends back down at the nodes, `F u`, times `μ w`.
        let down: Vec<f64> = (0..n)
            .map(|j| {
                let u_j: f64 = (0..n).map(|k| self.inverse[j * n + k] * first[k]).sum();
                let (mu_j, w_j) = self.nodes[j];
                self.h[j] * mu_j * w_j * self.fresnel[j] * u_j
            })
            .collect();
        mus.iter()
            .map(|&mu| {
                let mu = mu.clamp(1e-9, 1.0);
                let h = chandrasekhar_h(self.omega, mu);
                let once = if with_single { 0.0 } else { c / (mu + mu_t) };
                let reflected: f64 = self
                    .nodes
                    .iter()
                    .zip(&down)
                    .map(|(&(mu_j, _), d)| 0.5 * self.omega * h * d / (mu + mu_j))
                    .sum();
                c * h * h_t / (mu + mu_t) - once + reflected
            })
            .collect()
    }

    /// Total albedo (single plus multiple scattering, all orders of internal reflection) for
    /// light entering with refracted direction cosine `mu_t` (0..=1).
    pub fn albedo(&self, mu_t: f64) -> f64 {
        let mu_t = mu_t.clamp(1e-6, 1.0);
        let h_t = chandrasekhar_h(self.omega, mu_t);
        let n = self.nodes.len();
        // First return per unit incident flux, then all orders of internal reflection.
        let first: Vec<f64> =
            (0..n).map(|i| self.omega / (4.0 * PI) * self.h[i] * h_t / (self.nodes[i].0 + mu_t)).collect();
        (0..n)
            .map(|i| {
                let u_i: f64 = (0..n).map(|j| self.inverse[i * n + j] * first[j]).sum();
                let (mu, w) = self.nodes[i];
                2.0 * PI * w * mu * (1.0 - self.fresnel[i]) * u_i
            })
            .sum()
    }
}

/// Inverse of the dense `n × n` matrix `a` (row-major) by Gauss-Jordan with partial pivoting.
/// `I - K F` is diagonally dominant (the half-space returns less than it receives), so this is
/// well conditioned.
fn invert(mut a: Vec<f64>, n: usize) -> Vec<f64> {
    let mut inv: Vec<f64> = (0..n * n).map(|k| f64::from(u8::from(k / n == k % n))).collect();
    for col in 0..n {
        let pivot =
            (col..n).max_by(|&p, &q| a[p * n + col].abs().total_cmp(&a[q * n + col].abs())).unwrap_or(col);
        for k in 0..n {
            a.swap(col * n + k, pivot * n + k);
            inv.swap(col * n + k, pivot * n + k);
        }
        let d = a[col * n + col];
        for k in 0..n {
            a[col * n + k] /= d;
            inv[col * n + k] /= d;
        }
        for row in 0..n {
            let f = a[row * n + col];
            if row != col && f != 0.0 {
                for k in 0..n {
                    a[row * n + k] -= f * a[col * n + k];
                    inv[row * n + k] -= f * inv[col * n + k];
                }
            }
        }
    }
    inv
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn h_function_matches_tabulated_values() {
        // Chandrasekhar (1950) table XI: H(1) = 2.90781 at ω = 1; H(0.5) = 2.01278.
        assert!((chandrasekhar_h(1.0, 1.0) - 2.90781).abs() < 2e-5);
        assert!((chandrasekhar_h(1.0, 0.5) - 2.01278).abs() < 2e-5);
    }

    #[test]
    fn zeroth_moment_of_h_is_closed_form() {
        // ∫_0^1 H dμ = (2/ω)(1 - √(1-ω)) (Chandrasekhar eq. 39.9, isotropic).
        for omega in [0.3, 0.9, 0.99, 0.9999] {
            let q = gauss_legendre(64, 0.0, 1.0);
            let got: f64 = q.iter().map(|&(mu, w)| w * chandrasekhar_h(omega, mu)).sum();
            let want = 2.0 / omega * (1.0 - (1.0 - omega).sqrt());
            assert!((got - want).abs() < 1e-6 * want, "omega {omega}: {got} vs {want}");
        }
    }

    #[test]
    fn index_matched_albedo_is_chandrasekhars() {
        for omega in [0.2, 0.8, 0.99, 0.999] {
            let hs = HalfSpace::new(omega, 1.0);
            for mu in [0.1, 0.5, 1.0] {
                let want = 1.0 - chandrasekhar_h(omega, mu) * (1.0 - omega).sqrt();
                let got = hs.albedo(mu);
                assert!((got - want).abs() < 1e-5, "omega {omega} mu {mu}: {got} vs {want}");
            }
        }
    }

    #[test]
    fn conservative_medium_returns_everything_at_any_eta() {
        for eta in [1.0, 1.3, 1.5, 2.5] {
            let hs = HalfSpace::new(1.0, eta);
            for mu in [0.2, 0.7, 1.0] {
                let a = hs.albedo(mu);
                assert!((a - 1.0).abs() < 1e-4, "eta {eta} mu {mu}: {a}");
            }
        }
    }
}
