//! The energy bound on thin and touching parts (not in Mertens et al. 2003; issue "physically
//! right").
//!
//! Diffusion profiles are fitted to a flat, semi-infinite medium. On a thin part, or where two
//! parts nearly touch, a receiver gathers from surfaces on more than one side and the sum of its
//! form factors can exceed what light entering there could possibly give back. Under uniform
//! irradiance 1 on every face, reciprocity makes a face's `B` the share of light entering there
//! that leaves anywhere, which cannot exceed 1. Each face's `B` is therefore scaled, per channel,
//! by `min(1, 1 / U)`, where `U` is its `B` under uniform irradiance 1: where the profile keeps
//! energy (any thick, convex region: `U` is the flat total reflectance there, below 1) nothing
//! changes. `U` is gathered beside `B` (on the fly), or once per link set (render and
//! incremental modes), so the bound costs one extra add per link.

use crate::Rgb;

/// The factor applied to a face's `B` whose `B` under uniform irradiance 1 is `uniform`:
/// `min(1, 1/U)` per channel (1 where `U` is 0 or not finite).
#[inline]
pub fn bound(uniform: Rgb) -> Rgb {
    Rgb::from_array(uniform.to_array().map(|u| if u > 1.0 && u.is_finite() { 1.0 / u } else { 1.0 }))
}
