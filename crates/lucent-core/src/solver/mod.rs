//! Solving `B(x_o) = Σ_k E_k F(A_k, x_o)` (Mertens eq. 6).
//!
//! * [`census`]: counts of the oracle's decisions by cause and of the links by kind, level and
//!   geometry (diagnostic).
//! * [`energy`]: the energy bound that keeps thin and touching parts from glowing.
//! * [`exact`]: every face against every other face, O(N^2): the reference.
//! * [`hierarchical`]: the hierarchical boundary element solve over a mesh hierarchy (§3.2,
//!   §5.5) in on-the-fly, render and incremental modes.
//! * `refine`: its receiver-driven refinement, storing links or handing them to the gather,
//!   and the incremental relink that keeps what did not change (§3.2, §5.5).
//! * `gather`: a frame's pull, gather `Σ E F` and push, over the stored links or during the
//!   on-the-fly traversal (§3.2, §5.5).
//! * `evaluate`: the transport coefficient of an accepted link: one-point estimate, form
//!   factor or cubature (§3.1, §4).
//! * [`link_coef`]: stored link coefficients, 16 bits per channel, and render mode's gather
//!   kernel over them.
//! * [`link_set`]: the stored links, a run per receiver in a shared base or a per-update
//!   delta, so that an incremental update writes only what changed (§5.5).
//! * [`local`]: the profile's reach and the local limit `B = R_d E` where it is below a face.
//! * `near_face`: the receiver's own face and those beside it, in polar coordinates about
//!   the receiver, for the tabulated profile (§4).
//! * [`oracle`]: the refinement oracle (§5.2).
//! * [`point_sample`]: one-point transport estimates, four at a time (§4.2).
//! * [`progress`]: a counter a front end polls to show a long solve's progress.

pub mod census;
pub mod energy;
mod evaluate;
pub mod exact;
pub mod finite_body;
mod gather;
mod gather_linear;
pub mod hierarchical;
pub mod link_coef;
pub mod link_set;
pub mod local;
mod near_face;
pub mod oracle;
mod point_kernel;
#[cfg(target_arch = "x86_64")]
mod point_kernel_avx512;
pub mod point_sample;
pub mod progress;
mod refine;
pub mod transmission;

pub use hierarchical::{HierarchicalSolver, Solution, SolveStats};
pub use link_set::{Link, LinkSet};
pub use oracle::{LinkKind, Oracle};
pub use progress::Progress;
