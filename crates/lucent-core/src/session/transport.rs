//! The material at its size: what decides the diffusion profile of a [`super::FrameSession`].

use crate::bssrdf::{Material, Profile, ProfileKind};
use crate::shading::SingleScattering;
use crate::solver::transmission::Transmission;

/// The material at its size, which together decide the diffusion profile.
#[derive(Clone, Debug, PartialEq)]
pub struct Transport {
    /// Scattering coefficients (mm⁻¹) and relative index of refraction.
    pub material: Material,
    /// Model scale: the rest mesh's largest bounding-box side, metres (> 0).
    pub scale_m: f64,
    /// Diffusion profile (default [`ProfileKind::default`], photon beam diffusion).
    pub profile: ProfileKind,
    /// Where single scattering is computed (default [`SingleScattering::ViewRay`]; the `mertens`
    /// profile has none whatever this says).
    pub single_scattering: SingleScattering,
    /// How light crossing the body to a face on its far side is carried (default
    /// [`Transmission::Curved`]; only the profiles with a finite-body gain have it).
    pub transmission: Transmission,
}

impl Transport {
    /// `material` at `scale_m` metres with the default profile and single scattering.
    pub fn new(material: Material, scale_m: f64) -> Self {
        Transport {
            material,
            scale_m,
            profile: ProfileKind::default(),
            single_scattering: SingleScattering::default(),
            transmission: Transmission::default(),
        }
    }

    /// The shortest reduced mean free path `1 / (sigma_s' + sigma_a)` over the channels, metres.
    pub fn shortest_mean_free_path_m(&self) -> f64 {
        let m = &self.material;
        let sigma_t = (0..3).map(|c| m.sigma_s_prime[c] + m.sigma_a[c]).fold(0.0, f64::max);
        1e-3 / sigma_t
    }

    /// The profile in the units of a mesh whose largest bounding-box side is `extent` mesh
    /// units (tabulated profiles cost tens of milliseconds: made only when this changes).
    pub fn profile_at(&self, extent: f32) -> Profile {
        Profile::at_model_scale(
            &self.material,
            extent as f64,
            self.scale_m,
            self.profile,
            self.single_scattering.in_profile(),
        )
    }

    /// Whether single scattering is integrated along the view ray (needs the eye).
    pub fn single_scattering_along_view(&self) -> bool {
        self.single_scattering == SingleScattering::ViewRay && self.profile.has_single_scattering()
    }
}
