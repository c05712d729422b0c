//! Wall-clock milliseconds, the unit of every stage time the frame session and the front ends
//! report ([`crate::session::Timings`], the benches, `lucent render`'s per-frame times).

use std::time::Instant;

/// Milliseconds since `t`.
pub fn ms_since(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}
