//! The lateral spread of light crossing the body (issue 50): the slab transmission term of a
//! face ([`super::transmission`]) takes the far side's irradiance averaged over where light
//! entering there reaches the face, not at the one point across.
//!
//! Light entering a slab of thickness `t` at a point leaves the far face spread over a radius
//! of about `t` on a thin part, `sqrt(t / σ_tr)` on a thick one ([`crate::bssrdf::slab_spread`]: Donner & Jensen
//! 2005's multipole transmittance profile, normalised to 1). By reciprocity a face on the near
//! side receives, per unit of the slab's total transmittance, the far side's irradiance
//! averaged with that profile around the point across from it. With a point light close behind
//! a thin part the far side's irradiance is a spike, and the one face across from it took all
//! of it (a bright spot, on the bunny up to 11 times the half-space's).
//!
//! Per face, once per pose (like the thickness rays): the profile's radial share is split, by
//! the radii that hold 1/16, 4/16 and 9/16 of the widest channel's light, into a centre disk
//! and three rings; the centre is the thickness ray's own far face, and each ring `i` is
//! sampled by `2i + 1` rays parallel to the inward normal, at the ring's median radius and
//! evenly spaced angles (turned per face, so neighbours sample different places). A ray counts
//! where the first face it hits faces away from the face (it started inside the body and left
//! through the far side) within the ring's reach; the others (past the part's edge, into
//! another part) are left out, and each channel's ring weights, the ring's share of its own
//! profile, are normalised over the rings sampled. So the weights sum to 1 per channel: under
//! a uniform far side the term is what it was at one point, and the light that leaves through
//! the part's sides is not modelled. Under a light move only the sparse weighted sum
//! ([`Spread::average`]) is evaluated again.

use crate::Rgb;
use crate::bssrdf::Profile;
use crate::bssrdf::slab_spread::SpreadTable;
use crate::mesh::Mesh;
use crate::mesh::bvh::Bvh;
use rayon::prelude::*;

/// Rays per face off the centre: rings of 3, 5 and 7.
pub const SAMPLES: usize = 15;
/// The centre and the three rings.
const RINGS: usize = 4;
/// The first sample of each ring past the centre, and one past the last.
const RING_START: [usize; RINGS] = [0, 3, 8, SAMPLES];

/// Per face, the far-side faces its transmission term averages and their weights.
#[derive(Clone, Debug)]
pub struct Spread {
    /// Per face, the face each ring sample's ray left the body through (`u32::MAX`: not
    /// counted).
    faces: Vec<[u32; SAMPLES]>,
    /// Per face, the weight (unitless, per channel) of the centre and of each counted sample
    /// of each ring; per channel the weights of the counted samples sum to 1.
    weights: Vec<[Rgb; RINGS]>,
}

/// A fraction in 0..1 from a face index (Knuth's multiplicative hash), to turn its rings.
fn turn(f: usize) -> f32 {
    ((f as u32).wrapping_mul(0x9E37_79B9) >> 8) as f32 / (1u32 << 24) as f32
}

impl Spread {
    /// The samples of every face of `mesh` whose term crosses the body to `far[f]` (`u32::MAX`:
    /// none) through `thickness[f]` (mesh units), traced against `bvh` from `offset` inside the
    /// faces, with `profile`'s extinction and albedos.
    pub fn trace(
        profile: &Profile,
        mesh: &Mesh,
        bvh: &Bvh,
        offset: f32,
        far: &[u32],
        thickness: &[f32],
    ) -> Self {
        let tables: [_; 3] = std::array::from_fn(|c| {
            // The extrapolation distance in mean free paths: z_v = z_r (1 + 4A/3) = z_r + 2 z_b.
            let zb = 0.5 * (profile.z_v[c] / profile.z_r[c] - 1.0);
            SpreadTable::cached(profile.alpha_prime[c], profile.eta, zb)
        });
        let rows: Vec<([u32; SAMPLES], [Rgb; RINGS])> = (0..far.len())
            .into_par_iter()
            .map(|f| {
                if far[f] == u32::MAX || thickness[f] <= 0.0 {
                    return ([u32::MAX; SAMPLES], [Rgb::ZERO; RINGS]);
                }
                let t = thickness[f] as f64;
                let tau: [f64; 3] = std::array::from_fn(|c| profile.sigma_t[c] * t);
                // Radii in mesh units; the rings are the widest channel's (largest median).
                let q: [[f64; 7]; 3] =
                    std::array::from_fn(|c| tables[c].quantiles(tau[c]).map(|r| r / profile.sigma_t[c]));
                let p = (0..3).max_by(|&a, &b| q[a][6].total_cmp(&q[b][6])).unwrap_or(0);
                let bounds = [q[p][0], q[p][2], q[p][4]];
                let radii = [q[p][1], q[p][3], q[p][5]];
                let faces = Self::trace_face(mesh, bvh, offset, f, t as f32, radii);
                let counted: [bool; RINGS] = std::array::from_fn(|i| {
                    i == 0 || faces[RING_START[i - 1]..RING_START[i]].iter().any(|&k| k != u32::MAX)
                });
                let mut w = [[0.0f32; 3]; RINGS];
                for c in 0..3 {
                    let within = |r: f64| tables[c].within(tau[c], r * profile.sigma_t[c]);
                    let cum = [0.0, within(bounds[0]), within(bounds[1]), within(bounds[2]), 1.0];
                    let share: [f64; RINGS] = std::array::from_fn(|i| (cum[i + 1] - cum[i]).max(0.0));
                    let total: f64 = (0..RINGS).filter(|&i| counted[i]).map(|i| share[i]).sum();
                    for i in 0..RINGS {
                        let n = if i == 0 {
                            1
                        } else {
                            faces[RING_START[i - 1]..RING_START[i]].iter().filter(|&&k| k != u32::MAX).count()
                        };
                        w[i][c] = match (counted[i] && n > 0, total > 0.0) {
                            (true, true) => (share[i] / total / n as f64) as f32,
                            (_, false) if i == 0 => 1.0,
                            _ => 0.0,
                        };
                    }
                }
                (faces, w.map(Rgb::from_array))
            })
            .collect();
        Spread { faces: rows.iter().map(|r| r.0).collect(), weights: rows.iter().map(|r| r.1).collect() }
    }

    /// Face `f`'s ring rays (thickness `t`, rings at `radii`, mesh units), as
    /// [`Spread::trace`] describes: the face each left the body through, `u32::MAX` where not
    /// counted.
    fn trace_face(mesh: &Mesh, bvh: &Bvh, offset: f32, f: usize, t: f32, radii: [f64; 3]) -> [u32; SAMPLES] {
        let mut out = [u32::MAX; SAMPLES];
        let n = mesh.face_normal(f);
        if n == glam::Vec3::ZERO {
            return out;
        }
        let origin = mesh.face_centroid(f) - n * offset;
        let (u, v) = n.any_orthonormal_pair();
        let turned = turn(f);
        for ring in 1..RINGS {
            let count = RING_START[ring] - RING_START[ring - 1];
            let r = radii[ring - 1] as f32;
            for j in 0..count {
                let a = std::f32::consts::TAU
                    * (turned + j as f32 / count as f32 + 0.5 * ring as f32 / count as f32);
                let o = origin + (u * a.cos() + v * a.sin()) * r;
                // Within the slab's reach: the thickness and the ring's radius twice over.
                let reach = t + 2.0 * r + offset;
                if let Some((_, k)) = bvh.closest_hit(o, -n, 0.0, reach)
                    && mesh.face_normal(k as usize).dot(n) < 0.0
                {
                    out[RING_START[ring - 1] + j] = k;
                }
            }
        }
        out
    }

    /// Face `f`'s far-side value `e` (per face) averaged with its weights, the centre being
    /// `centre` (the face across along its inward normal).
    #[inline]
    pub fn average(&self, f: usize, centre: usize, e: impl Fn(usize) -> Rgb) -> Rgb {
        let (faces, w) = (&self.faces[f], &self.weights[f]);
        let mut sum = e(centre) * w[0];
        for ring in 1..RINGS {
            for &k in &faces[RING_START[ring - 1]..RING_START[ring]] {
                if k != u32::MAX {
                    sum += e(k as usize) * w[ring];
                }
            }
        }
        sum
    }

    /// Faces it was made for.
    pub fn len(&self) -> usize {
        self.faces.len()
    }

    /// Whether it was made for no face.
    pub fn is_empty(&self) -> bool {
        self.faces.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use crate::Rgb;
    use crate::bssrdf::Material;
    use crate::irradiance::ShadowCaster;
    use crate::mesh::generate;
    use crate::session::Transport;
    use crate::solver::finite_body::{FiniteBody, ThicknessRays};
    use crate::solver::transmission::{CrossBody, Transmission};

    /// A 50 x 50 x 3 mm box of `material` (index 1) and its terms with and without the spread.
    fn box_terms(material: &str) -> (crate::mesh::Mesh, CrossBody, CrossBody) {
        let mut mesh = generate::cube(24);
        mesh.positions.iter_mut().for_each(|p| p.z *= 0.06);
        let mut m = Material::by_name(material).unwrap();
        m.eta = 1.0;
        let profile = Transport::new(m, 0.05).profile_at(mesh.extent());
        let caster = ShadowCaster::new(&mesh);
        let fb = FiniteBody::new(&profile);
        let rays = ThicknessRays::trace(&mesh, caster.bvh(), caster.offset());
        let gains = fb.gains_along(&mesh, &rays, caster.offset());
        let point = CrossBody::new(&profile, &fb, &mesh, &rays, caster.offset(), &gains, Transmission::Slab);
        let spread = point.clone().with_spread(&profile, &mesh, caster.bvh(), caster.offset());
        (mesh, point, spread)
    }

    /// The weights sum to 1 per channel: a uniform far side gives the term at one point.
    #[test]
    fn a_uniform_far_side_gives_the_one_point_term() {
        for material in ["marble", "skimmilk"] {
            let (mesh, point, spread) = box_terms(material);
            let n = mesh.triangles.len();
            let e = vec![Rgb::new(0.7, 0.5, 0.3); n];
            let (mut a, mut b) = (vec![Rgb::splat(0.2); n], vec![Rgb::splat(0.2); n]);
            point.add(&mut a, &mut vec![Rgb::ZERO; n], &e, None);
            spread.add(&mut b, &mut vec![Rgb::ZERO; n], &e, None);
            let worst = a.iter().zip(&b).map(|(x, y)| (*x - *y).abs().max_element()).fold(0.0f32, f32::max);
            assert!(worst < 1e-6, "{material}: {worst}");
            assert!(a.iter().zip(&b).any(|(x, y)| x != &Rgb::splat(0.2) && y != &Rgb::splat(0.2)));
        }
    }

    /// Light entering at one face of the far side reaches the near side spread over about
    /// the thickness plus the diffusion length: the face across from it takes a fraction,
    /// its neighbours within a few millimetres the rest, and the total over the near side is
    /// about what the one face across took alone (the spread moves light, it makes none).
    #[test]
    fn a_spike_on_the_far_side_is_spread_over_the_near_side() {
        let (mesh, point, spread) = box_terms("marble");
        let n = mesh.triangles.len();
        // The far face nearest the centre of the -z side.
        let spike = (0..n)
            .filter(|&f| mesh.face_normal(f).z < -0.9)
            .min_by(|&a, &b| mesh.face_centroid(a).length().total_cmp(&mesh.face_centroid(b).length()))
            .unwrap();
        let mut e = vec![Rgb::ZERO; n];
        e[spike] = Rgb::ONE;
        let (mut a, mut b) = (vec![Rgb::ZERO; n], vec![Rgb::ZERO; n]);
        point.add(&mut a, &mut vec![Rgb::ZERO; n], &e, None);
        spread.add(&mut b, &mut vec![Rgb::ZERO; n], &e, None);
        let near = |v: &[Rgb]| -> (f32, f32, usize) {
            let lit: Vec<f32> = (0..n).filter(|&f| mesh.face_normal(f).z > 0.9).map(|f| v[f].x).collect();
            (
                lit.iter().sum(),
                lit.iter().cloned().fold(0.0, f32::max),
                lit.iter().filter(|&&x| x > 0.0).count(),
            )
        };
        let (sum_a, max_a, count_a) = near(&a);
        let (sum_b, max_b, count_b) = near(&b);
        assert!(count_a <= 2 && count_b >= 4 * count_a, "faces lit: {count_a} -> {count_b}");
        assert!(max_b < 0.5 * max_a, "peak {max_a} -> {max_b}");
        // Face areas are equal; the samples pick faces, so the total is kept only on average.
        assert!(sum_b > 0.5 * sum_a && sum_b < 2.0 * sum_a, "total {sum_a} -> {sum_b}");
    }
}
