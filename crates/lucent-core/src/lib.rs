//! # lucent-core
//!
//! The physics and the solvers of lucent, with no GPU dependency. The modules follow the data
//! flow of the homogeneous method (Mertens et al. 2003, "Interactive Rendering of Translucent
//! Deformable Objects"):
//!
//! ```text
//! mesh ──► hierarchy ──► irradiance ──► solver ──► shading ──► (lucent-gpu) image
//!            (§5.1)        (§5.3)      (§3, §5.2, §5.5)  (§5.4)
//!   └──────────────── session: one frame after another (§5.5) ────────────────┘
//! ```
//!
//! * [`bssrdf`]: the dipole diffusion model (Jensen et al. 2001; Mertens table 1), the measured
//!   materials and the dielectric Fresnel terms.
//! * [`camera`]: the orbit camera that frames an object by its bounding sphere (pure math; the
//!   GPU passes, the scene files and the viewer share it).
//! * [`clock`]: wall-clock milliseconds for the stage timings.
//! * [`fastexp`]: inlined, vectorisable exponentials for the hot loops.
//! * [`formfactor`]: the semi-analytic point-to-polygon form factor (Mertens §4) and a Monte Carlo
//!   reference for the same integral.
//! * [`limits`]: what lucent reads from files and the memory it spends decoding them.
//! * [`mesh`]: triangle meshes, file loading and validation, generators and deformers, and the
//!   BVH for ray and closest-point queries.
//! * [`hierarchy`]: face-cluster and subdivision hierarchies (Mertens §5.1).
//! * [`irradiance`]: lights, shadows and spherical-harmonic environment light at the leaves (§5.3).
//! * [`solver`]: the exact O(N^2) reference and the hierarchical solve in its three modes:
//!   oracle, refinement, and each frame's pull, gather and push.
//! * [`session`]: the frame session the CLI, the benches and the viewer drive: it owns the
//!   mesh pose, hierarchy, links, shadow BVH, lights and environment and does the least work
//!   for what changed (§5.5).
//! * [`simd`]: run-time choice of AVX2 / AVX-512 / portable code for the solver's hot kernels.
//! * [`shading`]: exitant radiance `L = F_t B / pi` and the final per-vertex colour (§5.4).
//! * [`volume`]: density volumes for the heterogeneous method (Shopf 2007, §4.2).
//!
//! Units: material coefficients are in mm^-1 as measured; a mesh is given a *model scale* (the
//! largest side of its bounding box in metres) and every length inside the solver is in mesh
//! units, with coefficients converted by [`bssrdf::Profile::new`].

pub mod bssrdf;
pub mod camera;
pub mod clock;
pub mod fastexp;
pub mod formfactor;
pub mod hierarchy;
pub mod irradiance;
pub mod limits;
pub mod mesh;
pub mod session;
pub mod shading;
pub mod simd;
pub mod solver;
pub mod volume;

/// An RGB triple of `f32` (radiance, irradiance or a per-channel coefficient, as documented
/// where it is used).
pub type Rgb = glam::Vec3;
