//! Gauss-Legendre quadrature on geometric panels, for the radial integrals of photon beam
//! diffusion ([`super::beam_diffusion`]) and the half-space's angular integrals
//! ([`super::halfspace`]).

/// 8-point Gauss-Legendre nodes on `[-1, 1]` (positive half) and weights.
const GL8_X: [f64; 4] =
    [0.183_434_642_495_649_8, 0.525_532_409_916_329, 0.796_666_477_413_626_7, 0.960_289_856_497_536_3];
const GL8_W: [f64; 4] =
    [0.362_683_783_378_362, 0.313_706_645_877_887_3, 0.222_381_034_453_374_5, 0.101_228_536_290_376_3];

/// `∫_a^b f` on geometric panels from `a > 0` (each `ratio` times the last) up to `b`, 8-point
/// Gauss-Legendre per panel, plus one panel on `[0, a]` when `from_zero`.
pub(crate) fn integrate_geometric(
    a: f64,
    b: f64,
    ratio: f64,
    from_zero: bool,
    f: impl Fn(f64) -> f64,
) -> f64 {
    let panel = |lo: f64, hi: f64| {
        let (m, h) = (0.5 * (lo + hi), 0.5 * (hi - lo));
        (0..4).map(|k| GL8_W[k] * (f(m - h * GL8_X[k]) + f(m + h * GL8_X[k]))).sum::<f64>() * h
    };
    let mut sum = if from_zero { panel(0.0, a) } else { 0.0 };
    let mut lo = a;
    while lo < b {
        let hi = (lo * ratio).min(b);
        sum += panel(lo, hi);
        lo = hi;
    }
    sum
}
