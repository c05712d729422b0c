//! The transport coefficient of an accepted link (Mertens et al. 2003, §3.1, §4): a one-point
//! estimate `A_E R_d` for a far emitter, and for a near one the semi-analytic form factor over
//! its (projected, §5.1.1) polygon, the `f32` seven-point cubature where `R_d` is smooth over a
//! face or over each of the pieces it is cut into, the polar rule of [`super::near_face`] for
//! the receiver's own face and those beside it, or uniform point sampling for the comparison
//! of Mertens table 5.

use super::near_face::Nodes;
use super::oracle::LinkKind;
use super::point_sample::{PointBuf, ProfileF32, ReceiverSources, SmoothBound};
use crate::bssrdf::Profile;
use crate::formfactor::montecarlo::sample_estimate;
use crate::formfactor::{FormFactorOptions, form_factor};
use crate::hierarchy::Hierarchy;
use glam::{DVec3, Vec3};

/// Most pieces [`Evaluator::smooth_face`] cuts a face into for the cubature: 280 points,
/// still cheaper than the edge integrals of a face that needs them (871K dragon: 1.2M such
/// links took the edge integrals at 16 pieces, 0.17M at 40).
pub(super) const MAX_PIECES: usize = 40;
/// Deepest midpoint subdivision [`Evaluator::smooth_face`] tries (pieces of a quarter of
/// the face's area, a sixteenth, ..., a 1024th).
const MAX_DEPTH: u8 = 5;

/// The four triangles of the midpoint subdivision of `t` (equal areas).
fn quarters(t: [Vec3; 3]) -> [[Vec3; 3]; 4] {
    let [a, b, c] = t;
    let (ab, bc, ca) = ((a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5);
    [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
}

/// Cuts triangle `t` (area `area`) into its midpoint quarters, which lie at subdivision
/// `level` (the whole face's quarters: 1), and adds Radon's points on each quarter that
/// `smooth(centroid, level)` passes to `buf`, cutting the others again, depth first.
/// `pieces` counts the pieces so far (`t` among them); false once a piece below
/// [`MAX_DEPTH`] levels or more than [`MAX_PIECES`] pieces would be needed (`buf` then holds
/// a part of the points).
fn cut_smooth(
    t: [Vec3; 3],
    area: f32,
    level: u8,
    pieces: &mut usize,
    buf: &mut PointBuf,
    smooth: &mut impl FnMut(Vec3, u8) -> bool,
) -> bool {
    if level > MAX_DEPTH || *pieces + 3 > MAX_PIECES {
        return false;
    }
    *pieces += 3;
    let area = 0.25 * area;
    quarters(t).into_iter().all(|q| {
        if smooth((q[0] + q[1] + q[2]) / 3.0, level) {
            buf.push_radon7(q, area);
            true
        } else {
            cut_smooth(q, area, level + 1, pieces, buf, smooth)
        }
    })
}

/// Evaluates links: holds the dipole in both precisions and a scratch polygon buffer.
pub(crate) struct Evaluator<'a> {
    pub h: &'a Hierarchy,
    pub profile: &'a Profile,
    pub d32: ProfileF32,
    pub opts: FormFactorOptions,
    /// Near links by uniform point sampling instead of the form factor (Mertens table 5).
    pub near_point_sampling: bool,
    /// Semi-analytic form factor evaluations so far.
    pub form_factors: usize,
    /// Form factor links evaluated by the `f32` cubature instead, so far.
    pub cubatures: usize,
    /// Form factor links evaluated in polar coordinates about the receiver instead, so far.
    pub polar_faces: usize,
    scratch: Vec<DVec3>,
    /// Scratch points of the cubatures and rays of the polar rule.
    points: PointBuf,
    rays: Nodes,
}

impl<'a> Evaluator<'a> {
    pub fn new(h: &'a Hierarchy, profile: &'a Profile, opts: FormFactorOptions) -> Self {
        Evaluator {
            h,
            profile,
            d32: ProfileF32::new(profile),
            opts,
            near_point_sampling: false,
            form_factors: 0,
            cubatures: 0,
            polar_faces: 0,
            scratch: Vec::with_capacity(16),
            points: PointBuf::new(),
            rays: Nodes::new(),
        }
    }

    /// Face `e` cut into pieces over each of which `R_d` from `src` is smooth, with Radon's
    /// seven points on every piece added to the evaluator's scratch points for the `f32`
    /// cubature to stand in for the form factor: whole when its `k ρ` is within
    /// [`FormFactorOptions::cubature_max_k_rho`] (the form factor would take the same short
    /// cut in `f64`), else by midpoint subdivision of the pieces that are not, down to
    /// [`MAX_DEPTH`] levels and [`MAX_PIECES`] pieces (a piece has half its parent's radius;
    /// faces past 32 times the limit, which no piece could meet, are not tried). Only the
    /// pieces near the receiver are cut again, so a face beside it takes 7 to 13 pieces,
    /// 49 to 91 points, about half the cycles of its edge integrals (48K dragon: 1,400
    /// against 3,000), which on dense scanned meshes were a quarter of the solve. Each
    /// level's [`SmoothBound`] is made once, so a piece's test is one squared distance.
    /// Returns the number of pieces; `None` (and no points added): too close to be cut
    /// smooth (the receiver's own face, which holds the profile's peak), so the polar rule
    /// or the edge integrals.
    #[inline]
    fn smooth_face(&mut self, src: &ReceiverSources, e: usize) -> Option<usize> {
        let eg = &self.h.geom[e];
        let poly = self.h.polygon(e);
        let max = self.opts.cubature_max_k_rho as f32;
        if !self.h.nodes[e].is_leaf() || self.near_point_sampling || poly.len() != 3 || max <= 0.0 {
            return None;
        }
        let tri = [poly[0], poly[1], poly[2]];
        let (d, buf) = (&self.d32, &mut self.points);
        // Midpoint subdivision makes four copies of a triangle at half the size, so a piece's
        // radius about its vertex average is the face's (a leaf's `radius`) halved per level
        // (the whole face: level 0); each level's bound is made when a piece first reaches it.
        let mut bounds: [Option<SmoothBound>; MAX_DEPTH as usize + 1] = [None; MAX_DEPTH as usize + 1];
        let mut smooth = |q: Vec3, level: u8| {
            let bound = bounds[level as usize]
                .get_or_insert_with(|| SmoothBound::new(d, eg.radius * 0.5f32.powi(level as i32), max));
            src.smooth_within(d, q, bound)
        };
        if smooth(eg.midpoint, 0) {
            buf.push_radon7(tri, eg.area);
            return Some(1);
        }
        // A face holding the receiver's peak (its own face) or a source next to it cannot be
        // cut smooth: no piece would pass.
        if !src.smooth_within(d, eg.midpoint, &SmoothBound::new(d, eg.radius, 32.0 * max)) {
            return None;
        }
        let mut pieces = 1;
        let cut = cut_smooth(tri, eg.area, 1, &mut pieces, buf, &mut smooth);
        if !cut {
            buf.clear();
            return None;
        }
        Some(pieces)
    }

    /// Face `e`'s form factor at face `r`'s midpoint in polar coordinates about it
    /// ([`super::near_face`]), for a face that [`Evaluator::smooth_face`] could not cut smooth:
    /// `r`'s own face or one that shares a vertex with it, for a profile of tables alone.
    #[inline]
    fn polar_face(&mut self, r: usize, e: usize) -> Option<[f32; 3]> {
        let table = self.d32.cumulative.as_ref()?;
        let (pr, pe) = (self.h.polygon(r), self.h.polygon(e));
        let usable = self.h.nodes[r].is_leaf()
            && self.h.nodes[e].is_leaf()
            && self.h.geom[r].area > 0.0
            && !self.near_point_sampling
            && self.opts.cubature_max_k_rho > 0.0
            && pr.len() == 3
            && pe.len() == 3
            && pe.iter().any(|v| pr.contains(v));
        if !usable {
            return None;
        }
        let tri = [pe[0], pe[1], pe[2]];
        table.polar_face(self.h.geom[r].midpoint, &tri, self.d32.isa(), &mut self.rays).map(|(f, _)| f)
    }

    /// The transport coefficient of the link `e -> r` (per channel, unitless).
    #[inline]
    pub fn eval(&mut self, src: &ReceiverSources, r: usize, e: usize, kind: LinkKind) -> [f32; 3] {
        match kind {
            LinkKind::PointSample => {
                let eg = &self.h.geom[e];
                src.point_sample(&self.d32, eg.midpoint, eg.area)
            }
            LinkKind::FormFactor => {
                self.cheap_form_factor(src, r, e).unwrap_or_else(|| self.edge_form_factor(r, e))
            }
        }
    }

    /// A form factor link's coefficient where a rule of points gives it (the cubature over a
    /// face that is smooth, else the polar rule over a face beside the receiver), or `None`
    /// where it takes the semi-analytic edge integrals ([`Evaluator::edge_form_factor`]),
    /// the cost an incremental update's budget counts.
    #[inline]
    pub fn cheap_form_factor(&mut self, src: &ReceiverSources, r: usize, e: usize) -> Option<[f32; 3]> {
        if self.smooth_face(src, e).is_some() {
            self.cubatures += 1;
            return Some(src.weighted_sum(&self.d32, &mut self.points));
        }
        let f = self.polar_face(r, e)?;
        self.polar_faces += 1;
        Some(f)
    }

    /// A form factor link's coefficient by the semi-analytic edge integrals (or, with
    /// `near_point_sampling`, Jensen & Buhler's uniform samples).
    pub fn edge_form_factor(&mut self, r: usize, e: usize) -> [f32; 3] {
        let (eg, rg) = (&self.h.geom[e], &self.h.geom[r]);
        self.form_factors += 1;
        self.scratch.clear();
        self.scratch.extend(self.h.polygon(e).iter().map(|p| p.as_dvec3()));
        if self.near_point_sampling {
            // Jensen & Buhler 2002 space their samples about one mean free path
            // `1/sigma_t'` apart: that many uniform samples over the polygon.
            let mfp = self.profile.z_r.iter().copied().fold(f64::MAX, f64::min);
            let n = ((eg.area as f64 / (mfp * mfp)).ceil() as usize).clamp(1, 1 << 16);
            let f = sample_estimate(
                &self.scratch,
                rg.midpoint.as_dvec3(),
                rg.normal.as_dvec3(),
                self.profile,
                n,
                (r as u64) << 32 | e as u64,
            );
            return f.map(|v| v as f32);
        }
        let f = form_factor(
            &self.scratch,
            rg.midpoint.as_dvec3(),
            rg.normal.as_dvec3(),
            self.profile,
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bssrdf::{Material, ProfileKind};

    /// Where a face is too close to the receiver for the whole-face rule, the pieces
    /// [`Evaluator::smooth_face`] cuts it into agree with the semi-analytic edge integrals (the
    /// cubature short cut off) within 0.2%, for the default profile and the dipole, at every
    /// depth of cutting (measured: within 3.4e-4, in 1 to 28 pieces).
    #[test]
    fn cut_faces_match_the_edge_integrals() {
        let m = Material::by_name("marble").unwrap();
        let edges = FormFactorOptions { cubature_max_k_rho: 0.0, ..FormFactorOptions::default() };
        for profile in [ProfileKind::Pbd, ProfileKind::Dipole] {
            let dip = Profile::at_model_scale(&m, 1.0, 0.01, profile, true);
            // One face beside the receiver's, then moved away along x: from touching to clear.
            let mut mesh_tris = Vec::new();
            for step in 0..40 {
                let dist = 0.0005 + 0.0015 * step as f32;
                mesh_tris.push([
                    Vec3::new(dist, -0.01, 0.0),
                    Vec3::new(dist + 0.03, 0.01, 0.0),
                    Vec3::new(dist + 0.01, 0.03, 0.002),
                ]);
            }
            mesh_tris.push([
                Vec3::new(-0.004, -0.004, 0.0),
                Vec3::new(0.008, -0.004, 0.0),
                Vec3::new(-0.004, 0.008, 0.0),
            ]);
            let positions = mesh_tris.iter().flatten().copied().collect();
            let triangles = (0..mesh_tris.len() as u32).map(|f| [3 * f, 3 * f + 1, 3 * f + 2]).collect();
            let h = crate::hierarchy::face_cluster::build(&crate::mesh::Mesh::new(positions, triangles));
            let mut ev = Evaluator::new(&h, &dip, FormFactorOptions::default());
            let receiver = h.face_node[mesh_tris.len() - 1] as usize;
            let rg = &h.geom[receiver];
            let src = ReceiverSources::new(&ev.d32, rg.midpoint, rg.normal);
            let mut pieces_seen = [0usize; MAX_PIECES + 1];
            for f in 0..mesh_tris.len() - 1 {
                let e = h.face_node[f] as usize;
                let Some(n) = ev.smooth_face(&src, e) else { continue };
                pieces_seen[n] += 1;
                let got = src.weighted_sum(&ev.d32, &mut ev.points);
                let poly: Vec<DVec3> = h.polygon(e).iter().map(|p| p.as_dvec3()).collect();
                let want = form_factor(&poly, rg.midpoint.as_dvec3(), rg.normal.as_dvec3(), &dip, &edges);
                for c in 0..3 {
                    assert!(
                        (got[c] as f64 / want[c] - 1.0).abs() < 2e-3,
                        "{profile:?} face {f} in {} pieces, channel {c}: {} vs {}",
                        n,
                        got[c],
                        want[c]
                    );
                }
            }
            // Whole faces, quarters, and faces cut twice or more (more than four pieces).
            assert!(pieces_seen[1] > 0 && pieces_seen[4] > 0, "{profile:?}: {pieces_seen:?}");
            assert!(pieces_seen[5..].iter().sum::<usize>() >= 3, "{profile:?}: {pieces_seen:?}");
            // And faces that once took the edge integrals: more than sixteen pieces.
            assert!(pieces_seen[17..].iter().sum::<usize>() >= 2, "{profile:?}: {pieces_seen:?}");
            // The receiver's own face holds its peak: it cannot be cut smooth, and the polar
            // rule takes it where the profile is tabulated alone, else the edge integrals.
            assert!(ev.smooth_face(&src, receiver).is_none());
            let own = ev.eval(&src, receiver, receiver, LinkKind::FormFactor);
            let poly: Vec<DVec3> = h.polygon(receiver).iter().map(|p| p.as_dvec3()).collect();
            let want = form_factor(&poly, rg.midpoint.as_dvec3(), rg.normal.as_dvec3(), &dip, &edges);
            let polar = profile == ProfileKind::Pbd;
            assert_eq!((ev.polar_faces, ev.form_factors), (polar as usize, !polar as usize), "{profile:?}");
            for c in 0..3 {
                assert!(
                    (own[c] as f64 / want[c] - 1.0).abs() < 1e-3,
                    "{profile:?} own face, channel {c}: {own:?} vs {want:?}"
                );
            }
        }
    }

    /// A receiver's own face holds single scattering's `1/r` peak, which no polynomial rule
    /// integrates: however small the face against `z_r` (here radii from about `z_r / 5` down
    /// to `z_r / 500`, three shapes down to a sliver), it is never cut smooth, and the polar
    /// rule agrees with the edge integrals within 3e-3 down to `z_r / 50` (measured: 2.5e-3
    /// on the sliver). The smoothness test once added `(z_r / 10)²` to the distance, and own
    /// faces of radius `z_r / 10` and under took the cubature, 13-85% short.
    #[test]
    fn own_faces_are_never_cut() {
        let m = Material::by_name("marble").unwrap();
        let edges = FormFactorOptions { cubature_max_k_rho: 0.0, ..FormFactorOptions::default() };
        let dip = Profile::at_model_scale(&m, 1.0, 0.01, ProfileKind::Pbd, true);
        let shapes = [
            [Vec3::new(-0.004, -0.004, 0.0), Vec3::new(0.008, -0.004, 0.0), Vec3::new(-0.004, 0.008, 0.0)],
            [Vec3::new(-0.006, -0.001, 0.0), Vec3::new(0.009, -0.001, 0.0), Vec3::new(-0.003, 0.002, 0.0)],
            [Vec3::new(-0.01, -0.0005, 0.0), Vec3::new(0.01, -0.0005, 0.0), Vec3::new(0.0, 0.001, 0.0)],
        ];
        for scale in [1.0f32, 0.5, 0.3, 0.2, 0.1, 0.05, 0.02, 0.01] {
            for (k, shape) in shapes.iter().enumerate() {
                let mesh = crate::mesh::Mesh::new(shape.map(|v| v * scale).to_vec(), vec![[0, 1, 2]]);
                let h = crate::hierarchy::face_cluster::build(&mesh);
                let mut ev = Evaluator::new(&h, &dip, FormFactorOptions::default());
                let r = h.face_node[0] as usize;
                let rg = &h.geom[r];
                let src = ReceiverSources::new(&ev.d32, rg.midpoint, rg.normal);
                assert!(ev.smooth_face(&src, r).is_none(), "scale {scale}, shape {k}: cut smooth");
                if scale < 0.1 {
                    continue;
                }
                let polar = ev.eval(&src, r, r, LinkKind::FormFactor);
                let poly: Vec<DVec3> = h.polygon(r).iter().map(|p| p.as_dvec3()).collect();
                let want = form_factor(&poly, rg.midpoint.as_dvec3(), rg.normal.as_dvec3(), &dip, &edges);
                for c in 0..3 {
                    let err = (polar[c] as f64 / want[c] - 1.0).abs();
                    assert!(err < 3e-3, "scale {scale}, shape {k}, channel {c}: {polar:?} vs {want:?}");
                }
            }
        }
    }
}
