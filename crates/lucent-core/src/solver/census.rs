//! Where the links of a solve come from: a serial rerun of the refinement that counts the
//! oracle's decisions by their cause and the accepted links by kind, level and geometry (the
//! measurement behind "why do scanned meshes need so many links":
//! `LUCENT_BENCH_CENSUS=1 lucent bench solver --real`). Diagnostic only: no solve reads it.

use super::hierarchical::HierarchicalSolver;
use super::oracle::{Decision, LinkKind, ReceiverView, Samples};
use super::point_sample::ProfileF32;
use std::collections::BTreeMap;

/// Why one of the oracle's two tests decided as it did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Cause {
    /// The test did not run.
    #[default]
    None,
    /// Passed: the receiver stays whole, or the emitter is far.
    Pass,
    /// The receiver has no normal, or lies (or a child lies) inside the emitter's bounding
    /// sphere.
    Degenerate,
    /// The two bounding spheres overlap.
    NotSeparated,
    /// The emitter is seen under more than `MAX_FAR_SOLID_ANGLE`.
    WideAngle,
    /// A dipole pole lies within the margin of the emitter.
    Poles,
    /// The distance-form receiver test: the profile varies too much over the receiver's radius.
    Size,
    /// The one-point estimates disagree beyond `eps1` (receiver) or `eps2` (emitter).
    Variation,
}

/// A candidate emitter with its one-point estimate at the receiver, if known.
type Candidate = (u32, Option<[f32; 3]>);

/// Counts of a census (see the module documentation).
#[derive(Clone, Debug, Default)]
pub struct Census {
    /// Decisions by (decision, receiver test cause, emitter test cause).
    pub decisions: BTreeMap<String, u64>,
    /// Links by (kind, receiver is a face, emitter is a face).
    pub links: BTreeMap<String, u64>,
    /// Links by the emitter test's cause (why a form factor link was near).
    pub near_causes: BTreeMap<String, u64>,
    /// Links by `floor(log2(d / (r_R + r_E)))`, `d` the midpoints' distance.
    pub separation: BTreeMap<i32, u64>,
    /// Links by `floor(log2(r_E sigma_tr))` (smallest `sigma_tr`): emitter size against the
    /// profile's length.
    pub emitter_size: BTreeMap<i32, u64>,
    /// Links by receiver level.
    pub receiver_level: BTreeMap<u16, u64>,
    /// Links whose receiver is a face, per face: percentiles 50, 90, 99, 100.
    pub per_face: [u64; 4],
    /// Mean links at faces with a sliver ratio (longest edge² over area, 2.3 for an
    /// equilateral triangle) above 20, and at the others; and how many faces are slivers.
    pub sliver_mean: f64,
    pub other_mean: f64,
    pub slivers: usize,
    /// Total links.
    pub total: u64,
}

impl HierarchicalSolver {
    /// Reruns the refinement serially and counts its decisions and links (see
    /// [`Census`]). Slow (one core) and diagnostic only.
    pub fn census(&self) -> Census {
        let h = &self.hierarchy;
        let d = ProfileF32::new(&self.profile);
        let r = self.profile.total_diffuse_reflectance();
        let inv_rtot = [(1.0 / r[0].max(r[1]).max(r[2]).max(1e-12)) as f32; 3];
        let sigma_min = d.sigma_tr[0].min(d.sigma_tr[1]).min(d.sigma_tr[2]);
        let mut c = Census::default();
        let mut at_face = vec![0u64; h.len()];
        // (receiver, its candidates with known estimates)
        let mut todo: Vec<(usize, Vec<Candidate>)> = vec![(0, vec![(0, None)])];
        let mut stack = Vec::new();
        while let Some((r, cands)) = todo.pop() {
            let view = ReceiverView::new(h, &d, inv_rtot, r);
            let n = h.nodes[r];
            let mut defer: Vec<Vec<Candidate>> = vec![Vec::new(); n.child_count as usize];
            stack.clear();
            stack.extend(cands);
            let mut s = Samples::default();
            while let Some((e, f)) = stack.pop() {
                let e = e as usize;
                s.f_mid = f;
                let dec = self.oracle.decide(h, &d, &view, r, e, &mut s);
                *c.decisions
                    .entry(format!("{:?} recv={:?} far={:?}", short(dec), s.why[0], s.why[1]))
                    .or_default() += 1;
                match dec {
                    Decision::Link(kind) => {
                        let (rg, eg) = (&h.geom[r], &h.geom[e]);
                        let (rl, el) = (n.is_leaf(), h.nodes[e].is_leaf());
                        *c.links.entry(format!("{kind:?} recv_face={rl} emit_face={el}")).or_default() += 1;
                        if kind == LinkKind::FormFactor {
                            *c.near_causes.entry(format!("{:?}", s.why[1])).or_default() += 1;
                        }
                        let sep = rg.midpoint.distance(eg.midpoint) / (rg.radius + eg.radius).max(1e-30);
                        *c.separation.entry(log2_bucket(sep)).or_default() += 1;
                        *c.emitter_size.entry(log2_bucket(eg.radius * sigma_min)).or_default() += 1;
                        *c.receiver_level.entry(n.level).or_default() += 1;
                        at_face[r] += rl as u64;
                        c.total += 1;
                    }
                    Decision::SplitReceiver => {
                        for (k, dk) in defer.iter_mut().enumerate() {
                            dk.push((e as u32, s.at_children.map(|f| f[k])));
                        }
                    }
                    Decision::SplitEmitter => {
                        let kids = h.nodes[e].children();
                        for (j, &k) in kids.iter().enumerate() {
                            stack.push((k, s.children.map(|f| f[j])));
                        }
                    }
                }
            }
            for (k, dk) in defer.into_iter().enumerate() {
                todo.push((n.children[k] as usize, dk));
            }
        }
        self.face_percentiles(&mut c, &at_face);
        c
    }

    fn face_percentiles(&self, c: &mut Census, at_face: &[u64]) {
        let h = &self.hierarchy;
        let mut counts = Vec::new();
        let (mut s_sum, mut o_sum, mut o_n) = (0u64, 0u64, 0usize);
        for (i, n) in h.nodes.iter().enumerate() {
            if !n.is_leaf() {
                continue;
            }
            let t = self.mesh.triangles[h.leaf_faces[n.leaf_start as usize] as usize];
            let p = t.map(|v| self.mesh.positions[v as usize]);
            let longest = (p[0] - p[1])
                .length_squared()
                .max((p[1] - p[2]).length_squared())
                .max((p[2] - p[0]).length_squared());
            let area = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length();
            if longest > 20.0 * area {
                c.slivers += 1;
                s_sum += at_face[i];
            } else {
                o_n += 1;
                o_sum += at_face[i];
            }
            counts.push(at_face[i]);
        }
        counts.sort_unstable();
        if let Some(&max) = counts.last() {
            let q = |f: f64| counts[((counts.len() - 1) as f64 * f) as usize];
            c.per_face = [q(0.5), q(0.9), q(0.99), max];
        }
        c.sliver_mean = s_sum as f64 / c.slivers.max(1) as f64;
        c.other_mean = o_sum as f64 / o_n.max(1) as f64;
    }
}

fn short(d: Decision) -> &'static str {
    match d {
        Decision::Link(LinkKind::PointSample) => "LinkPS",
        Decision::Link(LinkKind::FormFactor) => "LinkFF",
        Decision::SplitReceiver => "SplitR",
        Decision::SplitEmitter => "SplitE",
    }
}

fn log2_bucket(x: f32) -> i32 {
    if x > 0.0 { x.log2().floor() as i32 } else { i32::MIN }
}
