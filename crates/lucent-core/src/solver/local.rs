//! The local limit of the solve: where the profile's reach (the radius holding all but a
//! [`TAIL`] of `∫ R dA`) is shorter than a face's own extent around its midpoint, and no
//! other part of the surface comes that close, the face gathers only from itself:
//! `B = R_d_total E` (Mertens eq. 6 with one term, the rest below `TAIL`). Optically dense or
//! large objects are then solved with one link per face instead of a refinement down to
//! every face's neighbours, and emitters out of reach of any receiver are dropped instead of
//! linked, so the cost falls with locality.

use crate::bssrdf::Profile;
use crate::hierarchy::Hierarchy;
use crate::mesh::Mesh;
use crate::mesh::bvh::query::closest_on_triangle;
use glam::Vec3;

/// Share of the profile's integral `∫ R dA` beyond its reach: what the local limit and a
/// dropped emitter may leave out, relative to `R_d_total`.
pub const TAIL: f64 = 1e-4;

/// The profile's reach and what a local face gathers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Locality {
    /// Radius (mesh units) about an exit point beyond which the planar profile holds less
    /// than [`TAIL`] of its integral, in every channel.
    pub reach: f32,
    /// `∫ R dA` over the plane per channel (unitless), numerically: a local face's self
    /// coefficient.
    pub r_total: [f32; 3],
}

impl Locality {
    /// The reach of `d`'s profile (see [`Locality::reach`]), from `∫ 2π r² R(r) d ln r` on a
    /// log grid spanning every length of the profile.
    pub fn of(d: &Profile) -> Self {
        let mut lo = f64::INFINITY;
        let mut hi = 0.0f64;
        for c in 0..3 {
            let (zr, st) = (d.z_r[c], d.sigma_tr[c]);
            lo = lo.min(zr).min(1.0 / st);
            hi = hi.max(d.z_v[c]).max(1.0 / st);
            if let Some(t) = &d.tables {
                hi = hi.max(t.channels[c].r_max);
            }
        }
        let (lo, hi) = ((1e-4 * lo).max(f64::MIN_POSITIVE), 100.0 * hi);
        const N: usize = 4000;
        let step = (hi / lo).ln() / N as f64;
        let r_at = |i: usize| lo * (step * i as f64).exp();
        let w: Vec<[f64; 3]> = (0..=N)
            .map(|i| {
                let r = r_at(i);
                d.rd_planar(r).map(|v| 2.0 * std::f64::consts::PI * r * r * v * step)
            })
            .collect();
        let mut r_total = [0.0f32; 3];
        let mut reach = 0.0f64;
        for c in 0..3 {
            let total: f64 = w.iter().map(|v| v[c]).sum();
            r_total[c] = total as f32;
            let mut tail = 0.0;
            let mut i = N;
            while i > 0 && tail + w[i][c] <= TAIL * total {
                tail += w[i][c];
                i -= 1;
            }
            reach = reach.max(r_at(i));
        }
        Locality { reach: reach as f32, r_total }
    }

    /// Per cluster of `h`, whether every face below it is local: its midpoint is farther than
    /// the reach from its own edges and from every other face of `mesh`.
    pub fn local_clusters(&self, h: &Hierarchy, mesh: &Mesh) -> Vec<bool> {
        let mut local = vec![false; h.len()];
        for i in (0..h.len()).rev() {
            let n = &h.nodes[i];
            local[i] = if n.is_leaf() {
                let t = mesh.triangles[h.leaf_faces[n.leaf_start as usize] as usize];
                let p = t.map(|v| mesh.positions[v as usize]);
                self.inside_face(&p) && self.alone(h, mesh, i)
            } else {
                n.children().iter().all(|&c| local[c as usize])
            };
        }
        local
    }

    /// Whether the centroid of triangle `p` is farther than the reach from its edges.
    fn inside_face(&self, p: &[Vec3; 3]) -> bool {
        let twice_area = (p[1] - p[0]).cross(p[2] - p[0]).length();
        // The centroid's distance to edge `k` is a third of the height over it.
        (0..3).all(|k| twice_area / 3.0 > self.reach * (p[(k + 1) % 3] - p[k]).length())
    }

    /// Whether no face but leaf `r` comes within the reach of `r`'s midpoint.
    fn alone(&self, h: &Hierarchy, mesh: &Mesh, r: usize) -> bool {
        let x = h.geom[r].midpoint;
        let mut stack = vec![0usize];
        while let Some(e) = stack.pop() {
            if e == r || !self.may_reach(x, h, e) {
                continue;
            }
            let n = &h.nodes[e];
            if n.is_leaf() {
                let t = mesh.triangles[h.leaf_faces[n.leaf_start as usize] as usize];
                let p = t.map(|v| mesh.positions[v as usize]);
                if closest_on_triangle(x, &p).distance(x) <= self.reach {
                    return false;
                }
            } else {
                stack.extend(n.children().iter().map(|&c| c as usize));
            }
        }
        true
    }

    /// Whether cluster `e`'s bounding sphere comes within the reach of `x`.
    #[inline]
    pub fn may_reach(&self, x: Vec3, h: &Hierarchy, e: usize) -> bool {
        let g = &h.geom[e];
        let r = self.reach + g.radius;
        (x - g.midpoint).length_squared() <= r * r
    }

    /// Whether clusters `r` and `e` (bounding spheres) are farther apart than the reach.
    #[inline]
    pub fn apart(&self, h: &Hierarchy, r: usize, e: usize) -> bool {
        let (a, b) = (&h.geom[r], &h.geom[e]);
        let s = self.reach + a.radius + b.radius;
        (a.midpoint - b.midpoint).length_squared() > s * s
    }
}
