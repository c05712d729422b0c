//! Solving `B(x_o) = Σ_k E_k F(A_k, x_o)` (Mertens et al. 2003, eq. 6), as stages whose imports
//! point one way, from the kernels up (`scripts/check_layout.py` checks that no two modules
//! import each other, at any depth):
//!
//! 1. **Kernels**, which know nothing of the hierarchy's links:
//!    * [`point_sample`]: one-point transport estimates `A R_d`, four at a time, and the
//!      seven-point cubature, on the widest instruction set the CPU has (§4.2).
//!    * `near_face`: the receiver's own face and those beside it, in polar coordinates about
//!      the receiver, for tabulated profiles (§4).
//!    * [`link_coef`]: a link's coefficient packed in 16 bits a channel, and render mode's
//!      gather kernel over packed links (§5.5).
//!    * [`local`]: the profile's reach and the local limit `B = R_d E` where it is below a
//!      face; [`bound`]: the energy bound that keeps thin and touching parts from glowing;
//!      [`finite_body`]: the gain of a finite body over the half-space profile, with the rays
//!      that measure the body under each face.
//! 2. **The oracle decides** ([`oracle`], §5.2): for a candidate pair, link it (and how:
//!    [`LinkKind`]) or open the receiver or the emitter.
//! 3. **Evaluation** (`evaluate`, §3.1, §4): the transport coefficient of an accepted link:
//!    one-point estimate, the semi-analytic form factor of [`crate::formfactor`], cubature over
//!    pieces, or the polar rule.
//! 4. **The link set stores** ([`link_set`], §5.5): a run of links per receiver, in a base
//!    shared between updates and a per-update delta, so an incremental update writes only what
//!    changed.
//! 5. **The solver** ([`hierarchical`], §3.2, §5.5), its `impl` in one folder: the
//!    [`HierarchicalSolver`] and its entry points in on-the-fly, render and incremental modes;
//!    linking (`hierarchical::link`: the receiver-driven refinement and the incremental relink
//!    that keeps what did not change); a frame's pull, gather `Σ E F` and push
//!    (`hierarchical::gather`, with the receiver expansion of `hierarchical::expansion`); and
//!    the [`census`] of the oracle's decisions and the links (diagnostic).
//! 6. **On top**: [`exact`], every face against every other face, O(N²), the reference; and
//!    [`energy`], the energy bound measured on whole meshes (`lucent bench energy`, `albedo`).
//!
//! [`Progress`] (a counter a front end polls) lives in [`crate::progress`] and is re-exported
//! here.

pub mod bound;
pub mod cross_spread;
pub mod energy;
mod evaluate;
pub mod exact;
pub mod finite_body;
pub mod hierarchical;
pub mod link_coef;
pub mod link_set;
pub mod local;
mod near_face;
pub mod oracle;
pub mod point_sample;
mod sphere_term;
pub mod transmission;

pub use crate::progress::Progress;
pub use hierarchical::census;
pub use hierarchical::{HierarchicalSolver, RefitOptions, RefitStats, Solution, SolveStats};
pub use link_set::{Link, LinkSet};
pub use oracle::{LinkKind, Oracle};
