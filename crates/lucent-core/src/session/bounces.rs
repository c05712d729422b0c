//! The bounces of a [`super::FrameSession`] (`irradiance::interreflection`): the light the
//! subsurface solve sent out, caught by facing parts of the mesh through the air and solved
//! again, a set number of times. The solve is linear in the irradiance, so each bounce reuses
//! the stored links. The bounces after the set number are taken as a geometric series: once
//! the light between parts settles into the bounce operator's slowest mode, each bounce keeps
//! the same share `r` of the last, and all of them together add the last bounce times
//! `r / (1 - r)` ([`tail_ratio`]). A path tracer follows every bounce; cut at three, the
//! 11K Stanford dragon lit from behind left out about 5% of its image (docs/validation.md).

use super::body::Body;
use super::irradiance::Irradiance;
use super::subsurface::Subsurface;
use super::{Changes, Frame, SolveMode, Timings};
use crate::Rgb;
use crate::irradiance::ShadowCaster;
use crate::irradiance::interreflection::{BounceRays, bounced_irradiance_with, hit_weights};
use crate::solver::Oracle;

/// How much looser the oracle's thresholds are for a bounce solved on the fly than for the
/// direct light's solve. The bounce is a few percent of `B` (up to a third in a crevice), so its
/// share of the error stays below the direct solve's: on the 48K Stanford dragon (marble,
/// 10 cm) the image moved by 0.03% at the median pixel, 0.18% at the 99th percentile.
const BOUNCE_ORACLE_SLACK: f32 = 4.0;

/// The largest ratio of one bounce to the one before that [`tail_ratio`] takes: light
/// between parts loses most of itself at each bounce (the Stanford dragons in marble keep
/// 0.3-0.6 of it, lit from the front or behind), and a ratio near 1 would make the tail's `r / (1 - r)` blow up where
/// the estimate is poor.
const TAIL_RATIO_MAX: f32 = 0.8;

/// The rays between parts, kept across frames.
#[derive(Default)]
pub(super) struct Bounces {
    /// The bounce's rays between parts, traced on the first bounce, refitted after small
    /// deformations and traced again after large ones (`BounceRays::fits`).
    rays: Option<BounceRays>,
    /// Whether the mesh moved since `rays` were traced or last refitted.
    moved: bool,
    /// The hits' weights for `rays` under the profile of exit term and refractive index
    /// `key` (`hit_weights`), kept across light moves.
    weights: Option<((f64, f64), Vec<f32>)>,
}

impl Bounces {
    /// Adds to `face_b`, the subsurface solve's `B` of the direct light, the settings' number
    /// of bounces: each one the light the last sent out, caught by facing parts (rays against
    /// the shadow BVH of `irradiance`) and solved by `subsurface` (with the finite-body gain
    /// and the slab transmission of `body`); and to `sent` the transmitted light the bounces
    /// hold (`Body::add_transmission`); then, after two bounces or more, the tail of the
    /// bounces left out (module docs), unless ablated (`--ablate bounce-tail`).
    /// The direct light's single scattering leaves too, but is not bounced: with it the dragon
    /// read +6.5% against the path tracer (validation/README.md, "Single scattering of bounced
    /// light").
    pub(super) fn add(
        &mut self,
        f: &Frame,
        changes: &Changes,
        irradiance: &Irradiance,
        subsurface: &mut Subsurface,
        body: &Body,
        (face_b, sent): (&mut [Rgb], &mut Vec<Rgb>),
    ) {
        self.moved |= changes.geometry;
        let mut last = face_b.to_vec();
        if f.settings.ablate.direct_single_unbounced {
            // The ablation of the exclusion: the direct light's single scattering leaves too.
            irradiance.add_single(f, &mut last, irradiance.faces());
        }
        self.make_rays_current(f, irradiance.caster());
        let oracle = bounce_oracle(f);
        let key = (f.profile.exit_normalization(), f.profile.eta);
        if let Some(rays) = self.rays.as_ref().filter(|_| f.settings.bounces > 0)
            && self.weights.as_ref().is_none_or(|(k, _)| *k != key)
        {
            self.weights = Some((key, hit_weights(rays, &f.profile)));
        }
        // The bounce before the last, and what the last added to `sent`: the tail's ratio.
        let mut before_last: Option<Vec<Rgb>> = None;
        let mut sent_last = Vec::new();
        for bounce in 1..=f.settings.bounces {
            let (Some(rays), Some((_, weights))) = (&self.rays, &self.weights) else { break };
            let e = bounced_irradiance_with(rays, weights, &last, &f.profile);
            let carried = irradiance.carried(&e);
            let mut next =
                subsurface.solve(f, body, &carried, &Changes::default(), oracle, &mut Timings::default()).0;
            // Only the last bounce's share of `sent` is wanted.
            let sent_before = (bounce == f.settings.bounces).then(|| sent.clone());
            body.add_transmission(&mut next, sent, &carried, &e);
            if let Some(before) = sent_before {
                let zeros = std::iter::repeat(&Rgb::ZERO);
                sent_last = sent.iter().zip(before.iter().chain(zeros)).map(|(a, b)| *a - *b).collect();
            }
            irradiance.add_local(f, &mut next, &e);
            // No view ray follows the bounced light: its single scattering joins `B`.
            irradiance.add_single(f, &mut next, &e);
            face_b.iter_mut().zip(&next).for_each(|(b, l)| *b += *l);
            before_last = Some(std::mem::replace(&mut last, next));
        }
        if let Some(before) =
            before_last.filter(|_| f.settings.bounces >= 2 && !f.settings.ablate.bounce_tail)
        {
            let ratio = tail_ratio(&f.mesh, &before, &last);
            let add = |to: &mut [Rgb], from: &[Rgb]| {
                to.iter_mut().zip(from).for_each(|(t, l)| *t += *l * ratio / (Rgb::ONE - ratio));
            };
            add(face_b, &last);
            add(sent, &sent_last);
        }
    }

    /// The rays between parts, made current once for all the bounces of a solve: traced anew
    /// where none fit the mesh and profile, refitted where the mesh moved a little.
    fn make_rays_current(&mut self, f: &Frame, caster: Option<&ShadowCaster>) {
        let Some(caster) = caster.filter(|_| f.settings.bounces > 0) else { return };
        match &mut self.rays {
            Some(rays) if rays.fits(&f.mesh, &f.profile) => {
                if self.moved {
                    rays.refit(&f.mesh, caster);
                    self.weights = None;
                }
            }
            _ => {
                let progress = f.progress.as_deref();
                self.rays = Some(BounceRays::trace(&f.mesh, caster, &f.profile, progress));
                self.weights = None;
            }
        }
        self.moved = false;
    }
}

/// The ratio of the last bounce's light to the one before it, per channel, over the whole
/// mesh (area-weighted `B`), at most [`TAIL_RATIO_MAX`]: what each further bounce keeps of
/// the last once the series settles into its slowest mode (the bounce operator's largest
/// eigenvalue). Summed over every further bounce, the last bounce's light times `r / (1 - r)`
/// is the light a set number of bounces leaves out.
fn tail_ratio(mesh: &crate::mesh::Mesh, before: &[Rgb], last: &[Rgb]) -> Rgb {
    let (mut num, mut den) = (Rgb::ZERO, Rgb::ZERO);
    for (f, (b, l)) in before.iter().zip(last).enumerate() {
        let a = mesh.face_area(f);
        num += *l * a;
        den += *b * a;
    }
    let defined = num.cmpgt(Rgb::ZERO) & den.cmpgt(Rgb::ZERO);
    Rgb::select(defined, (num / den).min(Rgb::splat(TAIL_RATIO_MAX)), Rgb::ZERO)
}

/// The oracle a bounce links with: the session's, looser on the fly, where a bounce links anew
/// and its light is a small part of `B` (stored links are reused as they are).
fn bounce_oracle(f: &Frame) -> Oracle {
    let mut oracle = f.oracle();
    if f.settings.mode == SolveMode::OnTheFly {
        oracle.eps1 *= BOUNCE_ORACLE_SLACK;
        oracle.eps2 *= BOUNCE_ORACLE_SLACK;
        oracle.eps_abs *= BOUNCE_ORACLE_SLACK;
    }
    oracle
}
