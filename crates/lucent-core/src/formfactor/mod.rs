//! The semi-analytic point-to-polygon form factor of Mertens et al. 2003, §4:
//! `F(A, x_o) = ∫_A R_d(x_i, x_o) dx_i`, with the dipole placed at the receiver `x_o`
//! (the "inverse interpretation" of §4) and the area integral reduced to the polygon's edges.
//!
//! (Stub: a one-point estimate until the semi-analytic integration lands.)

use crate::bssrdf::Dipole;
use glam::DVec3;

pub mod montecarlo;

/// Options of the semi-analytic integration.
#[derive(Clone, Copy, Debug)]
pub struct FormFactorOptions {
    /// Largest allowed `L / r_0` of an edge segment before it is split (Mertens eq. 19 uses 2/5).
    pub max_segment_ratio: f64,
}

impl Default for FormFactorOptions {
    fn default() -> Self {
        FormFactorOptions { max_segment_ratio: 0.8 }
    }
}

/// `F(A, x_o)` per channel for the planar polygon `polygon` (vertices in order, any winding),
/// seen from the receiver `x_o` with unit normal `n_o`. Mesh units; the result is unitless.
pub fn form_factor(
    polygon: &[DVec3],
    x_o: DVec3,
    n_o: DVec3,
    dipole: &Dipole,
    _opts: &FormFactorOptions,
) -> [f64; 3] {
    point_sample(polygon, x_o, n_o, dipole)
}

/// One-sample estimate: `R_d` from the polygon's centroid times its area.
pub fn point_sample(polygon: &[DVec3], x_o: DVec3, n_o: DVec3, dipole: &Dipole) -> [f64; 3] {
    let (centroid, area) = polygon_centroid_area(polygon);
    let rd = dipole.rd(x_o, n_o, centroid);
    rd.map(|v| v * area)
}

/// Area centroid and area of a planar polygon.
pub fn polygon_centroid_area(polygon: &[DVec3]) -> (DVec3, f64) {
    let mut area_vec = DVec3::ZERO;
    let mut weighted = DVec3::ZERO;
    let mut total = 0.0;
    for i in 1..polygon.len().saturating_sub(1) {
        let c = (polygon[i] - polygon[0]).cross(polygon[i + 1] - polygon[0]);
        area_vec += c;
        let a = c.length() * 0.5;
        weighted += a * (polygon[0] + polygon[i] + polygon[i + 1]) / 3.0;
        total += a;
    }
    let _ = area_vec;
    if total > 0.0 { (weighted / total, total) } else { (polygon.first().copied().unwrap_or_default(), 0.0) }
}
