//! Solving `B(x_o) = Σ_k E_k F(A_k, x_o)` (Mertens eq. 6).
//!
//! * [`energy`]: the energy bound that keeps thin and touching parts from glowing.
//! * [`exact`]: every face against every other face, O(N^2): the reference.
//! * [`hierarchical`]: the hierarchical boundary element solve over a mesh hierarchy (§3.2,
//!   §5.5) in on-the-fly, render and incremental modes.
//! * [`link_coef`]: stored link coefficients, 16 bits per channel, and render mode's gather
//!   over them.
//! * [`link_set`]: the stored links, a run per receiver in a shared base or a per-update
//!   delta, so that an incremental update writes only what changed (§5.5).
//! * [`oracle`]: the refinement oracle (§5.2) and the per-link evaluation.
//! * [`point_sample`]: one-point transport estimates, four at a time (§4.2).

pub mod energy;
pub mod exact;
pub mod hierarchical;
pub mod link_coef;
pub mod link_set;
pub mod oracle;
pub mod point_sample;

pub use hierarchical::{HierarchicalSolver, Solution, SolveStats};
pub use link_set::{Link, LinkSet};
pub use oracle::{LinkKind, Oracle};
