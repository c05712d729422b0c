//! The transport coefficient of an accepted link (Mertens et al. 2003, §3.1, §4): a one-point
//! estimate `A_E R_d` for a far emitter, and for a near one the semi-analytic form factor over
//! its (projected, §5.1.1) polygon, the `f32` seven-point cubature where `R_d` is smooth over a
//! face, or uniform point sampling for the comparison of Mertens table 5.

use super::oracle::LinkKind;
use super::point_sample::{DipoleF32, ReceiverSources};
use crate::bssrdf::Dipole;
use crate::formfactor::montecarlo::sample_estimate;
use crate::formfactor::{FormFactorOptions, form_factor};
use crate::hierarchy::Hierarchy;
use glam::{DVec3, Vec3};

/// How a face whose `R_d` is smooth is integrated ([`Evaluator::smooth_face`]).
enum Smooth {
    /// Radon's seven points on the face.
    Whole([Vec3; 3]),
    /// Radon's seven points on each quarter.
    Quarters([[Vec3; 3]; 4]),
}

/// `k ρ` of triangle `t` about its vertex average ([`ReceiverSources::k_rho`]).
fn triangle_k_rho(src: &ReceiverSources, d: &DipoleF32, t: &[Vec3; 3]) -> f32 {
    let c = (t[0] + t[1] + t[2]) / 3.0;
    src.k_rho(d, c, t.iter().map(|p| p.distance(c)).fold(0.0, f32::max))
}

/// The four triangles of the midpoint subdivision of `t` (equal areas).
fn quarters(t: [Vec3; 3]) -> [[Vec3; 3]; 4] {
    let [a, b, c] = t;
    let (ab, bc, ca) = ((a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5);
    [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
}

/// Evaluates links: holds the dipole in both precisions and a scratch polygon buffer.
pub(crate) struct Evaluator<'a> {
    pub h: &'a Hierarchy,
    pub dipole: &'a Dipole,
    pub d32: DipoleF32,
    pub opts: FormFactorOptions,
    /// Near links by uniform point sampling instead of the form factor (Mertens table 5).
    pub near_point_sampling: bool,
    /// Semi-analytic form factor evaluations so far.
    pub form_factors: usize,
    /// Form factor links evaluated by the `f32` cubature instead, so far.
    pub cubatures: usize,
    scratch: Vec<DVec3>,
}

impl<'a> Evaluator<'a> {
    pub fn new(h: &'a Hierarchy, dipole: &'a Dipole, opts: FormFactorOptions) -> Self {
        Evaluator {
            h,
            dipole,
            d32: DipoleF32::new(dipole),
            opts,
            near_point_sampling: false,
            form_factors: 0,
            cubatures: 0,
            scratch: Vec::with_capacity(16),
        }
    }

    /// How face `e` is integrated where `R_d` from `src` is smooth over it, so that the `f32`
    /// cubature stands in for the form factor: whole when its `k ρ` is within
    /// [`FormFactorOptions::cubature_max_k_rho`] (the form factor would take the same short
    /// cut in `f64`), or as its four midpoint-subdivision quarters when each of theirs is (a
    /// quarter has half the radius, so faces up to about twice the limit; none are tried past
    /// four times it): 28 points, four to six times cheaper than the edge integrals, which on
    /// dense scanned meshes were a third of the solve.
    #[inline]
    fn smooth_face(&self, src: &ReceiverSources, e: usize) -> Option<Smooth> {
        let eg = &self.h.geom[e];
        let poly = self.h.polygon(e);
        let max = self.opts.cubature_max_k_rho as f32;
        if !self.h.nodes[e].is_leaf() || self.near_point_sampling || poly.len() != 3 || max <= 0.0 {
            return None;
        }
        let tri = [poly[0], poly[1], poly[2]];
        let k_rho = src.k_rho(&self.d32, eg.midpoint, eg.radius);
        if k_rho <= max {
            return Some(Smooth::Whole(tri));
        }
        if k_rho > 4.0 * max {
            return None;
        }
        let quarters = quarters(tri);
        quarters
            .iter()
            .all(|q| triangle_k_rho(src, &self.d32, q) <= max)
            .then_some(Smooth::Quarters(quarters))
    }

    /// Whether a form factor link `e -> r` costs a full semi-analytic evaluation (the
    /// incremental budget counts only those).
    #[inline]
    pub fn is_analytic(&self, src: &ReceiverSources, e: usize) -> bool {
        self.smooth_face(src, e).is_none()
    }

    /// The transport coefficient of the link `e -> r` (per channel, unitless).
    #[inline]
    pub fn eval(&mut self, src: &ReceiverSources, r: usize, e: usize, kind: LinkKind) -> [f32; 3] {
        let eg = &self.h.geom[e];
        match kind {
            LinkKind::PointSample => src.point_sample(&self.d32, eg.midpoint, eg.area),
            LinkKind::FormFactor => {
                let rg = &self.h.geom[r];
                match self.smooth_face(src, e) {
                    Some(Smooth::Whole(tri)) => {
                        self.cubatures += 1;
                        return src.triangle_cubature(&self.d32, &tri, eg.area);
                    }
                    Some(Smooth::Quarters(q)) => {
                        self.cubatures += 1;
                        let mut f = [0.0f32; 3];
                        for t in &q {
                            let g = src.triangle_cubature(&self.d32, t, 0.25 * eg.area);
                            f.iter_mut().zip(g).for_each(|(f, g)| *f += g);
                        }
                        return f;
                    }
                    None => {}
                }
                self.form_factors += 1;
                self.scratch.clear();
                self.scratch.extend(self.h.polygon(e).iter().map(|p| p.as_dvec3()));
                if self.near_point_sampling {
                    // Jensen & Buhler 2002 space their samples about one mean free path
                    // `1/sigma_t'` apart: that many uniform samples over the polygon.
                    let mfp = self.dipole.z_r.iter().copied().fold(f64::MAX, f64::min);
                    let n = ((eg.area as f64 / (mfp * mfp)).ceil() as usize).clamp(1, 1 << 16);
                    let f = sample_estimate(
                        &self.scratch,
                        rg.midpoint.as_dvec3(),
                        rg.normal.as_dvec3(),
                        self.dipole,
                        n,
                        (r as u64) << 32 | e as u64,
                    );
                    return f.map(|v| v as f32);
                }
                let f = form_factor(
                    &self.scratch,
                    rg.midpoint.as_dvec3(),
                    rg.normal.as_dvec3(),
                    self.dipole,
                    &self.opts,
                );
                // The projected polygon stands for the cluster's true area (§5.1.1); scale so
                // that the far field matches the point sample `A R_d`. Leaves: scale 1.
                let scale = if self.h.nodes[e].is_leaf() || eg.polygon_area <= 0.0 {
                    1.0
                } else {
                    eg.area as f64 / eg.polygon_area as f64
                };
                f.map(|v| (v * scale) as f32)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bssrdf::{Material, ProfileKind};

    /// Where a face is too close for the whole-face rule but each quarter is smooth, the
    /// 28-point quarters agree with the semi-analytic edge integrals (the cubature short cut
    /// off) within 0.2%, for the default profile (measured: within 7e-5 on 13 placements).
    #[test]
    fn quarter_cubature_matches_the_edge_integrals() {
        let m = Material::by_name("marble").unwrap();
        let dip = Dipole::profile_for_model_scale(&m, 1.0, 0.01, ProfileKind::Pbd, true);
        let d = DipoleF32::new(&dip);
        let max = FormFactorOptions::default().cubature_max_k_rho as f32;
        let edges = FormFactorOptions { cubature_max_k_rho: 0.0, ..FormFactorOptions::default() };
        let (x_o, n_o) = (Vec3::ZERO, Vec3::Z);
        let src = ReceiverSources::new(&d, x_o, n_o);
        let mut tested = 0;
        for step in 0..60 {
            let dist = 0.01 + 0.001 * step as f32;
            let tri = [
                Vec3::new(dist, 0.0, 0.0),
                Vec3::new(dist + 0.03, 0.01, 0.0),
                Vec3::new(dist + 0.01, 0.03, 0.002),
            ];
            let smooth_quarters = quarters(tri).iter().all(|q| triangle_k_rho(&src, &d, q) <= max);
            if triangle_k_rho(&src, &d, &tri) <= max || !smooth_quarters {
                continue;
            }
            let t64 = tri.map(|p| p.as_dvec3());
            let area = 0.5 * (t64[1] - t64[0]).cross(t64[2] - t64[0]).length();
            let want = form_factor(&t64, x_o.as_dvec3(), n_o.as_dvec3(), &dip, &edges);
            let mut got = [0.0f64; 3];
            for q in quarters(tri) {
                let g = src.triangle_cubature(&d, &q, 0.25 * area as f32);
                got.iter_mut().zip(g).for_each(|(s, g)| *s += g as f64);
            }
            for c in 0..3 {
                assert!(
                    (got[c] / want[c] - 1.0).abs() < 2e-3,
                    "at {dist}, channel {c}: {} vs {}",
                    got[c],
                    want[c]
                );
            }
            tested += 1;
        }
        assert!(tested >= 5, "only {tested} placements needed quarters");
    }
}
