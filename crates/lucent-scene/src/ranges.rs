//! The accepted range of every numeric parameter, in one place: command-line flags and scene
//! keys are checked against these before anything is loaded or solved. Values inside a range
//! finish in bounded time; values outside are refused with a one-line error naming the value and
//! the range.

use std::fmt::Display;
use std::ops::RangeInclusive;
use std::str::FromStr;

/// Model scale, metres (the largest side of the bounding box): 0.1 mm to 100 m.
pub const SCALE_M: RangeInclusive<f64> = 1e-4..=100.0;
/// Image width and height, pixels.
pub const IMAGE_SIDE: RangeInclusive<u32> = 1..=16384;
/// Frames of an animation.
pub const FRAMES: RangeInclusive<u32> = 1..=100_000;
/// Exposure multiplier.
pub const EXPOSURE: RangeInclusive<f32> = 1e-6..=1e6;
/// Display gamma of the tone curve.
pub const GAMMA: RangeInclusive<f32> = 0.1..=10.0;
/// Camera yaw and environment rotation, degrees.
pub const ANGLE_DEG: RangeInclusive<f32> = -3600.0..=3600.0;
/// Camera pitch, degrees.
pub const PITCH_DEG: RangeInclusive<f32> = -89.0..=89.0;
/// Camera distance, bounding-sphere radii.
pub const CAMERA_DISTANCE: RangeInclusive<f32> = 1.0001..=1e4;
/// Coordinates of a light (mesh units) and components of a direction.
pub const COORDINATE: RangeInclusive<f32> = -1e6..=1e6;
/// Light intensity and colour components, and environment intensity.
pub const INTENSITY: RangeInclusive<f32> = 0.0..=1e6;
/// Thresholds of the refinement oracle (`--oracle`); below the lower end every pair of faces
/// is refined to the leaves, an exact O(N^2) solve by another name.
pub const ORACLE_EPS: RangeInclusive<f32> = 1e-6..=1e3;
/// HTSM: ray-cast steps per sample ray.
pub const HTSM_STEPS: RangeInclusive<u32> = 1..=1024;
/// HTSM: side of the light-view reference images, texels.
pub const HTSM_SIZE: RangeInclusive<u32> = 16..=8192;
/// HTSM: transport distance, object units.
pub const TRANSPORT_DISTANCE: RangeInclusive<f32> = 1e-4..=1e3;
/// HTSM: Henyey-Greenstein asymmetry.
pub const PHASE_G: RangeInclusive<f32> = -0.99..=0.99;
/// Bounces of subsurface light between parts (`--bounces`, scene key `bounces`).
pub const BOUNCES: RangeInclusive<u32> = 0..=4;
/// The default number of bounces (render, scenes and the viewer alike): three. Light carried
/// between parts through the air is real; on the 11K Stanford dragon (marble, 10 cm) it is
/// what the path tracer shows and a solve without it lacks (against Mitsuba, median / bias /
/// worst 8x8 block: no bounce −11.4 / −15.7 / 46%, one −5.9 / −7.8 / 29%, three −3.9 / −5.0 /
/// 21%, four −3.8 / −4.7 / 21%). With stored links each bounce is a gather over them and the
/// rays between parts are traced once (refitted as the mesh deforms), so three cost little
/// more than one; on the fly each bounce links anew.
pub const DEFAULT_BOUNCES: u32 = 3;

/// The default number of bounces for `profile`: [`DEFAULT_BOUNCES`], but none for `mertens`,
/// the paper's model (which has none), kept to reproduce its tables: it does not bound energy
/// on thin parts (a face of the bunny at 1 cm returns 15,504 times its light), and bounces
/// carried that glow on (the 11K dragon's bias +9% at one bounce, +161% at three).
pub fn default_bounces(profile: lucent_core::bssrdf::ProfileKind) -> u32 {
    if profile.bounces_by_default() { DEFAULT_BOUNCES } else { 0 }
}

/// The bounces after the profile changed from `before` to `after` (the viewer's profile
/// switch): a count left at `before`'s default follows to `after`'s, one the user chose stays.
pub fn bounces_after_profile_change(
    bounces: u32,
    before: lucent_core::bssrdf::ProfileKind,
    after: lucent_core::bssrdf::ProfileKind,
) -> u32 {
    if bounces == default_bounces(before) { default_bounces(after) } else { bounces }
}
/// HTSM: extra absorption of density 1, per object unit.
pub const DENSITY_SCALE: RangeInclusive<f32> = 0.0..=1e4;

/// Slab albedo of a colour material (`--albedo`, scene key `albedo`), unitless; lucent-core's
/// range (the same at every eta, see `albedo_range`).
pub const ALBEDO: RangeInclusive<f64> = lucent_core::bssrdf::ALBEDO;
/// Reduced mean free path of a colour material (`--mfp`, scene key `mfp`), mm.
pub const MEAN_FREE_PATH_MM: RangeInclusive<f64> = lucent_core::bssrdf::MEAN_FREE_PATH_MM;

pub use lucent_core::limits::check_range as check;

/// A clap value parser: a number of type `T` within `range`.
pub fn parser<T>(
    range: RangeInclusive<T>,
) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync + 'static
where
    T: FromStr + PartialOrd + Display + Copy + Send + Sync + 'static,
{
    move |s: &str| {
        let value = s
            .trim()
            .parse::<T>()
            .map_err(|_| format!("'{s}' is not a number in {}..={}", range.start(), range.end()))?;
        check("value", value, &range)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_refuse_nan_and_out_of_range_with_the_range() {
        assert_eq!(check("--scale", 0.05, &SCALE_M), Ok(0.05));
        let e = check("--scale", -1.0, &SCALE_M).unwrap_err();
        assert!(e.contains("-1") && e.contains("0.0001..=100"), "{e}");
        assert!(check("--scale", f64::NAN, &SCALE_M).is_err());
        assert!(parser(IMAGE_SIDE)("0").is_err());
        assert_eq!(parser(IMAGE_SIDE)("640"), Ok(640));
        assert!(parser(EXPOSURE)("abc").unwrap_err().contains("not a number"));
    }

    #[test]
    fn default_bounces_follow_a_profile_switch_and_chosen_ones_stay() {
        use lucent_core::bssrdf::ProfileKind;
        for before in ProfileKind::ALL {
            for after in ProfileKind::ALL {
                let left = bounces_after_profile_change(default_bounces(before), before, after);
                assert_eq!(left, default_bounces(after), "{before} -> {after}: follows");
                for chosen in [1, 2] {
                    let kept = bounces_after_profile_change(chosen, before, after);
                    assert_eq!(kept, chosen, "{before} -> {after}: chosen by hand");
                }
            }
        }
        // The defaults differ, so switching moves them: none for the paper's profile.
        assert_eq!(default_bounces("mertens".parse().unwrap()), 0);
        assert_eq!(default_bounces(ProfileKind::default()), DEFAULT_BOUNCES);
    }
}
