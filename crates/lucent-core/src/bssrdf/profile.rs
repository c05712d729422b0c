//! Diffusion profiles: which radial function `R(r)` carries light from where it enters to where
//! it leaves ([`ProfileKind`], the list of names and everything that differs between them), and
//! [`Profile`], one material's profile at one model scale.
//!
//! Three profiles, each a radial function of the distance `r = |x_o - x_i|` between entry and
//! exit points together with its radial tail integral `Q(r) = ∫_r^∞ R(t) t dt` (the form factor
//! of Mertens §4 needs only `Q`: over a polygon, `∫_A R = Σ_e Δθ_e Q(h) - ∫_∂A Q(s(θ)) dθ`):
//!
//! * [`ProfileKind::Mertens`]: the dipole as Mertens et al. 2003 (table 1) place it, on the
//!   *normal* of the point the dipole sits at. Kept to reproduce the paper's tables; on parts
//!   thinner than `z_r` its real source lies beyond the far wall and form factors exceed 1.
//! * [`ProfileKind::Dipole`]: the classic dipole in Jensen et al. 2001's distance form,
//!   `d_r = √(r² + z_r²)`, `d_v = √(r² + z_v²)`: bounded everywhere, normal-free.
//! * [`ProfileKind::Pbd`]: photon beam diffusion (Habel, Christensen & Jarosz 2013), evaluated
//!   per channel on the radial grid of [`RadialTable`] ([`super::beam_diffusion`]), multiple
//!   plus single scattering.
//!
//! Single scattering: PBD's single-scattering term, tabulated likewise, is part of the `pbd`
//! profile and may be added to the `dipole` profile ([`super::Profile::single_scattering`]).

use super::{Entry, ExitLobe, Material, boundary_a, fresnel_moment1, tables};

/// Which diffusion profile a [`super::Profile`] evaluates.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum ProfileKind {
    /// Mertens et al. 2003's dipole on the receiver's normal (the paper's model).
    Mertens,
    /// Jensen et al. 2001's dipole in distance form (bounded, no normals).
    Dipole,
    /// Photon beam diffusion (Habel et al. 2013), tabulated per channel (the default).
    #[default]
    Pbd,
}

impl ProfileKind {
    /// Every profile, in the order the CLI lists them.
    pub const ALL: [ProfileKind; 3] = [ProfileKind::Mertens, ProfileKind::Dipole, ProfileKind::Pbd];

    /// The name used by `--profile` and scene files.
    pub fn name(self) -> &'static str {
        match self {
            ProfileKind::Mertens => "mertens",
            ProfileKind::Dipole => "dipole",
            ProfileKind::Pbd => "pbd",
        }
    }

    /// Whether `R` depends on the normal at the dipole's point (only Mertens' placement does:
    /// its poles sit on the receiver's normal; the others are functions of distance alone).
    pub fn uses_normals(self) -> bool {
        self == ProfileKind::Mertens
    }

    /// Whether the profile has a single-scattering term, on unless asked otherwise (`pbd` and
    /// `dipole`; the paper's `mertens` reproduces its tables without it).
    pub fn has_single_scattering(self) -> bool {
        self != ProfileKind::Mertens
    }

    /// Whether solves bound each face's `B` under uniform irradiance by 1 (the energy bound of
    /// [`crate::solver::energy`]) and apply the finite-body gain. Off for `mertens`, kept as
    /// published to reproduce the paper's tables.
    pub fn bounds_energy(self) -> bool {
        self != ProfileKind::Mertens
    }

    /// Whether light enters and leaves through the exact half-space's boundary terms (the
    /// entry term's albedo ratio, the exit lobe, the exit normalisation `1 / c`), or through
    /// Fresnel's transmittance alone and `F_t B / π` as Mertens et al. write it.
    pub fn half_space_boundary(self) -> bool {
        self != ProfileKind::Mertens
    }

    /// Whether light bounces between facing parts by default. Not for `mertens`, which does not
    /// bound energy on thin parts: bounces would carry that glow on.
    pub fn bounces_by_default(self) -> bool {
        self != ProfileKind::Mertens
    }

    /// The refinement oracle's thresholds `(ε1, ε2, ε_abs)` that keep this profile within 1% of
    /// the exact solve (see [`crate::solver::Oracle::for_profile`]); `None`: the oracle's
    /// defaults, the paper's.
    pub fn oracle_thresholds(self) -> Option<(f32, f32, f32)> {
        match self {
            ProfileKind::Mertens => None,
            ProfileKind::Dipole => Some((0.1, 0.03, 3e-4)),
            ProfileKind::Pbd => Some((0.3, 0.1, 5e-4)),
        }
    }
}

impl std::fmt::Display for ProfileKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A profile name that does not exist.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error("unknown diffusion profile '{0}'; expected one of: mertens, dipole, pbd")]
pub struct UnknownProfile(pub String);

impl std::str::FromStr for ProfileKind {
    type Err = UnknownProfile;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let want = s.trim().to_ascii_lowercase();
        ProfileKind::ALL.into_iter().find(|k| k.name() == want).ok_or_else(|| UnknownProfile(s.to_string()))
    }
}

/// The diffusion profile of one material at one model scale, per colour channel, with every
/// length in *mesh units* (coefficients are measured in mm^-1 and converted by `mm_per_unit`).
/// The dipole's coefficients are kept for every profile: they set the length scales the
/// solver's oracle and the form factor's segmentation use.
#[derive(Clone, Debug, PartialEq)]
pub struct Profile {
    /// Effective transport coefficient `sigma_tr = sqrt(3 sigma_a sigma_t')`, per mesh unit.
    pub sigma_tr: [f64; 3],
    /// Depth of the real source below the surface, `z_r = 1 / sigma_t'`, in mesh units.
    pub z_r: [f64; 3],
    /// Height of the virtual source above the surface, `z_v = z_r (1 + 4A/3)`, in mesh units.
    pub z_v: [f64; 3],
    /// Reduced albedo `alpha' = sigma_s' / sigma_t'` (unitless, 0..1).
    pub alpha_prime: [f64; 3],
    /// Relative index of refraction of the material (unitless, > 0; 1.3 for the measured table).
    pub eta: f64,
    /// How many millimetres one mesh unit stands for.
    pub mm_per_unit: f64,
    /// Which radial profile `R` is (default for [`Profile::new`]: [`ProfileKind::Mertens`], the
    /// paper's; front ends default to [`ProfileKind::default`]).
    pub kind: ProfileKind,
    /// Whether the single-scattering term is included (tabulated, see [`profile`]). Always
    /// `false` for [`ProfileKind::Mertens`].
    pub single_scattering: bool,
    /// Extinction coefficient `σ_t = σ_a + σ_s'` per channel, per mesh unit.
    pub sigma_t: [f64; 3],
    /// The tabulated part of the profile, per channel, if any (PBD; the single-scattering
    /// term of the distance-form dipole).
    pub tables: Option<tables::SharedTables>,
    /// Whether solves scale each face's `B` so that uniform irradiance never gives more than 1
    /// ([`crate::solver::energy`]). Default: on for every profile but Mertens', which is kept
    /// as published to reproduce the paper's tables.
    pub energy_bound: bool,
    /// How much of the light arriving from each direction enters and is carried by the profile:
    /// Fresnel's transmittance for [`ProfileKind::Mertens`] (the paper's), times the exact
    /// half-space albedo ratio `A(μ_t) / A(1)` for the others ([`Entry`]). Shared.
    pub entry: std::sync::Arc<Entry>,
    /// How the diffuse light leaves over exit angles: flat for [`ProfileKind::Mertens`] (the
    /// paper's `F_t B / π`), the half-space's lobe for light entering head-on for the others
    /// ([`ExitLobe`]).
    pub exit_lobe: ExitLobe,
}

impl Profile {
    /// Mertens' dipole for `material` when one mesh unit is `mm_per_unit` millimetres (the
    /// paper's model; see [`Profile::of_kind`] for the others).
    pub fn new(material: &Material, mm_per_unit: f64) -> Self {
        Self::of_kind(material, mm_per_unit, ProfileKind::Mertens, false)
    }

    /// Profile `kind` for `material` when one mesh unit is `mm_per_unit` millimetres, with or
    /// without single scattering (ignored for [`ProfileKind::Mertens`]). Tabulated profiles
    /// cost a table per distinct `eta` once (shared) and three channel tables here.
    pub fn of_kind(
        material: &Material,
        mm_per_unit: f64,
        kind: ProfileKind,
        single_scattering: bool,
    ) -> Self {
        let a = boundary_a(material.eta);
        let mut d = Profile {
            sigma_tr: [0.0; 3],
            z_r: [0.0; 3],
            z_v: [0.0; 3],
            alpha_prime: [0.0; 3],
            eta: material.eta,
            mm_per_unit,
            kind,
            single_scattering: single_scattering && kind.has_single_scattering(),
            sigma_t: [0.0; 3],
            tables: None,
            energy_bound: kind.bounds_energy(),
            entry: std::sync::Arc::new(Entry::fresnel(material.eta)),
            exit_lobe: ExitLobe::flat(),
        };
        for c in 0..3 {
            let sigma_a = material.sigma_a[c] * mm_per_unit;
            let sigma_s = material.sigma_s_prime[c] * mm_per_unit;
            let sigma_t = sigma_a + sigma_s;
            d.sigma_tr[c] = (3.0 * sigma_a * sigma_t).sqrt();
            d.z_r[c] = 1.0 / sigma_t;
            d.z_v[c] = d.z_r[c] * (1.0 + 4.0 * a / 3.0);
            d.alpha_prime[c] = sigma_s / sigma_t;
            d.sigma_t[c] = sigma_t;
        }
        let multiple = kind == ProfileKind::Pbd;
        if multiple || d.single_scattering {
            d.tables = Some(tables::channel_tables(
                &d.alpha_prime,
                &d.sigma_t,
                d.eta,
                multiple,
                d.single_scattering,
            ));
        }
        if kind.half_space_boundary() {
            d.entry = std::sync::Arc::new(Entry::half_space(&d.alpha_prime, d.eta, d.single_scattering));
            d.exit_lobe = ExitLobe::half_space(&d.alpha_prime, d.eta, d.single_scattering);
        }
        d
    }

    /// Dipole coefficients for a mesh whose bounding box's largest side (`extent`, in mesh
    /// units) is `scale_m` metres, as in the paper's "marble scaled at 10 cm".
    pub fn for_model_scale(material: &Material, extent: f64, scale_m: f64) -> Self {
        Self::new(material, scale_m * 1000.0 / extent)
    }

    /// [`Profile::of_kind`] at a model scale (see [`Profile::for_model_scale`]).
    pub fn at_model_scale(
        material: &Material,
        extent: f64,
        scale_m: f64,
        kind: ProfileKind,
        single_scattering: bool,
    ) -> Self {
        Self::of_kind(material, scale_m * 1000.0 / extent, kind, single_scattering)
    }

    /// Whether solves apply the energy bound of [`crate::solver::energy`] ([`Profile::energy_bound`]).
    #[inline]
    pub fn bounds_energy(&self) -> bool {
        self.energy_bound
    }

    /// Whether the analytic dipole terms are part of the profile (all but PBD).
    #[inline]
    pub fn has_analytic(&self) -> bool {
        self.kind != ProfileKind::Pbd
    }

    /// `R` at distance `r` (mesh units) in the plane of the entry point, per mesh unit^2. For
    /// the distance-form profiles this is the whole profile.
    pub fn rd_planar(&self, r: f64) -> [f64; 3] {
        std::array::from_fn(|c| {
            let mut v = 0.0;
            if self.has_analytic() {
                let (zr, zv) = (self.z_r[c], self.z_v[c]);
                let s_r = (r * r + zr * zr).sqrt();
                let s_v = (r * r + zv * zv).sqrt();
                v += self.rd_from_distances(c, s_r, s_v);
            }
            if let Some(t) = &self.tables {
                v += t.channels[c].radial(r);
            }
            v
        })
    }

    /// `R(x_i, x_o)` between an entry point `x_i` with unit normal `n_i` (where Mertens'
    /// dipole sits, table 1) and an exit point `x_o`. The distance-form profiles ignore `n_i`.
    pub fn rd(&self, x_i: glam::DVec3, n_i: glam::DVec3, x_o: glam::DVec3) -> [f64; 3] {
        if !self.kind.uses_normals() {
            return self.rd_planar(x_i.distance(x_o));
        }
        std::array::from_fn(|c| {
            let s_r = (x_i - self.z_r[c] * n_i - x_o).length();
            let s_v = (x_i + self.z_v[c] * n_i - x_o).length();
            self.rd_from_distances(c, s_r, s_v)
        })
    }

    /// The analytic dipole's `R_d` in channel `c` from the distances to the real (`s_r`) and
    /// virtual (`s_v`) sources.
    #[inline]
    pub fn rd_from_distances(&self, c: usize, s_r: f64, s_v: f64) -> f64 {
        let sigma = self.sigma_tr[c];
        let term = |z: f64, s: f64| z * (1.0 + sigma * s) * (-sigma * s).exp() / (s * s * s);
        self.alpha_prime[c] / (4.0 * std::f64::consts::PI) * (term(self.z_r[c], s_r) + term(self.z_v[c], s_v))
    }

    /// Distance (mesh units) from `p` to the nearest point where `R` peaks, per channel, for the
    /// dipole at `x_o` with normal `n_o`: the nearer of Mertens' two sources, or for the
    /// distance-form profiles `√(|p - x_o|² + z_r²)` (their `R` is smooth on the scale `z_r`).
    #[inline]
    pub fn peak_distance(&self, x_o: glam::DVec3, n_o: glam::DVec3, p: glam::DVec3) -> [f64; 3] {
        std::array::from_fn(|c| {
            if self.kind.uses_normals() {
                let s_r = (x_o - self.z_r[c] * n_o - p).length();
                let s_v = (x_o + self.z_v[c] * n_o - p).length();
                s_r.min(s_v)
            } else if self.tables.is_some() {
                // A table with single scattering peaks like 1/r at the entry point.
                (p.distance_squared(x_o) + 0.01 * self.z_r[c] * self.z_r[c]).sqrt()
            } else {
                (p.distance_squared(x_o) + self.z_r[c] * self.z_r[c]).sqrt()
            }
        })
    }

    /// Whether a sphere (`centre`, `radius`, mesh units) lies so far from the dipole at `x_o`
    /// (normal `n_o`) that `R` over it is below `e^{-60}` of its peak (beyond the tables'
    /// reach, for tabulated parts).
    pub fn out_of_reach(&self, x_o: glam::DVec3, n_o: glam::DVec3, centre: glam::DVec3, radius: f64) -> bool {
        let s = self.peak_distance(x_o, n_o, centre);
        (0..3).all(|c| {
            let analytic_far = !self.has_analytic() || self.sigma_tr[c] * (s[c] - radius) > 60.0;
            let table_far =
                self.tables.as_ref().is_none_or(|t| x_o.distance(centre) - radius > t.channels[c].r_max);
            analytic_far && table_far
        })
    }

    /// Total diffuse reflectance `∫ R dA` over an infinite plane, per channel, unitless 0..1:
    /// for the dipoles the closed form of Jensen et al. 2001 (eq. 6), plus the tabulated
    /// single-scattering total where included; for PBD its table's effective albedo.
    pub fn total_diffuse_reflectance(&self) -> [f64; 3] {
        let a = boundary_a(self.eta);
        std::array::from_fn(|c| {
            let mut total = 0.0;
            if self.has_analytic() {
                let ap = self.alpha_prime[c];
                let k = (3.0 * (1.0 - ap)).sqrt();
                total += 0.5 * ap * (1.0 + (-(4.0 / 3.0) * a * k).exp()) * (-k).exp();
            }
            if let Some(t) = &self.tables {
                total += t.channels[c].total();
            }
            total
        })
    }

    /// `∫ R dA` over a whole plane parallel to the entry point's and `t` mesh units from it, per
    /// channel, unitless: what a distance-form profile carries through a slab of thickness `t`
    /// to its far side under uniform light there (`t = 0`: [`Profile::total_diffuse_reflectance`]).
    /// The profile's tail at `t`: `2π Q(t)`, for each pole `α'/2 · z e^{-σ_tr s}/s` at
    /// `s = √(t² + z²)`. [`ProfileKind::Mertens`], whose poles sit on the normal, is taken in the
    /// distance form.
    pub fn plane_reflectance(&self, t: f64) -> [f64; 3] {
        std::array::from_fn(|c| {
            let mut total = 0.0;
            if self.has_analytic() {
                let pole = |z: f64| {
                    let s = (t * t + z * z).sqrt();
                    z * (-self.sigma_tr[c] * s).exp() / s
                };
                total += 0.5 * self.alpha_prime[c] * (pole(self.z_r[c]) + pole(self.z_v[c]));
            }
            if let Some(tables) = &self.tables {
                total += std::f64::consts::TAU * tables.channels[c].tail(t);
            }
            total
        })
    }

    /// The factor `1 / c`, `c = 1 - 2 FM_1(1/η)`, that normalises the exit term `F_t(η, ω_o) /
    /// (c π)` so that it integrates to 1 over the hemisphere (pbrt-v3's separable BSSRDF).
    /// 1 at `η = 1`, and 1 for [`ProfileKind::Mertens`], which keeps the paper's `F_t / π`.
    /// Applied to `B` by [`crate::shading`].
    pub fn exit_normalization(&self) -> f64 {
        if !self.kind.half_space_boundary() {
            return 1.0;
        }
        1.0 / (1.0 - 2.0 * fresnel_moment1(1.0 / self.eta))
    }
}
