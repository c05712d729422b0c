//! The diffusion BSSRDF: the dipole of Jensen, Marschner, Levoy & Hanrahan 2001 in the form of
//! Mertens et al. 2003, table 1, its distance form, and photon beam diffusion (Habel et al.
//! 2013), with the measured materials of Jensen et al. 2001 ([`profile`] compares them).
//!
//! In Mertens' placement the real source sits `z_r` below the surface and the virtual source
//! `z_v` *above* it (`x_v = x_i + z_v N_i`, as Mertens writes; the Shopf thesis's table 3.1 has
//! a sign typo).

pub mod beam_diffusion;
mod entry;
mod exit;
mod fresnel;
pub mod halfspace;
mod material;
pub mod profile;
mod quadrature;
pub mod slab;
pub mod slab_oblique;
pub mod slab_spread;
pub mod sphere_forward;
pub mod sphere_table;
pub mod sphere_walk;
pub mod tables;
pub mod walk;

pub use entry::{Entry, EntryParts, zonal_band_weights};
pub use exit::ExitLobe;
pub use fresnel::{
    boundary_a, fresnel_dielectric, fresnel_diffuse_reflectance, fresnel_moment1, fresnel_moment2,
    fresnel_transmittance, refracted_cosine,
};
pub use material::{ALBEDO, MEAN_FREE_PATH_MM, Material, MaterialError, PRESETS, albedo_range};
pub use profile::{Profile, ProfileKind, UnknownProfile};
pub use tables::RadialTable;

#[cfg(test)]
mod tests;
