//! Solving `B(x_o) = Σ_k E_k F(A_k, x_o)` (Mertens eq. 6).
//!
//! * [`exact`]: every face against every other face, O(N^2): the reference.

pub mod exact;
