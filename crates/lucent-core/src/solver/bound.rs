//! The energy bound on thin and touching parts (not in Mertens et al. 2003; issue "physically
//! right").
//!
//! Diffusion profiles are fitted to a flat, semi-infinite medium. On a thin part, or where two
//! parts nearly touch, a receiver gathers from surfaces on more than one side and the sum of its
//! form factors can exceed what light entering there could possibly give back. Under uniform
//! irradiance 1 on every face, reciprocity makes a face's `B` the share of light entering there
//! that leaves anywhere, which cannot exceed 1. Each face's `B` is therefore scaled by
//! `min(1, 1 / max U)`, where `U` is its `B` under uniform irradiance 1 and the maximum is over
//! the channels: where the profile keeps energy (any thick, convex region: `U` is the flat
//! total reflectance there, below 1) nothing changes. `U` is gathered beside `B` (on the fly),
//! or once per link set (render and incremental modes), so the bound costs one extra add per
//! link.
//!
//! One factor for all three channels, not `min(1, 1/U)` per channel: the excess is the far
//! field gathered through the part, which is redder than the light a lit face gathers near
//! itself, so a per-channel bound takes most from red and tints lit thin parts blue. Under
//! uniform light a thin part then keeps the hue its profile gives (the worst channel at 1)
//! rather than turning white.
//!
//! [`super::energy`] measures the bound on whole meshes, on top of the solvers.

use crate::Rgb;

/// The factor applied to a face's `B` whose `B` under uniform irradiance 1 is `uniform`:
/// `min(1, 1/U)` for the largest finite channel of `U`, the same in all three channels.
#[inline]
pub fn bound(uniform: Rgb) -> Rgb {
    let worst = uniform.to_array().into_iter().filter(|u| u.is_finite()).fold(0.0, f32::max);
    Rgb::splat(if worst > 1.0 { 1.0 / worst } else { 1.0 })
}

/// [`bound`] for a face whose `B` is multiplied by the finite-body gain `gain`
/// ([`super::finite_body::FiniteBody::face_gain`]): `gain min(1, 1/max_c(U_c gain_c))`, so
/// that `B` under uniform irradiance still does not exceed 1.
///
/// The gain is one factor for all channels but for the hue a small part's cut takes from the
/// farthest-reaching channel (the reach factor, which leaves the light alone): the walked gain
/// differs between channels only where the sphere is a few mean free paths across, and a gain
/// per channel runs blue above red there, tinting lit thin parts blue.
#[inline]
pub fn bound_with_gain(uniform: Rgb, gain: Rgb) -> Rgb {
    gain * bound(uniform * gain)
}

/// [`bound_with_gain`] for a face that also takes `term` (per channel, the `B` it adds under
/// uniform irradiance 1 after the solve: the slab transmission across the body,
/// [`super::transmission`]): the gathered `B` is scaled by one factor `k` so that
/// `U G k + term` stays at most 1 in every channel, and `gain k` returned (`k = 1` where it
/// does; equal to [`bound_with_gain`] for a zero term).
#[inline]
pub fn bound_with_gain_and_term(uniform: Rgb, gain: Rgb, term: Rgb) -> Rgb {
    let base = uniform * gain;
    let mut k = 1.0f32;
    for c in 0..3 {
        let (b, t) = (base[c], term[c].max(0.0));
        if b.is_finite() && b > 0.0 && b + t > 1.0 {
            k = k.min((1.0 - t).max(0.0) / b);
        }
    }
    gain * k
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bound_is_one_factor_set_by_the_worst_finite_channel() {
        assert_eq!(bound(Rgb::new(1.5, 1.2, 0.9)), Rgb::splat(1.0 / 1.5));
        assert_eq!(bound(Rgb::new(0.9, 0.99, 1.0)), Rgb::ONE);
        assert_eq!(bound(Rgb::new(f32::INFINITY, 2.0, 0.5)), Rgb::splat(0.5));
        assert_eq!(bound(Rgb::new(f32::NAN, 0.5, 0.0)), Rgb::ONE);
        // The hue a face gathers survives: every channel scales alike.
        let b = Rgb::new(0.3, 0.2, 0.1) * bound(Rgb::new(1.6, 1.1, 0.8));
        assert!((b.x / b.z - 3.0).abs() < 1e-6 && b.max_element() <= 0.3 / 1.6 + 1e-7);
    }
}
