//! The exit of light that crossed the body (issue 50; not in Mertens et al. 2003): flux
//! flowing out through a thin part's face with no source near it leaves forward-peaked. At 6.6
//! mean free paths (3 mm of marble's red) a slab's transmitted multiple scattering is 1.21 times
//! a Lambertian exit's radiance head-on and 0.83 at `μ = 0.45`, where the half-space's multiple
//! scattering, lucent's exit lobe, is 1.04-1.07 head-on (`validation/slab_walk.py lobe`, and
//! the 1D transport solve of `bssrdf::slab`, which tabulates it). Without it a 3 mm marble box
//! lit from behind read 16% dark against the path tracer with `B` right.

use crate::Rgb;
use crate::bssrdf::fresnel_transmittance;
use crate::bssrdf::slab::LobeRow;
use crate::bssrdf::{ExitLobe, Profile};
use crate::mesh::Mesh;
use crate::shading::single_scattering::ViewRay;
use crate::simd::Isa;
use crate::solver::transmission::{CrossBody, Tilt};
use glam::Vec3;
use rayon::prelude::*;

/// What a solve's `B` holds of light that crossed the body, per face, for the way it leaves.
#[derive(Clone, Debug, Default)]
pub(crate) struct Transmitted {
    /// `B` per face (radiosity units).
    pub face_b: Vec<Rgb>,
    /// The transmitted light it holds (`solver::transmission::CrossBody::add`; same units).
    pub sent: Vec<Rgb>,
    /// How the sphere's share of it leaves (`CrossBody::tilts`; empty: normal-centred).
    pub tilts: Vec<Tilt>,
}

/// Per vertex of `shares` (a solve's transmitted light, [`ExitShares`]), what multiplies the
/// diffuse radiance `B / (c π)` for the way the light crossing the body leaves, for a material
/// of relative index `eta`: the share `w` of the vertex's `B` that was transmitted
/// (`sent` over `face_b`, area-weighted over its faces) leaves as a slab's transmitted light
/// does (forward-peaked: 1.2 times a Lambertian exit head-on at 6.6 mean free paths, where
/// the half-space's multiple scattering is 1.04-1.07), the rest as before, times its chord
/// factor `chord`: `(1 - w) C + w p_T(μ_o) / lobe(μ_o)`, with `p_T` the slab's
/// (`bssrdf::slab::SlabTable::lobe_at`) at the vertex's thickness (weighted by the transmitted light) and
/// `lobe` the half-space's exit lobe the mesh pass applies. `rays` are the vertices' view
/// rays (`None`: not seen, `chord` as it is).
///
/// The sphere's share of it (`tilts`: at most the transmitted light, per face) came the short
/// way round rather than through the diameter, and leaves by its own lobe instead, from the
/// sphere walk's two moments there (`bssrdf::sphere_walk::Exits`): the mean normal cosine
/// `μ̄_n` ([`round_lobe_slope`]) and the tilt `μ̄_t`, the flux-weighted mean of `ω_o · t` along the
/// flow (0.05-0.29 from 45 degrees to the terminator), as
/// `1 + β (μ_o - 2/3) + 7.5 μ̄_t μ_o (ω_o · t)` over a Lambertian exit. The tilt term keeps
/// the flux and has that first moment (the `7.5` is `1 / ∫ μ² (ω·t)² dω / π`); the forward walk
/// that scores where each photon leaves (docs/transmission.md) favours it over the plain
/// first-moment lobe `1 + 4 μ̄_t (ω_o · t)`: light that leaves at grazing angles is tilted less
/// (spheres of 2.4 to 15 mean free paths: rms log error of the radiance in 16-32 direction
/// cells 0.08-0.30 against 0.12-0.43, and 0.22-0.63 for no tilt). The moments are
/// area-weighted to the vertices by the share, like `B`. At `η ≠ 1` the moments are the
/// dielectric walk's, of the light refracted out, and the lobe is over the mesh pass's own,
/// `F_t(η, μ_o) T(μ_o) / c` (`bssrdf::exit`), which at `η = 1` is `T(μ_o)`.
pub(crate) fn exit_factors(
    cross: &CrossBody,
    shares: &ExitShares,
    rays: &[Option<ViewRay>],
    eta: f64,
    chord: &[Rgb],
) -> Vec<Rgb> {
    let eta = eta as f32;
    (0..rays.len())
        .into_par_iter()
        .map(|v| {
            let c = chord.get(v).copied().unwrap_or(Rgb::ONE);
            let Some(ray) = &rays[v] else { return c };
            // The light reaches the surface along -w_t and leaves refracted: its tangential
            // part grows by η (Snell), its normal cosine is μ_o.
            let w_in = -ray.w_t;
            let w_o = if eta == 1.0 {
                w_in
            } else {
                (w_in - w_in.dot(ray.normal) * ray.normal) * eta + ray.normal * ray.mu_o
            };
            shares.factor(v, cross, ray.mu_o, w_o, c)
        })
        .collect()
}

/// Vertices per [`ShareBlock`].
const LANES: usize = 16;
/// Vertices per task of a camera move's evaluation ([`ExitShares::draw_split`]); no block
/// holds vertices of two.
const CHUNK: usize = 4096;

/// What [`exit_factors`] needs per vertex that does not depend on the eye (made once per
/// solve; the split view terms evaluate it per eye, [`ExitShares::draw_split`]).
#[derive(Clone, Debug, Default)]
pub(crate) struct ExitShares {
    /// The vertices whose transmitted light changes their factor, sixteen to a block in
    /// ascending order, a block's vertices within one chunk of [`CHUNK`].
    blocks: Vec<ShareBlock>,
    /// Per chunk of [`CHUNK`] vertices, its first block (one entry more than there are chunks).
    chunk_blocks: Vec<u32>,
    /// Per vertex, its lane `block * LANES + lane` (`u32::MAX`: none; its factor is the chord's).
    slot: Vec<u32>,
    /// The mesh pass's exit over a Lambertian one, `F_t(η, μ_o) T(μ_o) / c` (`bssrdf::exit`;
    /// `T` alone at `η = 1`), tabulated once: `c` is an integral and `F_t` costs a square root.
    base: ExitLobe,
}

/// Sixteen vertices' [`VertexShare`]s quantity by quantity, so that a camera move evaluates
/// them as vectors. An empty lane has vertex `u32::MAX`, a zero normal and `keep` 1.
#[derive(Clone, Debug)]
struct ShareBlock {
    /// Each lane's vertex (`u32::MAX`: an empty lane).
    vertex: [u32; LANES],
    /// Positions (mesh units) and unit normals, per axis.
    position: [[f32; LANES]; 3],
    normal: [[f32; LANES]; 3],
    /// [`VertexShare`]'s, per channel (`tilt` per axis, then channel).
    keep: [[f32; LANES]; 3],
    round: [[f32; LANES]; 3],
    round_slope: [[f32; LANES]; 3],
    tilt: [[[f32; LANES]; 3]; 3],
    /// The slab's shares where one lane has one (`None` at `η ≠ 1`, where it is not modelled).
    slab: Option<Box<SlabLanes>>,
}

/// [`VertexShare::slab`] and [`VertexShare::rows`] of a block's lanes, per channel.
#[derive(Clone, Debug, Default)]
struct SlabLanes {
    share: [[f32; LANES]; 3],
    rows: [[LobeRow; LANES]; 3],
}

/// One vertex's transmitted light, area-weighted from its faces, as what its factor over the
/// chord's is made of at an exit cosine `μ_o` toward `ω_o` (every part that no eye changes
/// found once): `keep C + (slab p_T(μ_o) + round + μ_o (round_slope + tilt · ω_o)) / lobe(μ_o)`
/// per channel ([`keep_add`], [`slab_term`]).
#[derive(Clone, Copy, Debug)]
struct VertexShare {
    /// What keeps the chord's factor: the share that did not cross the body, and the slab's
    /// share where its lobe is not modelled (unitless, 0..=1; 1 where `B` is 0).
    keep: Rgb,
    /// The slab's share, which leaves by the slab's lobe read at `rows` (unitless, 0..=1).
    slab: Rgb,
    /// Per channel, where the slab's lobe is read for the thickness under the vertex (weighted
    /// by the transmitted light; unused where `slab` is 0).
    rows: [LobeRow; 3],
    /// The sphere's share times its lobe's constant and `μ_o` terms, `w (1 - 2β/3)` and `w β`
    /// ([`round_lobe_slope`]; unitless).
    round: Rgb,
    round_slope: Rgb,
    /// Its tilt, `7.5 Σ share μ̄_t t / B` per axis (unitless).
    tilt: [Rgb; 3],
    /// The unit vertex normal (zero where none was given).
    normal: Vec3,
}

impl ExitShares {
    /// The shares of `transmitted`'s light at every vertex of `mesh`, with its unit vertex
    /// `normals` for [`ExitShares::draw_split`] (empty: not kept), for `profile`'s exit.
    pub(crate) fn new(
        cross: &CrossBody,
        mesh: &Mesh,
        normals: &[Vec3],
        transmitted: &Transmitted,
        profile: &Profile,
    ) -> Self {
        let Transmitted { face_b, sent, tilts } = transmitted;
        let b_v = mesh.face_to_vertex(face_b);
        let sent_v = mesh.face_to_vertex(sent);
        let weighted: Vec<Rgb> =
            sent.iter().zip(cross.thickness()).map(|(s, &t)| Rgb::splat(s.element_sum() * t)).collect();
        let t_v = mesh.face_to_vertex(&weighted);
        let sum_v =
            mesh.face_to_vertex(&sent.iter().map(|s| Rgb::splat(s.element_sum())).collect::<Vec<_>>());
        // Per face, the sphere's share of the transmitted light (at most all of it).
        let round: Vec<Rgb> = if tilts.len() == sent.len() {
            tilts.iter().zip(sent).map(|(t, s)| t.whole.min(*s).max(Rgb::ZERO)).collect()
        } else {
            Vec::new()
        };
        let round_v = if round.is_empty() { Vec::new() } else { mesh.face_to_vertex(&round) };
        // Per vertex, the share-weighted mean of its exit's normal cosine (times the share).
        let normal_v = if round.is_empty() {
            Vec::new()
        } else {
            mesh.face_to_vertex(&tilts.iter().zip(&round).map(|(t, r)| *r * t.normal).collect::<Vec<_>>())
        };
        // Per vertex and channel, its first moment `Σ share μ̄_t t` (B units), by axis.
        let tilt_v: Option<[Vec<Rgb>; 3]> = (!round.is_empty()).then(|| {
            std::array::from_fn(|axis| {
                let component: Vec<Rgb> =
                    tilts.iter().zip(&round).map(|(t, r)| *r * t.mean * t.along[axis]).collect();
                mesh.face_to_vertex(&component)
            })
        });
        let vertices: Vec<Option<VertexShare>> = (0..mesh.positions.len())
            .into_par_iter()
            .map(|v| {
                let b = b_v[v];
                if sum_v[v].x <= 0.0 || b.max_element() <= 0.0 {
                    return None;
                }
                let per_b = |x: Rgb| {
                    Rgb::from_array(std::array::from_fn(|k| if b[k] > 0.0 { x[k] / b[k] } else { 0.0 }))
                };
                let sent = per_b(sent_v[v]).clamp(Rgb::ZERO, Rgb::ONE);
                let round_sum = round_v.get(v).copied().unwrap_or(Rgb::ZERO);
                let round = per_b(round_sum).clamp(Rgb::ZERO, sent);
                let normal = normal_v.get(v).copied().unwrap_or(Rgb::ZERO);
                let mean_cos = Rgb::from_array(std::array::from_fn(|k| {
                    if round_sum[k] > 0.0 { normal[k] / round_sum[k] } else { 2.0 / 3.0 }
                }));
                let along = tilt_v.as_ref().map_or([Rgb::ZERO; 3], |t| std::array::from_fn(|a| t[a][v]));
                let thickness = t_v[v].x / sum_v[v].x;
                let mut share = VertexShare {
                    keep: Rgb::ONE,
                    slab: Rgb::ZERO,
                    rows: [LobeRow::default(); 3],
                    round: Rgb::ZERO,
                    round_slope: Rgb::ZERO,
                    tilt: [Rgb::ZERO; 3],
                    normal: normals.get(v).copied().unwrap_or(Vec3::ZERO),
                };
                for k in 0..3 {
                    if b[k] <= 0.0 {
                        continue;
                    }
                    let (w, w_round) = (sent[k], round[k]);
                    // The slab's share leaves by the slab's lobe; the sphere's, which came the
                    // short way round rather than through the diameter, by its own: the walk's
                    // two moments there, its mean normal cosine and its tilt.
                    match cross.transmitted_lobe_row(k, thickness) {
                        Some(row) => {
                            share.keep[k] = 1.0 - w;
                            share.slab[k] = w - w_round;
                            share.rows[k] = row;
                        }
                        None => share.keep[k] = 1.0 - w_round,
                    }
                    let beta = round_lobe_slope(mean_cos[k]);
                    share.round[k] = w_round * (1.0 - beta * 2.0 / 3.0);
                    share.round_slope[k] = w_round * beta;
                    for (tilt, along) in share.tilt.iter_mut().zip(&along) {
                        tilt[k] = 7.5 * along[k] / b[k];
                    }
                }
                Some(share)
            })
            .collect();
        let (eta, inv_c) = (profile.eta, profile.exit_normalization());
        let base = if eta == 1.0 {
            profile.exit_lobe.clone()
        } else {
            profile.exit_lobe.times(|mu| (fresnel_transmittance(mu as f64, eta) * inv_c) as f32)
        };
        let (blocks, chunk_blocks, slot) = packed(&vertices, &mesh.positions);
        ExitShares { blocks, chunk_blocks, slot, base }
    }

    /// What multiplies vertex `v`'s diffuse radiance `B / (c π)` seen at the exit cosine `mu_o`
    /// along the unit direction `w_o` outside (toward the eye), given its chord factor `c`: the
    /// non-transmitted share keeps `c`, the slab's share leaves by the slab's lobe, the
    /// sphere's by its own (both over the mesh pass's lobe).
    pub(crate) fn factor(&self, v: usize, cross: &CrossBody, mu_o: f32, w_o: Vec3, c: Rgb) -> Rgb {
        let Some(&s) = self.slot.get(v).filter(|s| **s != u32::MAX) else { return c };
        let (block, i) = (&self.blocks[s as usize / LANES], s as usize % LANES);
        let l = self.base.at(mu_o);
        Rgb::from_array(std::array::from_fn(|k| {
            let (keep, mut add) = keep_add(block, k, i, mu_o, w_o.to_array(), l[k]);
            if let Some(slab) = &block.slab {
                add += slab_term(cross, slab, k, i, mu_o, l[k]);
            }
            (keep * c[k] + add).max(0.0)
        }))
    }

    /// The transmitted light's exit on `radiance` (per vertex, the diffuse radiance `diffuse`
    /// times its chord factor, as the split view terms drew it), seen from `eye` (mesh units):
    /// [`ExitShares::factor`] of each vertex whose transmitted light changes it, the direction
    /// mirrored to the front where the vertex is turned slightly away (as the view rays are).
    /// Vertices turned well away (more than 120 degrees: none of their faces is drawn but in the
    /// sharpest creases) or without a normal are left as drawn.
    /// On `isa` if this CPU has it (they agree to rounding).
    pub(crate) fn draw_split(
        &self,
        isa: Isa,
        eye: Vec3,
        cross: &CrossBody,
        diffuse: &[Rgb],
        radiance: &mut [Rgb],
    ) {
        radiance.par_chunks_mut(CHUNK).enumerate().for_each(|(chunk, out)| {
            let Some(&[first, end]) = self.chunk_blocks.get(chunk..chunk + 2) else { return };
            let seen = Seen { shares: self, eye, cross, diffuse, start: chunk * CHUNK };
            seen.blocks(isa, &self.blocks[first as usize..end as usize], out);
        });
    }
}

/// `vertices`' shares at `positions` as [`ExitShares`] keeps them: those that change a factor
/// in blocks, each chunk's first block, and each vertex's lane.
fn packed(vertices: &[Option<VertexShare>], positions: &[Vec3]) -> (Vec<ShareBlock>, Vec<u32>, Vec<u32>) {
    let per_chunk: Vec<Vec<ShareBlock>> = vertices
        .par_chunks(CHUNK)
        .enumerate()
        .map(|(chunk, shares)| {
            let changing = shares.iter().enumerate().filter_map(|(v, s)| {
                let s = s.as_ref()?;
                let identity = s.keep == Rgb::ONE
                    && s.slab == Rgb::ZERO
                    && s.round == Rgb::ZERO
                    && s.round_slope == Rgb::ZERO
                    && s.tilt == [Rgb::ZERO; 3];
                (!identity).then_some((chunk * CHUNK + v, s))
            });
            let mut blocks: Vec<ShareBlock> = Vec::new();
            for (n, (v, s)) in changing.enumerate() {
                if n % LANES == 0 {
                    blocks.push(ShareBlock::empty());
                }
                blocks.last_mut().expect("pushed").set(n % LANES, v as u32, positions[v], s);
            }
            blocks
        })
        .collect();
    let mut chunk_blocks = vec![0u32];
    let mut blocks = Vec::new();
    for chunk in per_chunk {
        blocks.extend(chunk);
        chunk_blocks.push(blocks.len() as u32);
    }
    let mut slot = vec![u32::MAX; vertices.len()];
    for (b, block) in blocks.iter().enumerate() {
        for (i, &v) in block.vertex.iter().enumerate().filter(|(_, v)| **v != u32::MAX) {
            slot[v as usize] = (b * LANES + i) as u32;
        }
    }
    (blocks, chunk_blocks, slot)
}

/// What [`ExitShares::draw_split`] sees a chunk's blocks with: `diffuse` per vertex, and its
/// output's first vertex `start`.
struct Seen<'a> {
    shares: &'a ExitShares,
    eye: Vec3,
    cross: &'a CrossBody,
    diffuse: &'a [Rgb],
    start: usize,
}

impl Seen<'_> {
    /// `blocks` onto `out` (the chunk's radiance), on `isa` if this CPU has it.
    fn blocks(&self, isa: Isa, blocks: &[ShareBlock], out: &mut [Rgb]) {
        match isa {
            // SAFETY: checked here that this CPU has the instruction set.
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512 if isa.is_available() => unsafe { avx512::blocks(self, blocks, out) },
            // SAFETY: as above.
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 if isa.is_available() => unsafe { avx2::blocks(self, blocks, out) },
            _ => blocks.iter().for_each(|b| self.block(b, out)),
        }
    }

    /// One block, quantity by quantity over its lanes with straight-line arithmetic (a branch
    /// is a select), so that each loop compiles to vector instructions.
    #[inline(always)]
    fn block(&self, block: &ShareBlock, out: &mut [Rgb]) {
        let e = self.eye.to_array();
        let (mut mu_o, mut w_o, mut seen) = ([0.0f32; LANES], [[0.0f32; LANES]; 3], [false; LANES]);
        for i in 0..LANES {
            let to: [f32; 3] = std::array::from_fn(|a| e[a] - block.position[a][i]);
            let rcp = 1.0 / (to[0] * to[0] + to[1] * to[1] + to[2] * to[2]).sqrt();
            let ok = rcp.is_finite() & (rcp > 0.0);
            let n: [f32; 3] = std::array::from_fn(|a| block.normal[a][i]);
            let w: [f32; 3] = std::array::from_fn(|a| if ok { to[a] * rcp } else { 0.0 });
            let mu = n[0] * w[0] + n[1] * w[1] + n[2] * w[2];
            // Turned slightly away: mirrored to the front.
            let mirror = 2.0 * mu.min(0.0);
            for a in 0..3 {
                w_o[a][i] = w[a] - n[a] * mirror;
            }
            mu_o[i] = mu.abs().clamp(1e-3, 1.0);
            seen[i] = (mu >= -0.5) & (n[0] * n[0] + n[1] * n[1] + n[2] * n[2] > 0.0);
        }
        if !seen.contains(&true) {
            return;
        }
        let l = self.shares.base.at_lanes(&mu_o);
        let (mut keep, mut add) = ([[0.0f32; LANES]; 3], [[0.0f32; LANES]; 3]);
        for k in 0..3 {
            for i in 0..LANES {
                let w = [w_o[0][i], w_o[1][i], w_o[2][i]];
                (keep[k][i], add[k][i]) = keep_add(block, k, i, mu_o[i], w, l[k][i]);
            }
        }
        if let Some(slab) = &block.slab {
            for k in 0..3 {
                for i in 0..LANES {
                    add[k][i] += slab_term(self.cross, slab, k, i, mu_o[i], l[k][i]);
                }
            }
        }
        for i in (0..LANES).filter(|&i| seen[i]) {
            let v = block.vertex[i] as usize;
            let (r, d) = (&mut out[v - self.start], self.diffuse[v]);
            *r = Rgb::from_array(std::array::from_fn(|k| (keep[k][i] * r[k] + d[k] * add[k][i]).max(0.0)));
        }
    }
}

/// [`Seen::blocks`] compiled for one instruction set.
macro_rules! isa_blocks {
    ($name:ident, $features:literal) => {
        #[cfg(target_arch = "x86_64")]
        mod $name {
            use super::{Rgb, Seen, ShareBlock};

            #[target_feature(enable = $features)]
            pub(super) fn blocks(seen: &Seen, blocks: &[ShareBlock], out: &mut [Rgb]) {
                blocks.iter().for_each(|b| seen.block(b, out))
            }
        }
    };
}

isa_blocks!(avx2, "avx2,fma,f16c");
isa_blocks!(avx512, "avx512f,avx512vl,avx2,fma,f16c");

impl ShareBlock {
    fn empty() -> Self {
        ShareBlock {
            vertex: [u32::MAX; LANES],
            position: [[0.0; LANES]; 3],
            normal: [[0.0; LANES]; 3],
            keep: [[1.0; LANES]; 3],
            round: [[0.0; LANES]; 3],
            round_slope: [[0.0; LANES]; 3],
            tilt: [[[0.0; LANES]; 3]; 3],
            slab: None,
        }
    }

    /// Lane `i`: vertex `v` at `position` with `share`.
    fn set(&mut self, i: usize, v: u32, position: Vec3, share: &VertexShare) {
        self.vertex[i] = v;
        for a in 0..3 {
            self.position[a][i] = position[a];
            self.normal[a][i] = share.normal[a];
        }
        for k in 0..3 {
            self.keep[k][i] = share.keep[k];
            self.round[k][i] = share.round[k];
            self.round_slope[k][i] = share.round_slope[k];
            for a in 0..3 {
                self.tilt[a][k][i] = share.tilt[a][k];
            }
            if share.slab[k] != 0.0 {
                let slab = self.slab.get_or_insert_with(Default::default);
                slab.share[k][i] = share.slab[k];
                slab.rows[k][i] = share.rows[k];
            }
        }
    }
}

/// Lane `i` of `block` in channel `k` at exit cosine `mu_o` toward the unit direction `w_o`
/// outside, where the mesh pass's lobe is `l`, its slab's share left out ([`slab_term`]): its
/// factor over the chord factor `C` as `keep C + add` (`(keep, add)`).
#[inline(always)]
fn keep_add(block: &ShareBlock, k: usize, i: usize, mu_o: f32, w_o: [f32; 3], l: f32) -> (f32, f32) {
    let tilt = block.tilt[0][k][i] * w_o[0] + block.tilt[1][k][i] * w_o[1] + block.tilt[2][k][i] * w_o[2];
    let lobes = block.round[k][i] + (block.round_slope[k][i] + tilt) * mu_o;
    // Where the mesh pass's lobe vanishes (grazing at `η > 1`) none of it is drawn.
    let drawn = l > 1e-6;
    (if drawn { block.keep[k][i] } else { 1.0 }, if drawn { lobes / l } else { 0.0 })
}

/// What lane `i`'s slab share adds to its `add` ([`keep_add`]) in channel `k`: the slab's
/// lobe over the mesh pass's, `l`, at exit cosine `mu_o`.
#[inline]
fn slab_term(cross: &CrossBody, slab: &SlabLanes, k: usize, i: usize, mu_o: f32, l: f32) -> f32 {
    let share = slab.share[k][i];
    if share != 0.0 && l > 1e-6 {
        share * cross.transmitted_lobe_at(k, slab.rows[k][i], mu_o) / l
    } else {
        0.0
    }
}

/// The slope `β` of a sphere's transmitted light's radiance over a Lambertian exit's,
/// `1 + β (μ_o - 2/3)` at exit cosine `μ_o`, for an exit whose flux-weighted mean cosine is
/// `mean_cos`: the lowest-order lobe with that mean and the same flux (`β = 18 (mean - 2/3)`;
/// Milne's deep half-space, mean 0.711, gives 0.63 at `μ_o = 0.2` and 1.26 head-on, as its `H`
/// function does). `β` is kept to ±1.5, where the lobe stays non-negative.
fn round_lobe_slope(mean_cos: f32) -> f32 {
    (18.0 * (mean_cos - 2.0 / 3.0)).clamp(-1.5, 1.5)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bssrdf::Material;
    use crate::irradiance::ShadowCaster;
    use crate::mesh::generate;
    use crate::session::Transport;
    use crate::solver::finite_body::{FiniteBody, ThicknessRays};
    use crate::solver::transmission::Transmission;

    /// A camera move draws, on every instruction set, each vertex's [`ExitShares::factor`]
    /// (what the traced view terms apply) from the eye's direction: on a skim-milk sphere whose
    /// upper half holds light that crossed, some of it the sphere's, at index 1 (where the
    /// slab's lobe is read) and 1.3 (where it is not).
    #[test]
    fn a_camera_move_draws_each_vertex_factor() {
        let mesh = generate::icosphere(3);
        let normals = mesh.vertex_normals();
        let caster = ShadowCaster::new(&mesh);
        let rays = ThicknessRays::trace(&mesh, caster.bvh(), caster.offset());
        let upper: Vec<bool> = mesh
            .triangles
            .iter()
            .map(|t| t.iter().map(|&v| mesh.positions[v as usize].y).sum::<f32>() > 0.0)
            .collect();
        let face_b = vec![Rgb::new(1.0, 0.8, 0.5); upper.len()];
        let sent: Vec<Rgb> =
            upper.iter().map(|&u| if u { Rgb::new(0.6, 0.5, 0.3) } else { Rgb::ZERO }).collect();
        let tilts = sent
            .iter()
            .map(|s| Tilt {
                along: Vec3::X * 0.8,
                whole: *s * 0.5,
                mean: Rgb::splat(0.2),
                normal: Rgb::splat(0.72),
            })
            .collect();
        let transmitted = Transmitted { face_b, sent, tilts };
        let diffuse: Vec<Rgb> =
            (0..normals.len()).map(|v| Rgb::new(0.3, 0.2, 0.1) * (1.0 + (v % 7) as f32 / 7.0)).collect();
        let chord: Vec<Rgb> = (0..normals.len()).map(|v| Rgb::splat(0.9 + (v % 5) as f32 * 0.05)).collect();
        let drawn: Vec<Rgb> = diffuse.iter().zip(&chord).map(|(d, c)| *d * *c).collect();
        let eye = Vec3::new(0.5, 1.5, 4.0);
        for eta in [1.0, 1.3] {
            let mut milk = Material::by_name("skimmilk").unwrap();
            milk.eta = eta;
            let profile = Transport::new(milk, 0.02).profile_at(mesh.extent());
            let fb = FiniteBody::new(&profile);
            let gains = fb.gains_along(&mesh, &rays, caster.offset());
            let cross =
                CrossBody::new(&profile, &fb, &mesh, &rays, caster.offset(), &gains, Transmission::Curved);
            let shares = ExitShares::new(&cross, &mesh, &normals, &transmitted, &profile);
            assert_eq!(
                shares.blocks.iter().any(|b| b.slab.is_some()),
                eta == 1.0,
                "the slab's lobe at index 1 only"
            );
            let want: Vec<Rgb> = (0..normals.len())
                .map(|v| {
                    let (n, w) = (normals[v], (eye - mesh.positions[v]).normalize());
                    let mu = n.dot(w);
                    if mu < -0.5 {
                        return drawn[v];
                    }
                    let w = w - n * (2.0 * mu.min(0.0));
                    diffuse[v] * shares.factor(v, &cross, mu.abs().clamp(1e-3, 1.0), w, chord[v])
                })
                .collect();
            let changed =
                want.iter().zip(&drawn).filter(|(a, b)| (**a - **b).abs().max_element() > 1e-4).count();
            assert!(changed > normals.len() / 4, "index {eta}: the lobe changes {changed} vertices");
            for isa in Isa::available() {
                let mut got = drawn.clone();
                shares.draw_split(isa, eye, &cross, &diffuse, &mut got);
                for (v, (g, w)) in got.iter().zip(&want).enumerate() {
                    let err = (*g - *w).abs().max_element() / w.max_element().max(1e-6);
                    assert!(err < 1e-5, "index {eta}, {isa:?}, vertex {v}: {g} against {w}");
                }
            }
        }
    }
}
