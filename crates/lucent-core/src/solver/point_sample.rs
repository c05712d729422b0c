//! One-point transport estimates `A_E R_d(x_E, x_o)` (Mertens et al. 2003, §4.2: the far-field
//! link coefficient, and the quantity the transport oracle of §5.2 compares) in `f32`, four
//! points at a time.
//!
//! The oracle asks for the estimate between a receiver and an emitter, then between the
//! receiver and the emitter's children, then between the receiver's children and the emitter:
//! twelve profile evaluations (four points × three channels) per question. The arithmetic is
//! `point_kernel`'s, run on the widest instruction set the CPU has ([`Isa::best`]);
//! every estimate of one [`ProfileF32`] takes the same path, so that the oracle may hand an
//! estimate from one form on as another's.

use super::near_face::CumulativeTables;
use super::point_kernel::{self as kernel, ProfileLanes};
use crate::bssrdf::Profile;
use crate::bssrdf::tables::TABLE_SIZE;
use crate::formfactor::cubature;
use crate::simd::{Isa, Separate};
use glam::{Vec3, Vec3A};

/// The profile's coefficients in `f32` for the hot loops (see [`Profile`] for their meaning;
/// lengths in mesh units).
#[derive(Clone, Debug)]
pub struct ProfileF32 {
    /// `sigma_tr` per channel, per mesh unit.
    pub sigma_tr: [f32; 3],
    /// `z_r` per channel, mesh units.
    pub z_r: [f32; 3],
    /// `z_v` per channel, mesh units.
    pub z_v: [f32; 3],
    /// `alpha' / 4π` per channel.
    pub k: [f32; 3],
    /// 1 where the poles sit on the receiver's normal (Mertens), 0 for the distance form
    /// (poles at the receiver point, `z` away in distance).
    pub normal_weight: f32,
    /// Squared distances added to the real and virtual poles' (`z²` in the distance form, 0
    /// for Mertens), per channel.
    off_r: [f32; 3],
    off_v: [f32; 3],
    /// Squared length (per channel) on which the profile is smooth at the receiver point, for
    /// the oracle's error estimates: `z_r²` for the analytic distance form; a tabulated profile
    /// with single scattering peaks like `1/r` there, so a tenth of `z_r`.
    near_off: [f32; 3],
    /// Squared length added to a piece's squared distance in the cubature's smoothness test
    /// ([`SmoothBound`]): the analytic distance form's `z_r²` (its poles lie `z_r` off the
    /// surface, so it is smooth on that scale), but 0 with tables: single scattering peaks
    /// like `1/r` at the receiver point, which no polynomial rule integrates however small
    /// the piece (with `near_off` there, a receiver's own face of radius `z_r / 10` and under
    /// took the cubature and fell 13-85% short).
    cut_off: [f32; 3],
    /// The lanes, poles and table of the kernel.
    kernel: ProfileLanes,
    /// The cumulative tables of a profile of tables alone (photon beam diffusion), for the
    /// faces at the receiver's peak.
    pub(super) cumulative: Option<CumulativeTables>,
    /// The instruction set every estimate runs on.
    isa: Isa,
}

impl ProfileF32 {
    /// The `f32` copy of `d`.
    pub fn new(d: &Profile) -> Self {
        let sigma_tr = d.sigma_tr.map(|v| v as f32);
        let z_r = d.z_r.map(|v| v as f32);
        let z_v = d.z_v.map(|v| v as f32);
        let k = d.alpha_prime.map(|v| (v / (4.0 * std::f64::consts::PI)) as f32);
        let normal_weight = if d.kind.uses_normals() { 1.0 } else { 0.0 };
        let off = |z: [f32; 3]| z.map(|z| (1.0 - normal_weight) * z * z);
        let (off_r, off_v) = (off(z_r), off(z_v));
        let (near_off, cut_off) = match &d.tables {
            Some(_) => (off(z_r.map(|z| 0.1 * z)), [0.0; 3]),
            None => (off_r, off_r),
        };
        let table = d.tables.as_ref().map(|t| {
            let n = TABLE_SIZE + 1;
            Box::new(std::array::from_fn(|k| t.channels[k / n].r_radial.get(k % n).copied().unwrap_or(0.0)))
        });
        let per_table = |f: fn(&crate::bssrdf::RadialTable) -> f64| {
            d.tables.as_ref().map_or([0.0; 3], |t| t.channels.each_ref().map(|c| f(c) as f32))
        };
        let (inv_r_max, r_floor) = (per_table(|c| 1.0 / c.r_max), per_table(|c| c.r_floor));
        ProfileF32 {
            sigma_tr,
            z_r,
            z_v,
            k,
            normal_weight,
            off_r,
            off_v,
            near_off,
            cut_off,
            kernel: ProfileLanes::new(
                [sigma_tr, z_r, z_v, k, off_r, off_v, inv_r_max, r_floor],
                d.has_analytic(),
                table,
            ),
            cumulative: CumulativeTables::new(d),
            isa: Isa::best(),
        }
    }

    /// The same profile on instruction set `isa` (if this CPU has it; for tests and benches).
    pub fn with_isa(mut self, isa: Isa) -> Self {
        if isa.is_available() {
            self.isa = isa;
        }
        self
    }

    /// The instruction set the estimates run on.
    pub fn isa(&self) -> Isa {
        self.isa
    }
}

/// The poles of one receiver point (the profile sits at the receiver, §4's inverse
/// interpretation): for Mertens real sources `x_o - z_r n_o` and virtual sources
/// `x_o + z_v n_o` per channel; for the distance-form profiles both at `x_o` (their `z`
/// enters as an added squared distance).
#[derive(Clone, Copy, Debug)]
pub struct ReceiverSources {
    pub(super) x_r: [Vec3; 3],
    pub(super) x_v: [Vec3; 3],
}

impl ReceiverSources {
    /// The sources for receiver point `x_o` with unit normal `n_o`.
    #[inline]
    pub fn new(d: &ProfileF32, x_o: Vec3, n_o: Vec3) -> Self {
        let n = d.normal_weight * n_o;
        ReceiverSources {
            x_r: std::array::from_fn(|c| x_o - d.z_r[c] * n),
            x_v: std::array::from_fn(|c| x_o + d.z_v[c] * n),
        }
    }

    /// Whether every pole is farther from `p` than `margin + base + spread z` (its own `z`;
    /// distances include the distance form's added `z²`): the poles of all points within
    /// `base` of the receiver point whose normals stray by at most `spread` stay `margin` away
    /// from `p` (the distance form's poles do not move with the normal: callers pass 0).
    #[inline]
    pub fn clear_of(&self, d: &ProfileF32, p: Vec3, margin: f32, base: f32, spread: f32) -> bool {
        let at = self.at(d, p);
        (0..3).all(|c| {
            let rr = margin + base + spread * d.z_r[c];
            let rv = margin + base + spread * d.z_v[c];
            at.real(c) + d.off_r[c] > rr * rr && at.virt(c) + d.off_v[c] > rv * rv
        })
    }

    /// The squared distances from `p` to the poles, made once where all poles coincide (the
    /// distance form: the receiver point) rather than six times.
    #[inline]
    fn at(&self, d: &ProfileF32, p: Vec3) -> PoleDistances {
        if d.normal_weight == 0.0 {
            PoleDistances::One((self.x_r[0] - p).length_squared())
        } else {
            PoleDistances::Each(
                std::array::from_fn(|c| (self.x_r[c] - p).length_squared()),
                std::array::from_fn(|c| (self.x_v[c] - p).length_squared()),
            )
        }
    }

    /// Distance from `p` to the nearer of the two poles, per channel (with the distance
    /// form's added `z²`): where `R` varies fastest.
    #[inline]
    pub fn nearest(&self, d: &ProfileF32, p: Vec3) -> [f32; 3] {
        let at = self.at(d, p);
        std::array::from_fn(|c| (at.nearer(c) + d.near_off[c]).sqrt())
    }

    /// One-point form factor `A R(p)` for an emitter of area `area` at `p`.
    #[inline]
    pub fn point_sample(&self, d: &ProfileF32, p: Vec3, area: f32) -> [f32; 3] {
        let k = &d.kernel;
        match d.isa {
            // SAFETY: `d.isa` is only ever an instruction set this CPU has (`Isa::best`,
            // `ProfileF32::with_isa` check `is_available`).
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512 => unsafe { kernel::avx512::to_point(k, self, p, area) },
            // SAFETY: as above.
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => unsafe { kernel::avx2::to_point(k, self, p, area) },
            _ => kernel::to_point::<Separate, 3>(k, self, p, area),
        }
    }

    /// [`ReceiverSources::point_sample`] for four emitters at once (pad with area 0).
    #[inline]
    pub fn point_samples(&self, d: &ProfileF32, p: &[Vec3; 4], area: &[f32; 4]) -> [[f32; 3]; 4] {
        let k = &d.kernel;
        match d.isa {
            // SAFETY: `d.isa` is only ever an instruction set this CPU has (`Isa::best`,
            // `ProfileF32::with_isa` check `is_available`).
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512 => unsafe { kernel::avx512::to_points(k, self, p, area) },
            // SAFETY: as above.
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => unsafe { kernel::avx2::to_points(k, self, p, area) },
            _ => kernel::to_points::<Separate, 12>(k, self, p, area),
        }
    }
}

impl ReceiverSources {
    /// `∫_T R_d` over triangle `tri` (area `area`) by Radon's degree-5 rule
    /// ([`crate::formfactor::cubature`]): seven dipole points in two batches. The form
    /// factor's own short cut in `f32`, for where `ReceiverSources::smooth_within` holds.
    #[inline]
    pub fn triangle_cubature(&self, d: &ProfileF32, tri: &[Vec3; 3], area: f32) -> [f32; 3] {
        self.cubature(d, &[(*tri, area)])
    }

    /// The sum of [`ReceiverSources::triangle_cubature`] over `pieces` (triangle, area).
    pub fn cubature(&self, d: &ProfileF32, pieces: &[([Vec3; 3], f32)]) -> [f32; 3] {
        let (mut buf, mut sum) = (PointBuf::new(), [0.0f32; 3]);
        for chunk in pieces.chunks((POINT_BUF - 1) / 7) {
            chunk.iter().for_each(|&(tri, area)| buf.push_radon7(tri, area));
            let f = self.weighted_sum(d, &mut buf);
            sum.iter_mut().zip(f).for_each(|(s, f)| *s += f);
        }
        sum
    }

    /// `Σ_i w_i R(p_i)` per channel over the points in `buf`, which it empties. On AVX-512
    /// the points go sixteen to a register (`point_kernel_avx512::weighted_sum`), elsewhere
    /// four to a batch.
    pub(crate) fn weighted_sum(&self, d: &ProfileF32, buf: &mut PointBuf) -> [f32; 3] {
        let used = std::mem::take(&mut buf.used);
        #[cfg(target_arch = "x86_64")]
        if d.isa == Isa::Avx512 {
            // The last register's unused lanes: weight 0 (they hold an earlier sum's points).
            let n = used.next_multiple_of(16);
            buf.w[used..n].fill(0.0);
            // SAFETY: `d.isa` is only ever an instruction set this CPU has.
            return unsafe {
                kernel::avx512::weighted_sum(
                    &d.kernel,
                    self,
                    &buf.x[..n],
                    &buf.y[..n],
                    &buf.z[..n],
                    &buf.w[..n],
                )
            };
        }
        let mut sum = [0.0f32; 3];
        for i in (0..used).step_by(4) {
            let mut pts = [Vec3::ZERO; 4];
            let mut wts = [0.0f32; 4];
            for j in 0..4.min(used - i) {
                pts[j] = Vec3::new(buf.x[i + j], buf.y[i + j], buf.z[i + j]);
                wts[j] = buf.w[i + j];
            }
            for f in self.point_samples(d, &pts, &wts) {
                sum.iter_mut().zip(f).for_each(|(s, f)| *s += f);
            }
        }
        sum
    }

    /// Whether `k ρ ≤ max` ([`cubature::k_rho`]) for an emitter with midpoint `mid` and the
    /// radius and `max` of `bound`: one squared distance against the bound where all poles
    /// coincide, else one per channel (the cubature's pieces ask it dozens of times a link).
    #[inline]
    pub(crate) fn smooth_within(&self, d: &ProfileF32, mid: Vec3, bound: &SmoothBound) -> bool {
        match self.at(d, mid) {
            PoleDistances::One(s2) => s2 >= bound.s2_max,
            at => (0..3).all(|c| at.nearer(c) >= bound.s2[c]),
        }
    }
}

/// [`ReceiverSources::smooth_within`]'s test for one piece radius, `k ρ ≤ max` in squares,
/// `9 ρ² ≤ (max - σ_tr ρ)² (s² + cut_off)`, solved for the squared
/// distance: a piece of that radius is smooth where every channel's nearer pole is at least
/// `s2[c]` away (squared), so a test is one distance and a comparison. Made once per level
/// of [`super::evaluate::Evaluator::smooth_face`]'s cutting rather than per piece.
#[derive(Clone, Copy)]
pub(crate) struct SmoothBound {
    /// Least squared distance per channel (`f32::INFINITY`: never smooth).
    s2: [f32; 3],
    /// The largest of `s2`, for the distance form (all poles at one place).
    s2_max: f32,
}

impl SmoothBound {
    /// The bound for pieces of radius `radius` and largest `k ρ` `max`.
    #[inline]
    pub fn new(d: &ProfileF32, radius: f32, max: f32) -> Self {
        // Three channels in one vector division: a face's cutting makes several of these.
        let room = Vec3A::splat(max) - Vec3A::from_array(d.sigma_tr) * radius;
        let s2 = Vec3A::splat(9.0 * radius * radius) / (room * room) - Vec3A::from_array(d.cut_off);
        let s2 = Vec3A::select(room.cmpgt(Vec3A::ZERO), s2, Vec3A::INFINITY);
        SmoothBound { s2: s2.to_array(), s2_max: s2.max_element() }
    }
}

/// Squared distances from a point to a receiver's poles ([`ReceiverSources::at`]).
#[derive(Clone, Copy)]
enum PoleDistances {
    /// All six poles at one place.
    One(f32),
    /// Per channel, to the real and the virtual pole.
    Each([f32; 3], [f32; 3]),
}

impl PoleDistances {
    #[inline(always)]
    fn real(self, c: usize) -> f32 {
        match self {
            PoleDistances::One(s2) => s2,
            PoleDistances::Each(r, _) => r[c],
        }
    }

    #[inline(always)]
    fn virt(self, c: usize) -> f32 {
        match self {
            PoleDistances::One(s2) => s2,
            PoleDistances::Each(_, v) => v[c],
        }
    }

    #[inline(always)]
    fn nearer(self, c: usize) -> f32 {
        match self {
            PoleDistances::One(s2) => s2,
            PoleDistances::Each(r, v) => r[c].min(v[c]),
        }
    }
}

/// Most points one [`PointBuf`] holds: Radon's seven points on each of the most pieces a
/// face is cut into, plus the padding lane of the last piece, in whole registers of sixteen.
pub(crate) const POINT_BUF: usize = (7 * super::evaluate::MAX_PIECES + 1).next_multiple_of(16);

/// Radon's seven points as barycentric weights of a triangle's vertices `a`, `b`, `c` (rows
/// 0-2) and their rule weights (row 3), padded to eight lanes with a point of weight 0.
const RADON7_BARY: [[f32; 8]; 4] = {
    let (w0, [(t1, w1), (t2, w2)]) = (cubature::RADON7_CENTROID_WEIGHT, cubature::RADON7_ORBITS);
    let third = 1.0 / 3.0;
    let (s1, s2) = (1.0 - 2.0 * t1, 1.0 - 2.0 * t2);
    [
        [third as f32, s1 as f32, t1 as f32, t1 as f32, s2 as f32, t2 as f32, t2 as f32, 0.0],
        [third as f32, t1 as f32, s1 as f32, t1 as f32, t2 as f32, s2 as f32, t2 as f32, 0.0],
        [third as f32, t1 as f32, t1 as f32, s1 as f32, t2 as f32, t2 as f32, s2 as f32, 0.0],
        [w0 as f32, w1 as f32, w1 as f32, w1 as f32, w2 as f32, w2 as f32, w2 as f32, 0.0],
    ]
};

/// Weighted points gathered for one [`ReceiverSources::weighted_sum`], as coordinate arrays
/// (kept by the caller between sums, so no sum clears them).
pub(crate) struct PointBuf {
    x: [f32; POINT_BUF],
    y: [f32; POINT_BUF],
    z: [f32; POINT_BUF],
    w: [f32; POINT_BUF],
    used: usize,
}

impl PointBuf {
    pub fn new() -> Self {
        PointBuf {
            x: [0.0; POINT_BUF],
            y: [0.0; POINT_BUF],
            z: [0.0; POINT_BUF],
            w: [0.0; POINT_BUF],
            used: 0,
        }
    }

    /// Adds Radon's seven points on triangle `tri` of area `area` (the rule of
    /// [`cubature::radon7`]), with their weights times the area. Writes eight lanes (the
    /// eighth, weight 0, is overwritten by the next piece or ignored by the sum), so that
    /// each coordinate is one eight-wide multiply-add of the vertices.
    #[inline]
    pub fn push_radon7(&mut self, [a, b, c]: [Vec3; 3], area: f32) {
        let i = self.used;
        let lanes = |v: &mut [f32; POINT_BUF], (a, b, c): (f32, f32, f32)| {
            let out: &mut [f32; 8] = (&mut v[i..i + 8]).try_into().unwrap();
            for k in 0..8 {
                out[k] = a * RADON7_BARY[0][k] + b * RADON7_BARY[1][k] + c * RADON7_BARY[2][k];
            }
        };
        lanes(&mut self.x, (a.x, b.x, c.x));
        lanes(&mut self.y, (a.y, b.y, c.y));
        lanes(&mut self.z, (a.z, b.z, c.z));
        let w: &mut [f32; 8] = (&mut self.w[i..i + 8]).try_into().unwrap();
        for k in 0..8 {
            w[k] = area * RADON7_BARY[3][k];
        }
        self.used = i + 7;
    }

    /// Drops the points added since the last sum.
    #[inline]
    pub fn clear(&mut self) {
        self.used = 0;
    }
}

/// One emitter of area `area` at `p` seen from four receivers' sources:
/// `[src[j].point_sample(d, p, area); 4]`, batched.
#[inline]
pub fn point_samples_from(src: &[ReceiverSources; 4], d: &ProfileF32, p: Vec3, area: f32) -> [[f32; 3]; 4] {
    let k = &d.kernel;
    match d.isa {
        // SAFETY: `d.isa` is only ever an instruction set this CPU has (`Isa::best`,
        // `ProfileF32::with_isa` check `is_available`).
        #[cfg(target_arch = "x86_64")]
        Isa::Avx512 => unsafe { kernel::avx512::from_point(k, src, p, area) },
        // SAFETY: as above.
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 => unsafe { kernel::avx2::from_point(k, src, p, area) },
        _ => kernel::from_point::<Separate, 12>(k, src, p, area),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bssrdf::Material;

    #[test]
    fn batches_match_the_f64_dipole() {
        let m = Material::by_name("skimmilk").unwrap();
        let dip = Profile::for_model_scale(&m, 1.0, 0.05);
        let d = ProfileF32::new(&dip);
        let x_o = Vec3::new(0.1, -0.2, 0.05);
        let n_o = Vec3::new(0.3, 0.4, 0.866).normalize();
        let src = ReceiverSources::new(&d, x_o, n_o);
        let p = [Vec3::new(0.3, 0.1, 0.0), Vec3::new(-0.2, 0.0, 0.1), Vec3::new(0.1, -0.15, 0.05), Vec3::X];
        let area = [0.01, 0.02, 0.003, 0.0];
        let got = src.point_samples(&d, &p, &area);
        for j in 0..4 {
            let want = dip.rd(x_o.as_dvec3(), n_o.as_dvec3(), p[j].as_dvec3());
            for c in 0..3 {
                let w = want[c] * area[j] as f64;
                assert!(
                    (got[j][c] as f64 - w).abs() <= 1e-5 * w.abs() + 1e-30,
                    "{j} {c}: {} vs {w}",
                    got[j][c]
                );
            }
        }
        // The oracle hands estimates from one form on as the other's: they must agree exactly.
        let from = point_samples_from(&[src; 4], &d, p[0], area[0]);
        assert_eq!(from[2], got[0]);
        for j in 0..4 {
            assert_eq!(src.point_sample(&d, p[j], area[j]), got[j]);
        }
    }

    /// Every instruction set against the portable path on random points, for every profile
    /// (Mertens' normal placement, the distance-form dipole with single scattering, PBD).
    /// Tolerance 2e-5 relative: fusing (and AVX-512's Newton-step `1 / s`) rounds `σ_tr s`
    /// differently, and one ulp of it is up to 87 ulp of `e^{-σ_tr s}`; 1e-30 absolute for
    /// results that underflow to subnormals. Prints the worst relative difference.
    #[test]
    fn vector_paths_match_the_portable_one() {
        use crate::bssrdf::ProfileKind;
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(11);
        let mut point = |s: f32| Vec3::new(rng.random(), rng.random(), rng.random()) * (2.0 * s) - s;
        // Points from touching the poles to beyond the profile's range.
        let trials: Vec<(Vec3, Vec3, [Vec3; 4])> = (0..400)
            .map(|t| {
                let s = [0.002, 0.02, 0.2, 1.0][t % 4];
                let (x_o, n_o) = (point(s), point(1.0).normalize_or(Vec3::Z));
                (x_o, n_o, [point(s), point(s), point(s), x_o])
            })
            .collect();
        for name in ["marble", "skimmilk", "ketchup"] {
            let m = Material::by_name(name).unwrap();
            for kind in ProfileKind::ALL {
                let dip = Profile::of_kind(&m, 50.0, kind, kind.has_single_scattering());
                let scalar = ProfileF32::new(&dip).with_isa(Isa::Scalar);
                for isa in Isa::available().into_iter().skip(1) {
                    let d = ProfileF32::new(&dip).with_isa(isa);
                    let mut worst = 0.0f32;
                    for &(x_o, n_o, p) in &trials {
                        let src = ReceiverSources::new(&d, x_o, n_o);
                        let area = [1e-3, 2e-3, 5e-4, 1e-3];
                        let got = src.point_samples(&d, &p, &area);
                        let want = src.point_samples(&scalar, &p, &area);
                        let from = point_samples_from(&[src; 4], &d, p[1], area[1]);
                        for j in 0..4 {
                            assert_eq!(src.point_sample(&d, p[j], area[j]), got[j]);
                            assert_eq!(src.point_sample(&scalar, p[j], area[j]), want[j]);
                            assert_eq!(from[j], got[1]);
                            for c in 0..3 {
                                let (g, w) = (got[j][c], want[j][c]);
                                if w.abs() > 1e-30 && g.is_finite() {
                                    worst = worst.max((g - w).abs() / w.abs());
                                }
                                assert!(
                                    (g - w).abs() <= 2e-5 * w.abs() + 1e-30
                                        || (g.is_infinite() && w.is_infinite()),
                                    "{name} {kind} {isa:?} {j} {c}: {g} vs {w}"
                                );
                            }
                        }
                    }
                    eprintln!("{name} {kind} {isa:?}: worst relative difference {worst:e}");
                }
            }
        }
    }

    #[test]
    fn triangle_cubature_matches_the_f64_rule() {
        let m = Material::by_name("marble").unwrap();
        let dip = Profile::for_model_scale(&m, 1.0, 0.01);
        let d = ProfileF32::new(&dip);
        let (x_o, n_o) = (Vec3::new(0.01, 0.02, 0.0), Vec3::new(0.1, -0.2, 1.0).normalize());
        let src = ReceiverSources::new(&d, x_o, n_o);
        let tri = [Vec3::new(0.0, 0.0, 0.001), Vec3::new(0.02, 0.005, 0.0), Vec3::new(0.004, 0.03, -0.002)];
        let t64 = tri.map(|p| p.as_dvec3());
        let normal = (t64[1] - t64[0]).cross(t64[2] - t64[0]);
        let area = 0.5 * normal.length();
        let want = cubature::polygon_integral(&t64, normal.normalize(), x_o.as_dvec3(), n_o.as_dvec3(), &dip);
        let got = src.triangle_cubature(&d, &tri, area as f32);
        for c in 0..3 {
            assert!((got[c] as f64 / want[c] - 1.0).abs() < 1e-5, "{c}: {} vs {}", got[c], want[c]);
        }
        // `smooth_within` is `k ρ ≤ max` in squares: at the f64 rule's own `k ρ`, either side.
        let (mid, radius) = ((tri[0] + tri[1] + tri[2]) / 3.0, 0.02f32);
        let k_rho =
            cubature::k_rho(&dip, x_o.as_dvec3(), n_o.as_dvec3(), mid.as_dvec3(), radius as f64) as f32;
        assert!(
            src.smooth_within(&d, mid, &SmoothBound::new(&d, radius, 1.01 * k_rho))
                && !src.smooth_within(&d, mid, &SmoothBound::new(&d, radius, 0.99 * k_rho))
        );
    }

    /// The cubature over many pieces (AVX-512: sixteen points a register, with padding lanes
    /// masked off the sums) agrees with the portable four-point batches on every path this
    /// CPU has, for every profile, including a piece count that leaves a register part-used.
    #[test]
    fn cubature_matches_across_instruction_sets() {
        use crate::bssrdf::ProfileKind;
        let m = Material::by_name("skimmilk").unwrap();
        let (x_o, n_o) = (Vec3::new(0.001, -0.002, 0.0), Vec3::new(0.1, 0.05, 1.0).normalize());
        let pieces: Vec<([Vec3; 3], f32)> = (0..37)
            .map(|i| {
                let o = Vec3::new(0.004 * i as f32, 0.003 * (i % 4) as f32, 0.0005 * (i % 3) as f32);
                ([o, o + Vec3::new(0.003, 0.0, 0.0), o + Vec3::new(0.0, 0.003, 0.0005)], 4.5e-6)
            })
            .collect();
        for profile in ProfileKind::ALL {
            let dip = Profile::at_model_scale(&m, 1.0, 0.01, profile, true);
            let portable = ProfileF32::new(&dip).with_isa(Isa::Scalar);
            let src = ReceiverSources::new(&portable, x_o, n_o);
            // 37 pieces: two full chunks of sixteen on AVX-512, then five.
            for n in [1, 2, 5, 13, 37] {
                let want = src.cubature(&portable, &pieces[..n]);
                for isa in Isa::ALL.into_iter().filter(|i| i.is_available()) {
                    let got = src.cubature(&ProfileF32::new(&dip).with_isa(isa), &pieces[..n]);
                    for c in 0..3 {
                        assert!(want[c] > 0.0, "{profile:?}: {want:?}");
                        let rel = (got[c] / want[c] - 1.0).abs();
                        assert!(rel < 2e-5, "{profile:?} {isa:?}, {n} pieces, channel {c}: {rel}");
                    }
                }
            }
        }
    }
}
