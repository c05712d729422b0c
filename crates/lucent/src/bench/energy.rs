//! `lucent bench energy`: under uniform irradiance 1 every face's `B` is the share of light
//! entering there that leaves anywhere and cannot exceed 1 (`lucent_core::solver::energy`).
//! Prints `max_b_uniform` (after the energy bound) and the profile's own maximum before it.

use crate::cli::BenchArgs;
use anyhow::{Context, Result};
use lucent_core::bssrdf::{Material, Profile};
use lucent_core::solver::{Oracle, energy};

pub fn run(args: &BenchArgs) -> Result<()> {
    let name = args.mesh.clone().unwrap_or_else(|| "bunny".into());
    let mesh = crate::scene::load_named_mesh(&name).with_context(|| format!("--mesh {name}"))?;
    let material = Material::by_name(args.material.as_deref().unwrap_or("marble"))?;
    let scale = args.scale.unwrap_or(0.1);
    let kind = args.profile.unwrap_or_default();
    let profile =
        Profile::at_model_scale(&material, mesh.extent() as f64, scale, kind, kind.has_single_scattering());
    let t = std::time::Instant::now();
    let r = energy::uniform_report(&mesh, &profile, args.oracle().unwrap_or(Oracle::for_profile(kind)));
    let ms = t.elapsed().as_secs_f64() * 1e3;
    if args.json {
        println!(
            "{{\"mesh\":{name:?},\"triangles\":{},\"material\":{:?},\"scale_m\":{scale},\"profile\":\"{kind}\",\
             \"max_b_uniform\":{},\"max_b_unbounded\":{},\"faces_bounded\":{},\"links\":{},\"ms\":{ms:.1}}}",
            r.faces, material.name, r.max_b_uniform, r.max_b_unbounded, r.faces_bounded, r.links
        );
    } else {
        println!(
            "{name}: {} triangles, {} at {scale} m, profile {kind}: max B under uniform irradiance 1 = {:.4} \
             (before the bound {:.4}; {} faces above 1), {} links, {ms:.0} ms",
            r.faces, material.name, r.max_b_uniform, r.max_b_unbounded, r.faces_bounded, r.links
        );
    }
    Ok(())
}
