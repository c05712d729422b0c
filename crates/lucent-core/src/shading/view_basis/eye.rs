//! The per-face half of a camera move (issue 51's target: 5 ms of CPU at 203K faces): the
//! closed forms of [`super::ViewBasis::face_seen`] over blocks of [`LANES`] faces, each
//! quantity of a block contiguous (structure of arrays), so that one vector instruction serves
//! sixteen faces, and compiled per instruction set as the solver's kernels are
//! ([`crate::simd`]).
//!
//! The arithmetic is `face_seen`'s, operation for operation, except the exponentials: the C
//! library's `exp_m1` (a call per channel, about half of the old camera move) is
//! [`crate::fastexp::exp_m1_with`] here, within 6e-7 relative; the chord factor's
//! `1 - e^{-σ_t T}` is computed once per channel and shared with the single scattering, which
//! computed it again. The blocks take the faces by the direction of their normals
//! ([`normal_order`]), so that a block's faces mostly turn to or from the eye together; a block
//! whose faces all turn away costs one dot product per face and reads nothing else. Faces with an infinite chord (a ray that left an open mesh,
//! where `chord` picks a sample instead of interpolating) are left to `face_seen`.

use super::{ENV_MU, FaceFrame, FaceTerms};
use crate::Rgb;
use crate::fastexp::exp_m1_with;
use crate::simd::{Isa, Madd, Separate};
use glam::Vec3;

/// Faces per block: one AVX-512 register of `f32`, two of AVX2.
pub(super) const LANES: usize = 16;

type Lanes = [f32; LANES];

/// What a face gives the vertex means: `[weight, kept · weight (3)]` and `[single · weight
/// (3), 0]`, the weight being its area where it faces the eye, else 0 (every entry 0). One
/// half cache line, read by each of the face's vertices as two vector loads.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(32))]
pub(super) struct FaceSeen(pub(super) [glam::Vec4; 2]);

impl FaceSeen {
    /// The eight entries in order.
    #[cfg(test)]
    fn entries(&self) -> [f32; 8] {
        let [a, b] = self.0;
        [a.x, a.y, a.z, a.w, b.x, b.y, b.z, b.w]
    }
}

/// The geometry of [`LANES`] faces that an eye reads ([`FaceFrame`]'s), by quantity and
/// component; lanes past the last face are zero (they face no eye).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct GeoBlock {
    centroid: [Lanes; 3],
    /// The geometric normal; zero where the face has no normal (it faces no eye).
    facing: [Lanes; 3],
    n: [Lanes; 3],
    t1: [Lanes; 3],
    t2: [Lanes; 3],
    area: Lanes,
    chords: [Lanes; 5],
}

/// The light and environment terms of [`LANES`] faces ([`FaceTerms`]'s).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct SourceBlock {
    a: [Lanes; 3],
    /// `g[c][axis]`.
    g: [[Lanes; 3]; 3],
    cap: [Lanes; 3],
    env_body: [Lanes; 3],
}

/// Cells of the cube map of normal directions that [`normal_order`] sorts faces into: 4 × 4
/// on each side.
const NORMAL_CELLS: usize = 6 * 16;

/// The faces of `frames` in the order the blocks take them: by the cell of their normal's
/// direction ([`NORMAL_CELLS`]), the mesh's order within a cell. A block's faces then turn to
/// or from an eye together (about half the blocks are skipped whole), while a vertex's faces,
/// of similar normals, mostly stay near each other for the vertex means.
pub(super) fn normal_order(frames: &[FaceFrame]) -> Vec<u32> {
    let cell = |n: Vec3| {
        let a = n.abs();
        let (side, u, v, m) = if a.x >= a.y && a.x >= a.z {
            (usize::from(n.x < 0.0), n.y, n.z, a.x)
        } else if a.y >= a.z {
            (2 + usize::from(n.y < 0.0), n.x, n.z, a.y)
        } else {
            (4 + usize::from(n.z < 0.0), n.x, n.y, a.z)
        };
        let at = |c: f32| if m > 0.0 { ((c / m * 0.5 + 0.5) * 4.0).clamp(0.0, 3.0) as usize } else { 0 };
        side * 16 + at(u) * 4 + at(v)
    };
    let cells: Vec<usize> = frames.iter().map(|fr| cell(fr.facing)).collect();
    let mut start = [0usize; NORMAL_CELLS + 1];
    for &c in &cells {
        start[c + 1] += 1;
    }
    for c in 0..NORMAL_CELLS {
        start[c + 1] += start[c];
    }
    let mut order = vec![0u32; frames.len()];
    for (f, &c) in cells.iter().enumerate() {
        order[start[c]] = f as u32;
        start[c] += 1;
    }
    order
}

/// The blocks of `frames` (and of `terms` where not empty) taken in `order`, and the
/// positions in it of the faces with an infinite chord, which `face_seen` evaluates.
pub(super) fn blocks(
    frames: &[FaceFrame],
    terms: &[FaceTerms],
    order: &[u32],
) -> (Vec<GeoBlock>, Vec<SourceBlock>, Vec<u32>) {
    use rayon::prelude::*;
    let geo = order
        .par_chunks(LANES)
        .map(|chunk| {
            let mut b = GeoBlock::default();
            for (i, fr) in chunk.iter().map(|&f| &frames[f as usize]).enumerate() {
                let facing = if fr.n == Vec3::ZERO { Vec3::ZERO } else { fr.facing };
                for (dst, v) in [
                    (&mut b.centroid, fr.centroid),
                    (&mut b.facing, facing),
                    (&mut b.n, fr.n),
                    (&mut b.t1, fr.t1),
                    (&mut b.t2, fr.t2),
                ] {
                    dst[0][i] = v.x;
                    dst[1][i] = v.y;
                    dst[2][i] = v.z;
                }
                b.area[i] = fr.area;
                for (c, t) in fr.chords.iter().enumerate() {
                    b.chords[c][i] = *t;
                }
            }
            b
        })
        .collect();
    let source = order
        .par_chunks(LANES)
        .filter(|_| !terms.is_empty())
        .map(|chunk| {
            let mut b = SourceBlock::default();
            for (i, t) in chunk.iter().map(|&f| &terms[f as usize]).enumerate() {
                for c in 0..3 {
                    b.a[c][i] = t.a[c];
                    b.cap[c][i] = t.cap[c];
                    b.env_body[c][i] = t.env_body[c];
                    for axis in 0..3 {
                        b.g[c][axis][i] = t.g[c][axis];
                    }
                }
            }
            b
        })
        .collect();
    let open = order
        .iter()
        .enumerate()
        .filter(|(_, f)| {
            let fr = &frames[**f as usize];
            fr.n != Vec3::ZERO && fr.chords.iter().any(|t| t.is_infinite())
        })
        .map(|(p, _)| p as u32)
        .collect();
    (geo, source, open)
}

/// What every face of one eye shares.
pub(super) struct EyeConsts {
    /// The eye, mesh units.
    pub(super) eye: Vec3,
    pub(super) eta: f32,
    pub(super) sin_tilt: f32,
    pub(super) sigma_t: [f32; 3],
    /// `α' / (4π)` per channel.
    pub(super) albedo_4pi: [f32; 3],
    /// Whether the chord factor's kept share is wanted (else 0).
    pub(super) chord: bool,
}

/// `out`'s faces seen from `k.eye`, block by block (`source` empty: no single scattering;
/// `env` empty: no environment; else one of each per face), on `isa` if this CPU has it.
pub(super) fn faces_seen(
    isa: Isa,
    k: &EyeConsts,
    geo: &[GeoBlock],
    source: &[SourceBlock],
    env: &[[Rgb; ENV_MU]],
    out: &mut [[FaceSeen; LANES]],
) {
    match isa {
        // SAFETY: checked here that this CPU has the instruction set.
        #[cfg(target_arch = "x86_64")]
        Isa::Avx512 if isa.is_available() => unsafe { avx512::blocks_seen(k, geo, source, env, out) },
        // SAFETY: as above.
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 if isa.is_available() => unsafe { avx2::blocks_seen(k, geo, source, env, out) },
        _ => blocks_seen::<Separate>(k, geo, source, env, out),
    }
}

/// The blocks of `out`, as [`faces_seen`] (multiply-adds fused or not: `M`).
#[inline(always)]
fn blocks_seen<M: Madd>(
    k: &EyeConsts,
    geo: &[GeoBlock],
    source: &[SourceBlock],
    env: &[[Rgb; ENV_MU]],
    out: &mut [[FaceSeen; LANES]],
) {
    for (b, (g, o)) in geo.iter().zip(out.iter_mut()).enumerate() {
        let env = env.get(b * LANES..).map(|e| &e[..e.len().min(LANES)]).unwrap_or(&[]);
        block::<M>(k, g, source.get(b), env, o);
    }
}

/// One block: see the module docs; `face_seen`'s steps are named as there. Each loop runs
/// over the lanes with straight-line arithmetic (a branch is a select), so that the compiler
/// turns it into vector instructions; a loop over the channels stays outside the lanes'.
#[inline(always)]
fn block<M: Madd>(
    k: &EyeConsts,
    g: &GeoBlock,
    source: Option<&SourceBlock>,
    env: &[[Rgb; ENV_MU]],
    out: &mut [FaceSeen; LANES],
) {
    let mut facing = [0.0f32; LANES];
    for (i, d) in facing.iter_mut().enumerate() {
        let to = [k.eye.x - g.centroid[0][i], k.eye.y - g.centroid[1][i], k.eye.z - g.centroid[2][i]];
        *d = g.facing[0][i] * to[0] + g.facing[1][i] * to[1] + g.facing[2][i] * to[2];
    }
    if facing.iter().all(|d| *d <= 0.0) {
        *out = [FaceSeen::default(); LANES];
        return;
    }
    let (mu_o, w_t, t) = view_rays(k, g);
    // The kept shares, and the single scattering of the lights.
    let mut kept = [[0.0f32; LANES]; 3];
    let mut single = [[0.0f32; LANES]; 3];
    for ch in 0..3 {
        let s = k.sigma_t[ch];
        for i in 0..LANES {
            kept[ch][i] = -exp_m1_with::<M>(-s * t[i]);
        }
        let Some(src) = source else { continue };
        for i in 0..LANES {
            // `single`: the view ray's closed form under the face's exponential source.
            let a_src = src.a[ch][i];
            let g = &src.g[ch];
            let grow = (g[0][i] * w_t[0][i]) + (g[1][i] * w_t[1][i]) + (g[2][i] * w_t[2][i]);
            let a = s - grow.min(2.0 * s);
            let x = a * t[i];
            let small = t[i] * (1.0 - 0.5 * x);
            let integral = if x.abs() < 1e-4 { small } else { -exp_m1_with::<M>(-x) / a };
            let value = (s * a_src * integral).min(src.cap[ch][i] * kept[ch][i]);
            single[ch][i] = if a_src <= 0.0 { 0.0 } else { k.albedo_4pi[ch] * value };
        }
    }
    if let Some(src) = source {
        for (i, table) in env.iter().enumerate() {
            // The environment's half-space table at the exit cosine, and the body's term.
            let x = mu_o[i] * (ENV_MU - 1) as f32;
            let j = (x as usize).min(ENV_MU - 2);
            let w = x - j as f32;
            let half_space = (table[j] * (1.0 - w) + table[j + 1] * w).max(Rgb::ZERO);
            for ch in 0..3 {
                single[ch][i] += half_space[ch] + src.env_body[ch][i];
            }
        }
    }
    // `(weight, kept · weight, single · weight)`, lane by lane, then into the faces' records.
    let eta2 = k.eta * k.eta;
    let mut weighted = [[0.0f32; LANES]; 7];
    for i in 0..LANES {
        let w = if facing[i] <= 0.0 { 0.0 } else { g.area[i] };
        weighted[0][i] = w;
        for ch in 0..3 {
            let l = single[ch][i] / eta2;
            let l = if l > 0.0 { l } else { 0.0 };
            weighted[1 + ch][i] = if k.chord { kept[ch][i] * w } else { 0.0 };
            weighted[4 + ch][i] = if source.is_some() { l * w } else { 0.0 };
        }
    }
    for (i, o) in out.iter_mut().enumerate() {
        let w = |q: usize| weighted[q][i];
        *o = FaceSeen([glam::Vec4::new(w(0), w(1), w(2), w(3)), glam::Vec4::new(w(4), w(5), w(6), 0.0)]);
    }
}

/// Per lane of `g` seen from `k.eye`: the exit cosine `μ_o`, the refracted view direction
/// `w_t` (by component) and the chord along it (`refract_inward` and `chord`'s arithmetic,
/// for finite chords).
#[inline(always)]
fn view_rays(k: &EyeConsts, g: &GeoBlock) -> (Lanes, [Lanes; 3], Lanes) {
    let (mut mu_o, mut w_t, mut t) = ([0.0f32; LANES], [[0.0f32; LANES]; 3], [0.0f32; LANES]);
    let eta = k.eta;
    for i in 0..LANES {
        let to = [k.eye.x - g.centroid[0][i], k.eye.y - g.centroid[1][i], k.eye.z - g.centroid[2][i]];
        let w_o = normalize_or_zero(to);
        let n = [g.n[0][i], g.n[1][i], g.n[2][i]];
        let mu = dot(n, w_o);
        let two_mu = 2.0 * mu;
        let back = mu < 0.0;
        let w_o = [
            if back { w_o[0] - two_mu * n[0] } else { w_o[0] },
            if back { w_o[1] - two_mu * n[1] } else { w_o[1] },
            if back { w_o[2] - two_mu * n[2] } else { w_o[2] },
        ];
        let mu = if back { -mu } else { mu };
        // `f32::clamp(mu, 1e-3, 1.0)`.
        let mu = if mu < 1e-3 { 1e-3 } else { mu };
        let mu = if mu > 1.0 { 1.0 } else { mu };
        mu_o[i] = mu;
        let cos_t = (1.0 - (1.0 - mu * mu) / (eta * eta)).max(0.0).sqrt();
        let along = mu / eta - cos_t;
        let wt = normalize_or_zero([
            -w_o[0] / eta + along * n[0],
            -w_o[1] / eta + along * n[1],
            -w_o[2] / eta + along * n[2],
        ]);
        let u = dot(wt, [g.t1[0][i], g.t1[1][i], g.t1[2][i]]) / k.sin_tilt;
        let v = dot(wt, [g.t2[0][i], g.t2[1][i], g.t2[2][i]]) / k.sin_tilt;
        let reach = (u.abs() + v.abs()).max(1.0);
        let (u, v) = (u / reach, v / reach);
        let c = &g.chords;
        let cu = if u >= 0.0 { c[1][i] } else { c[2][i] };
        let cv = if v >= 0.0 { c[3][i] } else { c[4][i] };
        t[i] = c[0][i] * (1.0 - u.abs() - v.abs()) + cu * u.abs() + cv * v.abs();
        for axis in 0..3 {
            w_t[axis][i] = wt[axis];
        }
    }
    (mu_o, w_t, t)
}

/// `glam::Vec3::dot`'s arithmetic.
#[inline(always)]
fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    (a[0] * b[0]) + (a[1] * b[1]) + (a[2] * b[2])
}

/// `glam::Vec3::normalize_or_zero`'s arithmetic.
#[inline(always)]
fn normalize_or_zero(v: [f32; 3]) -> [f32; 3] {
    let rcp = 1.0 / dot(v, v).sqrt();
    // `&`, not `&&`: a select per component, no branch.
    let ok = rcp.is_finite() & (rcp > 0.0);
    [if ok { v[0] * rcp } else { 0.0 }, if ok { v[1] * rcp } else { 0.0 }, if ok { v[2] * rcp } else { 0.0 }]
}

/// [`blocks_seen`] compiled for one instruction set, with fused multiply-adds in the
/// exponentials (the rest has none to fuse: Rust does not contract `a * b + c`).
macro_rules! isa_blocks {
    ($name:ident, $features:literal) => {
        #[cfg(target_arch = "x86_64")]
        mod $name {
            use super::{ENV_MU, EyeConsts, FaceSeen, GeoBlock, LANES, SourceBlock};
            use crate::Rgb;
            use crate::simd::Fused;

            #[target_feature(enable = $features)]
            pub(super) fn blocks_seen(
                k: &EyeConsts,
                geo: &[GeoBlock],
                source: &[SourceBlock],
                env: &[[Rgb; ENV_MU]],
                out: &mut [[FaceSeen; LANES]],
            ) {
                super::blocks_seen::<Fused>(k, geo, source, env, out)
            }
        }
    };
}

isa_blocks!(avx2, "avx2,fma,f16c");
isa_blocks!(avx512, "avx512f,avx512vl,avx2,fma,f16c");

#[cfg(test)]
mod tests {
    use super::*;

    /// A fixed pseudo-random sequence (xorshift) in `[0, 1]`.
    struct Sequence(u32);

    impl Sequence {
        fn next(&mut self) -> f32 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 17;
            self.0 ^= self.0 << 5;
            self.0 as f32 / u32::MAX as f32
        }

        fn unit(&mut self) -> Vec3 {
            Vec3::new(self.next() - 0.5, self.next() - 0.5, self.next() - 0.5).normalize_or(Vec3::Y)
        }
    }

    /// Faces in every orientation about the origin with finite chords, and their terms.
    fn faces(count: usize) -> (Vec<FaceFrame>, Vec<FaceTerms>, Vec<[Rgb; ENV_MU]>) {
        let mut r = Sequence(0x2545_f491);
        let frames: Vec<FaceFrame> = (0..count)
            .map(|_| {
                let n = r.unit();
                let (t1, t2) = n.any_orthonormal_pair();
                let facing = (n + 0.2 * r.unit()).normalize();
                let chords = std::array::from_fn(|k| 0.05 + k as f32 * 0.3 * r.next().powi(3));
                FaceFrame { centroid: n, facing, n, t1, t2, area: 0.01 + r.next(), chords }
            })
            .collect();
        let terms: Vec<FaceTerms> = (0..count)
            .map(|_| {
                let lit = r.next() > 0.2;
                FaceTerms {
                    a: if lit { Rgb::new(r.next(), r.next(), r.next()) } else { Rgb::ZERO },
                    g: std::array::from_fn(|_| r.unit() * 40.0 * r.next()),
                    cap: Rgb::splat(2.0 + r.next()),
                    env_body: Rgb::splat(0.1 * r.next()),
                }
            })
            .collect();
        let env =
            (0..count).map(|_| std::array::from_fn(|k| Rgb::splat(0.05 * k as f32 + r.next()))).collect();
        (frames, terms, env)
    }

    /// Every instruction set this CPU has gives the portable path's values to a few roundings
    /// (they differ only by fused multiply-adds in the exponentials), with and without the
    /// single scattering and the environment; faces turned away give zero.
    #[test]
    fn the_instruction_sets_agree() {
        let (frames, terms, env) = faces(40 * LANES + 5);
        let identity: Vec<u32> = (0..frames.len() as u32).collect();
        let (geo, source, open) = blocks(&frames, &terms, &identity);
        assert!(open.is_empty());
        let k = EyeConsts {
            eye: Vec3::new(3.0, 1.0, -2.0),
            eta: 1.3,
            sin_tilt: 0.5,
            sigma_t: [30.0, 12.0, 4.0],
            albedo_4pi: [0.05, 0.07, 0.079],
            chord: true,
        };
        for (source, env) in [(&source[..], &env[..]), (&source[..], &[][..]), (&[][..], &[][..])] {
            let run = |isa: Isa| {
                let mut out = vec![[FaceSeen::default(); LANES]; geo.len()];
                faces_seen(isa, &k, &geo, source, env, &mut out);
                out
            };
            let portable = run(Isa::Scalar);
            let flat = portable.as_flattened();
            for (f, fr) in frames.iter().enumerate() {
                let away = fr.facing.dot(k.eye - fr.centroid) <= 0.0;
                assert_eq!(away, flat[f].entries() == [0.0; 8], "face {f}");
            }
            assert_eq!(flat.iter().any(|s| s.entries()[4] > 0.0), !source.is_empty());
            for isa in Isa::available() {
                let got = run(isa);
                for (a, b) in got.as_flattened().iter().zip(flat) {
                    for (x, y) in a.entries().iter().zip(b.entries()) {
                        assert!((x - y).abs() <= 2e-6 * y.abs(), "{}: {x} vs {y}", isa.name());
                    }
                }
            }
        }
    }
}
