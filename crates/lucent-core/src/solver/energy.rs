//! Measurements of the energy bound ([`super::bound`]) on whole meshes, on top of the solvers:
//! the largest `B` under uniform irradiance ([`uniform_report`], `lucent bench energy`) and the
//! albedo rendered on a flat slab ([`slab_albedo`], `lucent bench albedo`).

pub use super::bound::{bound, bound_with_gain, bound_with_gain_and_term};
use crate::Rgb;

/// What [`uniform_report`] measures on one mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UniformReport {
    /// Largest `B` over faces and channels under uniform irradiance 1 after the finite-body gain,
    /// the bound and the slab transmission across the body, as a render applies them
    /// (unitless; at most 1 for the bounded profiles).
    pub max_b_uniform: f32,
    /// The same before the bound: how far the profile alone breaks energy conservation.
    pub max_b_unbounded: f32,
    /// Faces whose `B` exceeds 1 before the bound in some channel (those the bound lowers,
    /// where the profile has it on).
    pub faces_bounded: usize,
    /// Faces in the mesh.
    pub faces: usize,
    /// Links of the hierarchical solve.
    pub links: usize,
}

/// Solves `mesh` under uniform irradiance 1 with the hierarchical solver (on the fly) and
/// reports the largest `B` with and without the bound (`lucent bench energy`).
pub fn uniform_report(
    mesh: &crate::mesh::Mesh,
    profile: &crate::bssrdf::Profile,
    oracle: super::Oracle,
) -> UniformReport {
    let h = crate::hierarchy::face_cluster::build(mesh);
    let mut unbounded = profile.clone();
    unbounded.energy_bound = false;
    let ones = vec![Rgb::ONE; mesh.triangles.len()];
    let solver = super::HierarchicalSolver::new(mesh.clone(), h, unbounded, oracle);
    let raw = solver.solve_on_the_fly(&ones);
    let max = |b: &[Rgb]| b.iter().map(|v| v.max_element()).fold(0.0f32, f32::max);
    // As a render does: the finite-body gain of each face, applied with the bound, and the
    // transmission across the body (`super::transmission`, the default mode).
    let mut cross: Option<super::transmission::CrossBody> = None;
    let gain = profile.bounds_energy().then(|| {
        let caster = crate::irradiance::ShadowCaster::new(mesh);
        let fb = super::finite_body::FiniteBody::new(profile);
        let rays = super::finite_body::ThicknessRays::trace(mesh, caster.bvh(), caster.offset());
        let gains = fb.gains_along(mesh, &rays, caster.offset());
        let mode = super::transmission::Transmission::default();
        cross = Some(super::transmission::CrossBody::new(
            profile,
            &fb,
            mesh,
            &rays,
            caster.offset(),
            &gains,
            mode,
        ));
        gains
    });
    let mut bounded: Vec<Rgb> = raw
        .face_b
        .iter()
        .enumerate()
        .map(|(f, &u)| match (&gain, &cross) {
            (Some(g), Some(c)) => u * bound_with_gain_and_term(u, g[f], c.uniform_term(f)),
            (Some(g), None) => u * bound_with_gain(u, g[f]),
            _ => u,
        })
        .collect();
    if let Some(cross) = cross {
        cross.add(&mut bounded, &mut vec![Rgb::ZERO; ones.len()], &ones, None);
    }
    UniformReport {
        max_b_uniform: max(&bounded),
        max_b_unbounded: max(&raw.face_b),
        faces_bounded: raw.face_b.iter().filter(|u| u.max_element() > 1.0).count(),
        faces: mesh.triangles.len(),
        links: raw.stats.links,
    }
}

/// What [`slab_albedo`] measured.
#[derive(Clone, Copy, Debug)]
pub struct SlabAlbedo {
    /// Mean `B` of the top faces within a tenth of the side of the centre, under transmitted
    /// irradiance 1 on the top: the albedo lucent renders (unitless, per channel).
    pub rendered: Rgb,
    /// The slab's side, mm.
    pub side_mm: f64,
    /// Triangles of the slab mesh.
    pub triangles: usize,
}

/// Which solver [`slab_albedo`] uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SlabSolver {
    /// The hierarchical solve on the fly with the profile's default oracle
    /// ([`super::Oracle::for_profile`]): what `lucent render` does.
    Hierarchical,
    /// The O(N²) reference ([`super::exact`]): every form factor integrated exactly, so the
    /// result does not depend on the tessellation, and a coarse slab suffices.
    Exact,
}

/// The albedo lucent renders for `material` on a flat slab (issue "Materials the way artists
/// give them"): a square slab, its side 40 diffusion lengths `1 / sigma_tr` of the slowest
/// channel and at least 200 mean free paths, a quarter as thick, `subdivisions^2` squares per
/// side, lit with transmitted irradiance 1 on its top, solved by `solver` with the default
/// profile ([`crate::bssrdf::ProfileKind::default`]).
///
/// With [`SlabSolver::Exact`] it measures the inversion and the profile's table (0.001% on the
/// grid of `lucent bench albedo`); the hierarchical solve adds the error of its far links, a
/// one-point estimate `A R(d)` of a convex, decaying profile, which is always low (Jensen's
/// inequality): -0.3% at worst with 48² squares a side, less on coarser slabs.
pub fn slab_albedo(material: &crate::bssrdf::Material, subdivisions: u32, solver: SlabSolver) -> SlabAlbedo {
    use crate::bssrdf::{Profile, ProfileKind};
    let mut mesh = crate::mesh::generate::cube(subdivisions);
    for p in &mut mesh.positions {
        p.y *= 0.25;
    }
    let reach_mm = (0..3)
        .map(|c| {
            let (s, a) = (material.sigma_s_prime[c], material.sigma_a[c]);
            let sigma_tr = (3.0 * a * (s + a)).sqrt();
            (40.0 / sigma_tr).max(200.0 / (s + a))
        })
        .fold(0.0, f64::max);
    let kind = ProfileKind::default();
    let profile = Profile::at_model_scale(
        material,
        mesh.extent() as f64,
        reach_mm / 1000.0,
        kind,
        kind.has_single_scattering(),
    );
    let top: Vec<bool> = (0..mesh.triangles.len()).map(|f| mesh.face_normal(f).y > 0.99).collect();
    let irradiance: Vec<Rgb> = top.iter().map(|&t| if t { Rgb::ONE } else { Rgb::ZERO }).collect();
    let b = match solver {
        SlabSolver::Exact => super::exact::solve(&mesh, &profile, &irradiance, &Default::default()),
        SlabSolver::Hierarchical => {
            let h = crate::hierarchy::face_cluster::build(&mesh);
            let oracle = super::Oracle::for_profile(kind);
            super::HierarchicalSolver::new(mesh.clone(), h, profile, oracle)
                .solve_on_the_fly(&irradiance)
                .face_b
        }
    };
    let (mut sum, mut n) = (Rgb::ZERO, 0);
    for (f, &t) in top.iter().enumerate() {
        let c = mesh.face_centroid(f);
        if t && c.x.abs() < 0.1 && c.z.abs() < 0.1 {
            sum += b[f];
            n += 1;
        }
    }
    SlabAlbedo { rendered: sum / n.max(1) as f32, side_mm: reach_mm, triangles: mesh.triangles.len() }
}
