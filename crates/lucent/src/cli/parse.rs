//! The value parsers of `lucent`'s flags: each turns one flag's text into its value, or into
//! a one-line usage error naming the flag, the value and the accepted range.

use lucent_core::bssrdf::ProfileKind;
use lucent_core::mesh::refine::Refine;
use lucent_core::shading::SingleScattering;
use lucent_core::solver::Oracle;
use lucent_core::solver::oracle::OracleMode;

/// The mesh hierarchy of `lucent render --hierarchy`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum HierarchyChoice {
    /// Face clustering over the input mesh (Mertens §5.1.1).
    #[default]
    FaceCluster,
    /// The input shrink-wrapped by an icosahedron subdivided this many times (§5.1.2).
    ShrinkWrap(u32),
}

/// Parses `face-cluster` or `shrink-wrap:LEVELS` (LEVELS in `0..=MAX_LEVELS`).
pub fn parse_hierarchy(s: &str) -> Result<HierarchyChoice, String> {
    use lucent_core::hierarchy::shrink_wrap::MAX_LEVELS;
    if s == "face-cluster" {
        return Ok(HierarchyChoice::FaceCluster);
    }
    let Some(levels) = s.strip_prefix("shrink-wrap:") else {
        return Err(format!(
            "expected `face-cluster` or `shrink-wrap:LEVELS` (LEVELS 0..={MAX_LEVELS}), got `{s}`"
        ));
    };
    match levels.parse::<u32>() {
        Ok(l) if l <= MAX_LEVELS => Ok(HierarchyChoice::ShrinkWrap(l)),
        _ => Err(format!(
            "shrink-wrap LEVELS must be a whole number from 0 to {MAX_LEVELS} (20 x 4^LEVELS triangles), got `{levels}`"
        )),
    }
}

/// A parser accepting exactly `names` (listed in `--help` and in errors), parsed by `T`'s
/// `FromStr`.
pub(super) fn names<T>(names: &[&'static str]) -> impl clap::builder::TypedValueParser<Value = T>
where
    T: std::str::FromStr<Err = String> + Clone + Send + Sync + 'static,
{
    use clap::builder::TypedValueParser as _;
    clap::builder::PossibleValuesParser::new(names.to_vec())
        .map(|s| s.parse::<T>().expect("one of the possible values"))
}

/// `--transmission NAME`: `curved`, `slab` or `halfspace`, case-insensitive.
pub fn parse_transmission(s: &str) -> Result<lucent_core::solver::transmission::Transmission, String> {
    s.parse::<lucent_core::solver::transmission::Transmission>().map_err(|e| e.to_string())
}

/// `--profile NAME`: one of the diffusion profiles, case-insensitive.
pub fn parse_profile(s: &str) -> Result<ProfileKind, String> {
    s.parse::<ProfileKind>().map_err(|e| e.to_string())
}

/// Three comma-separated finite numbers, `R,G,B` (each parsed as `T` directly, so an `f32`
/// colour is not rounded twice).
pub fn parse_rgb<T: std::str::FromStr + Copy + Into<f64>>(s: &str) -> Result<[T; 3], String> {
    let v: Vec<T> = s
        .split(',')
        .map(|x| x.trim().parse::<T>().map_err(|_| format!("'{x}' is not a number")))
        .collect::<Result<_, _>>()?;
    match v[..] {
        [r, g, b] if v.iter().all(|&x| x.into().is_finite()) => Ok([r, g, b]),
        _ => Err(format!("expected three finite numbers R,G,B, got '{s}'")),
    }
}

/// `--albedo R,G,B`: slab albedos, each within [`crate::ranges::ALBEDO`] (the range at eta 1.3,
/// the eta of `--albedo` materials), so that a bad one is a usage error.
pub fn parse_albedo(s: &str) -> Result<[f64; 3], String> {
    rgb_within("--albedo", s, &crate::ranges::ALBEDO)
}

/// `--mfp R,G,B`: reduced mean free paths in mm, each within
/// [`crate::ranges::MEAN_FREE_PATH_MM`].
pub fn parse_mfp(s: &str) -> Result<[f64; 3], String> {
    rgb_within("--mfp", s, &crate::ranges::MEAN_FREE_PATH_MM)
}

fn rgb_within(flag: &str, s: &str, range: &std::ops::RangeInclusive<f64>) -> Result<[f64; 3], String> {
    let rgb = parse_rgb(s)?;
    for v in rgb {
        crate::ranges::check(flag, v, range)?;
    }
    Ok(rgb)
}

/// `auto` or 0..=3 (`--refine`).
pub fn parse_refine(s: &str) -> Result<Refine, String> {
    s.parse()
}

/// `view`/`on`, `profile` or `off` (`--single-scattering`).
pub fn parse_single_scattering(s: &str) -> Result<SingleScattering, String> {
    s.parse().map_err(|e: lucent_core::shading::UnknownSingleScattering| e.to_string())
}

/// Parses the refinement oracle of `--oracle` (Mertens §5.2): `transport` (lucent's default),
/// `transport:EPS1,EPS2[,EPS_ABS[,EPS_SHARE[,CONTRAST]]]` (`CONTRAST`, the oracle's
/// `irradiance_contrast`, is capped at 1), `transport-constant:EPS1,EPS2[,...]` (the same
/// thresholds, given, with one value per receiver cluster as in the paper instead of linear
/// receivers: [`Oracle::linear_receivers`] off, to compare), `transport-linear:EPS1,EPS2[,...]`
/// (linear receivers without their curvature: [`Oracle::curved_receivers`] off) or
/// `solid-angle:EPS1,EPS2` (the paper's
/// criteria, `ε` in steradians). Every threshold must be a positive, finite number; the rest
/// stay at their defaults ([`Oracle::default`]).
pub fn parse_oracle(s: &str) -> Result<Oracle, String> {
    let usage = "expected `transport`, `transport:EPS1,EPS2[,EPS_ABS[,EPS_SHARE[,CONTRAST]]]`, `transport-constant:EPS1,EPS2[,...]`, `transport-linear:EPS1,EPS2[,...]` or `solid-angle:EPS1,EPS2`";
    let (mode, values) = s.split_once(':').unwrap_or((s, ""));
    let linear_receivers = mode != "transport-constant";
    let curved_receivers = mode == "transport";
    let (mode, counts) = match mode {
        "transport" => (OracleMode::Transport, [0, 2, 3, 4, 5].as_slice()),
        "transport-constant" | "transport-linear" => (OracleMode::Transport, [2, 3, 4, 5].as_slice()),
        "solid-angle" => (OracleMode::SolidAngle, [2].as_slice()),
        _ => return Err(format!("{usage}, got `{s}`")),
    };
    let eps: Vec<f32> = if values.is_empty() {
        Vec::new()
    } else {
        values
            .split(',')
            .map(|v| match v.trim().parse::<f32>() {
                Ok(x) if crate::ranges::ORACLE_EPS.contains(&x) => Ok(x),
                _ => Err(format!(
                    "oracle thresholds must be positive numbers within {:?}, got `{v}` in `{s}`",
                    crate::ranges::ORACLE_EPS
                )),
            })
            .collect::<Result<_, _>>()?
    };
    if !counts.contains(&eps.len()) {
        return Err(format!("{usage}, got {} threshold(s) in `{s}`", eps.len()));
    }
    let mut oracle = Oracle { mode, linear_receivers, curved_receivers, ..Oracle::default() };
    if let [e1, e2, ref rest @ ..] = eps[..] {
        (oracle.eps1, oracle.eps2) = (e1, e2);
        let mut rest = rest.iter().copied();
        oracle.eps_abs = rest.next().unwrap_or(oracle.eps_abs);
        oracle.eps_share = rest.next().unwrap_or(oracle.eps_share);
        oracle.irradiance_contrast = rest.next().map_or(oracle.irradiance_contrast, |v| v.min(1.0));
    }
    Ok(oracle)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn oracle_flag_sets_mode_and_thresholds_and_rejects_bad_values() {
        assert_eq!(parse_oracle("transport"), Ok(Oracle::default()));
        let o = parse_oracle("transport:0.5,0.2").unwrap();
        assert_eq!(
            (o.mode, o.eps1, o.eps2, o.eps_abs),
            (OracleMode::Transport, 0.5, 0.2, Oracle::default().eps_abs)
        );
        assert!(parse_oracle("transport").unwrap().linear_receivers);
        let constant = parse_oracle("transport-constant:0.5,0.2").unwrap();
        assert!(!constant.linear_receivers && constant.mode == OracleMode::Transport && constant.eps1 == 0.5);
        assert!(parse_oracle("transport-constant").is_err());
        let linear = parse_oracle("transport-linear:0.5,0.2").unwrap();
        assert!(linear.linear_receivers && !linear.curved_receivers && linear.eps1 == 0.5);
        assert!(parse_oracle("transport").unwrap().curved_receivers);
        let o = parse_oracle("transport:0.5,0.2,1e-3,0.01,0.5").unwrap();
        assert_eq!((o.eps_abs, o.eps_share, o.irradiance_contrast), (1e-3, 0.01, 0.5));
        let o = parse_oracle("solid-angle:0.02,0.05").unwrap();
        assert_eq!((o.mode, o.eps1, o.eps2), (OracleMode::SolidAngle, 0.02, 0.05));
        assert_eq!(o.eps_near_cluster, Oracle::default().eps_near_cluster);
        for bad in [
            "solid-angle",
            "solid-angle:0.1",
            "solid-angle:0.1,0.2,0.3",
            "transport:0.1",
            "transport:0.1,-0.2",
            "transport:0.1,nan",
            "transport:0.1,0",
            "transport:a,b",
            "jensen:0.1,0.1",
        ] {
            let err = parse_oracle(bad).expect_err(bad);
            assert!(err.contains(bad) || err.contains("positive"), "{bad}: {err}");
        }
    }
}
