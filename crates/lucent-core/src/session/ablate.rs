//! Corrections of the default path switched off one at a time, for measuring what each does
//! against the path tracer (`validation/lucent_validation.py ablate`, docs/corrections.md).
//!
//! Every field is `false` by default, and then nothing here changes a frame. The corrections
//! that already have a setting are ablated through it and are not repeated here: bounces
//! (`--bounces 0`), splitting (`--refine 0`) and view-ray single scattering
//! (`--single-scattering profile`).

use crate::bssrdf::{Entry, EntryParts, Profile};
use crate::solver::finite_body::GainTerms;

/// Which corrections a [`super::FrameSession`] leaves out (all kept by default). The command
/// line's hidden `lucent render --ablate NAME[,NAME]` sets them by [`Ablations::NAMES`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Ablations {
    /// The finite-body gain (`solver::finite_body`): every face's gain 1 (the energy bound
    /// stays).
    pub gain: bool,
    /// The gain's division by the profile's share through a slab-like part, `1 + s X(t)/R_d`.
    pub slab_share: bool,
    /// The gain's per-channel reach factor (the hue a small part's cut takes back).
    pub reach: bool,
    /// The reach factor's division by its mean over the channels (a choice made on the fit
    /// cases): each channel takes its whole factor, light and hue, as the sphere derives it.
    pub reach_division: bool,
    /// The entry term's half-space albedo ratio `A(μ_t)/A(1)` (`bssrdf::Entry`): Fresnel's
    /// transmittance alone, all of it carried by the profile.
    pub entry_ratio: bool,
    /// The entry term's local part: all of `F_t A(μ_t)/A(1)` carried by the profile, none
    /// given back at the entry face.
    pub entry_local: bool,
    /// The exit lobe `T(μ_o)` (`bssrdf::ExitLobe`): a flat lobe on the GPU (the chord keeps the
    /// half-space lobe's weights).
    pub exit_lobe: bool,
    /// The body's chord along the view ray (`shading::exit_chord`): factor 1.
    pub chord: bool,
    /// The environment's shadow by the mesh (lights keep theirs).
    pub env_shadows: bool,
    /// The geometric blend of view-ray single scattering across a face: linear (the mesh
    /// pass, `Solved::linear_single`).
    pub single_blend: bool,
    /// The exclusion of the direct light's single scattering from the bounces (a choice made
    /// on the fit cases, `session/bounces.rs`): with this the first bounce sends it on too.
    pub direct_single_unbounced: bool,
    /// The view ray's light paths taken without a ray where their outcome is certain
    /// (`shading::single_scattering::light_paths`, a shortcut rather than a correction): with this every path is
    /// traced, the reference the shortcut is measured against.
    pub light_paths: bool,
    /// The split view terms' fast exponentials (`shading::view_basis`, a shortcut of a camera
    /// move rather than a correction): with this the C library's, as before issue 51's
    /// camera-move work, the reference the fast ones are measured against.
    pub view_exp: bool,
    /// The bounces' geometric tail (`session/bounces.rs`): with this the series of bounces
    /// stops at the set number, leaving out the light of every further one.
    pub bounce_tail: bool,
    /// The exit lobe of light that crossed a round part (`shading::transmitted_exit`: the
    /// sphere walk's mean normal cosine and tilt): with this it leaves by the slab's
    /// transmitted lobe, centred on the normal.
    pub round_exit: bool,
}

impl Ablations {
    /// The names `--ablate` takes, each with what it switches off.
    pub const NAMES: [(&'static str, &'static str); 15] = [
        ("gain", "the finite-body gain (every face's gain 1)"),
        ("slab-share", "the gain's division by the profile's share through a slab-like part"),
        ("reach", "the gain's per-channel reach factor"),
        ("reach-division", "the reach factor's division by its channel mean: light and hue"),
        ("entry-ratio", "the entry term's albedo ratio A(mu_t)/A(1): Fresnel alone"),
        ("entry-local", "the entry term's local part: all carried by the profile"),
        ("exit-lobe", "the exit lobe T(mu_o): flat"),
        ("chord", "the body's chord along the view ray"),
        ("env-shadows", "the environment's shadow by the mesh"),
        ("single-blend", "the geometric blend of view-ray single scattering: linear"),
        ("unbounced-single", "the direct light's single scattering left out of the bounces: bounced"),
        ("light-paths", "the view ray's light paths taken without a ray where certain: all traced"),
        ("view-exp", "the split view terms' fast exponentials: the C library's"),
        ("bounce-tail", "the bounces' geometric tail: the series cut after the set number"),
        (
            "round-exit",
            "the exit lobe of light that crossed a round part (walked tilt and normal cosine): the slab's",
        ),
    ];

    /// Whether nothing is left out (lucent's default).
    pub fn is_none(&self) -> bool {
        *self == Ablations::default()
    }

    fn flag(&mut self, name: &str) -> Option<&mut bool> {
        Some(match name {
            "gain" => &mut self.gain,
            "slab-share" => &mut self.slab_share,
            "reach" => &mut self.reach,
            "reach-division" => &mut self.reach_division,
            "entry-ratio" => &mut self.entry_ratio,
            "entry-local" => &mut self.entry_local,
            "exit-lobe" => &mut self.exit_lobe,
            "chord" => &mut self.chord,
            "env-shadows" => &mut self.env_shadows,
            "single-blend" => &mut self.single_blend,
            "unbounced-single" => &mut self.direct_single_unbounced,
            "light-paths" => &mut self.light_paths,
            "view-exp" => &mut self.view_exp,
            "bounce-tail" => &mut self.bounce_tail,
            "round-exit" => &mut self.round_exit,
            _ => return None,
        })
    }

    /// The finite-body gain's terms beside the sphere's gain.
    pub fn gain_terms(&self) -> GainTerms {
        GainTerms { slab_share: !self.slab_share, reach: !self.reach, reach_hue_only: !self.reach_division }
    }

    /// `profile` with the entry term's ablated parts left out (unchanged without any, or for a
    /// profile whose entry term is Fresnel's alone).
    pub fn applied(&self, mut profile: Profile) -> Profile {
        let parts = EntryParts { ratio: !self.entry_ratio, local: !self.entry_local };
        if parts != EntryParts::ALL && profile.kind.half_space_boundary() {
            let entry =
                Entry::half_space_parts(&profile.alpha_prime, profile.eta, profile.single_scattering, parts);
            profile.entry = std::sync::Arc::new(entry);
        }
        profile
    }
}

impl std::str::FromStr for Ablations {
    type Err = String;
    /// Comma-separated names of [`Ablations::NAMES`] (case-insensitive), or `none`.
    fn from_str(s: &str) -> Result<Self, String> {
        let mut a = Ablations::default();
        for name in
            s.split(',').map(|n| n.trim().to_ascii_lowercase()).filter(|n| !n.is_empty() && n != "none")
        {
            *a.flag(&name).ok_or_else(|| {
                let names: Vec<_> = Ablations::NAMES.iter().map(|(n, _)| *n).collect();
                format!(
                    "unknown correction {name:?} to ablate; expected none or some of {}",
                    names.join(", ")
                )
            })? = true;
        }
        Ok(a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_and_unknown_ones_are_refused() {
        let a: Ablations = "gain, Chord".parse().unwrap();
        assert!(a.gain && a.chord && !a.reach);
        assert!("none".parse::<Ablations>().unwrap().is_none());
        for (name, _) in Ablations::NAMES {
            assert!(!name.parse::<Ablations>().unwrap().is_none(), "{name}");
        }
        let e = "gian".parse::<Ablations>().unwrap_err();
        assert!(e.contains("\"gian\"") && e.contains("slab-share"), "{e}");
    }

    #[test]
    fn the_entry_ablations_change_the_entry_term_and_nothing_else() {
        use crate::bssrdf::{Material, ProfileKind};
        let p = Profile::of_kind(&Material::by_name("marble").unwrap(), 1.0, ProfileKind::Pbd, false);
        assert_eq!(Ablations::default().applied(p.clone()), p);
        let fresnel = Ablations { entry_ratio: true, ..Default::default() }.applied(p.clone());
        // Fresnel's transmittance alone (the preset's eta, 1.3), in every channel.
        let f_t = Entry::fresnel(p.eta).at(0.3);
        assert!(
            (fresnel.entry.at(0.3) - f_t).abs().max_element() < 1e-6,
            "{} vs {f_t}",
            fresnel.entry.at(0.3)
        );
        assert!(!fresnel.entry.has_local());
        let carried = Ablations { entry_local: true, ..Default::default() }.applied(p.clone());
        assert!(!carried.entry.has_local());
        // All of the ratio is carried: the default's carried and local parts together.
        let sum = p.entry.at(0.3) + p.entry.local_at(0.3);
        assert!((carried.entry.at(0.3) - sum).abs().max_element() < 1e-5);
        assert_eq!(fresnel.exit_lobe, p.exit_lobe);
    }
}
