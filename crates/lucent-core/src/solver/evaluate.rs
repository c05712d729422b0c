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

    /// The corners of face `e` when `R_d` from `src` is smooth over it (`k ρ` within
    /// [`FormFactorOptions::cubature_max_k_rho`]), so that the `f32` cubature stands in for
    /// the form factor, which would take the same short cut in `f64`.
    #[inline]
    fn smooth_face(&self, src: &ReceiverSources, e: usize) -> Option<[Vec3; 3]> {
        let eg = &self.h.geom[e];
        let poly = self.h.polygon(e);
        (self.h.nodes[e].is_leaf()
            && !self.near_point_sampling
            && poly.len() == 3
            && src.k_rho(&self.d32, eg.midpoint, eg.radius) <= self.opts.cubature_max_k_rho as f32)
            .then(|| [poly[0], poly[1], poly[2]])
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
                if let Some(tri) = self.smooth_face(src, e) {
                    self.cubatures += 1;
                    return src.triangle_cubature(&self.d32, &tri, eg.area);
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
