//! `lucent bench htsm`: HTSM frame time for n = 1, 5, 9, 13 sample rays at 512^2 and 1024^2
//! (Shopf 2007 fig. 5.9 gives frames per second for the same n on 2006 GPUs).
//!
//! The scene is `lucent render --method htsm`'s default (mesh, light, camera, vein volume,
//! material). A frame is all four passes (reference images, their mips, the camera pass, tone
//! mapping); its time is the wall time from encoding to the queue being idle again
//! (`queue.submit` then `device.poll(wait)`), without read-back, median over the frames.
//! `memory_bytes` is what the thesis counts: reference images with mips plus the density volume
//! with mips. `--htsm-model` times another transport model than the render's default
//! (`diffusion` with the scene's material); the JSON names the model timed.
//! `cpu_ms_per_frame` is the median CPU time of the process's threads per frame: on a software
//! adapter (lavapipe) sharing its cores with other jobs the wall time swings with their load,
//! the CPU time far less, so two models or builds compare by it there.

use super::cpu_time::process_cpu_ns;
use crate::cli::{BenchArgs, Cli, Command, HtsmModel, RenderArgs};
use crate::render::Scene;
use crate::render::htsm::{build_volume, htsm_medium, htsm_params};
use anyhow::{Context, Result};
use clap::Parser;
use lucent_core::camera::bounding_sphere;
use lucent_gpu::GpuContext;
use lucent_gpu::htsm::{HtsmParams, HtsmRenderer, HtsmView};
use std::time::{Duration, Instant};

/// Sample-ray counts of fig. 5.9.
const SAMPLES: [u32; 4] = [1, 5, 9, 13];
/// Square image sizes measured.
const SIZES: [u32; 2] = [512, 1024];
/// Frames before timing (pipeline and driver warm-up).
const WARMUP: usize = 2;
/// Timed frames: at least `MIN_FRAMES`, more until `BUDGET` has passed or `MAX_FRAMES`.
const MIN_FRAMES: usize = 5;
const MAX_FRAMES: usize = 50;
const BUDGET: Duration = Duration::from_secs(3);

/// Frames of `params` after [`WARMUP`]: the median wall time (ms), the median CPU time of the
/// process's threads (ms, where readable) and the number of frames timed.
fn time_frames(
    renderer: &mut HtsmRenderer,
    ctx: &GpuContext,
    view: &HtsmView,
    params: &HtsmParams,
) -> Result<(f64, Option<f64>, usize)> {
    for _ in 0..WARMUP {
        renderer.render_timed(ctx, view, params)?;
    }
    let started = Instant::now();
    let (mut times, mut cpu) = (Vec::new(), Vec::new());
    while times.len() < MIN_FRAMES || (times.len() < MAX_FRAMES && started.elapsed() < BUDGET) {
        let before = process_cpu_ns();
        times.push(renderer.render_timed(ctx, view, params)?.as_secs_f64() * 1e3);
        if let (Some(b), Some(a)) = (before, process_cpu_ns()) {
            cpu.push(a.saturating_sub(b) as f64 * 1e-6);
        }
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let frames = times.len();
    let cpu_ms = (cpu.len() == frames).then(|| median(&mut cpu));
    Ok((median(&mut times), cpu_ms, frames))
}

/// `lucent render --method htsm`'s arguments, with `--htsm-model` when given.
fn render_args(model: Option<HtsmModel>) -> RenderArgs {
    let mut argv = vec!["lucent", "render", "--method", "htsm"];
    if let Some(model) = model {
        let name = match model {
            HtsmModel::Thesis => "thesis",
            HtsmModel::BeerLambert => "beer-lambert",
            HtsmModel::Diffusion => "diffusion",
        };
        argv.extend(["--htsm-model", name]);
    }
    match Cli::parse_from(argv).command {
        Some(Command::Render(a)) => a,
        _ => unreachable!("render is a subcommand"),
    }
}

pub fn run(args: &BenchArgs) -> Result<()> {
    let render_args = render_args(args.htsm_model);
    let scene = Scene::resolve(&render_args.overrides())?;
    let light = scene.lights.first().context("the default scene has a light")?.light;
    let medium = htsm_medium(&render_args.htsm, scene.material(), scene.scale())?;
    let base = htsm_params(
        &render_args.htsm,
        &scene.mesh,
        None,
        (medium, scene.material().eta as f32),
        &render_args,
    )?;
    let volume = build_volume(&render_args.htsm, &scene.mesh)?;
    let ctx = GpuContext::new()?;
    let adapter = ctx.describe();
    let mut renderer = HtsmRenderer::new(&ctx, &scene.mesh, &volume, render_args.htsm.htsm_size)?;
    let memory = renderer.memory();
    let (centre, radius) = bounding_sphere(&scene.mesh.positions);

    if !args.json {
        println!(
            "HTSM on {adapter}: {} ({} triangles), volume {}x{}x{}, reference images {}^2, K = {} steps",
            scene.source,
            scene.mesh.triangles.len(),
            volume.dims[0],
            volume.dims[1],
            volume.dims[2],
            renderer.reference_size(),
            base.steps
        );
        println!("frame = submit + device.poll(wait), no read-back; median");
        println!("{:>3} {:>11} {:>12} {:>9} {:>7}", "n", "size", "ms/frame", "fps", "frames");
    }
    for size in SIZES {
        let view = HtsmView {
            camera: scene.camera.frame(centre, radius, 1.0),
            lights: vec![light],
            environment: None,
            width: size,
            height: size,
        };
        for samples in SAMPLES {
            let params = HtsmParams { samples, ..base };
            let (ms, cpu_ms, frames) = time_frames(&mut renderer, &ctx, &view, &params)?;
            if args.json {
                println!(
                    "{}",
                    serde_json::json!({
                        "bench": "htsm",
                        "samples": samples,
                        "width": size,
                        "height": size,
                        "steps": params.steps,
                        "model": format!("{:?}", params.model),
                        "ms_per_frame": ms,
                        "fps": 1e3 / ms,
                        "frames": frames,
                        "timing": "median of submit + device.poll(wait), no read-back",
                        "cpu_ms_per_frame": cpu_ms,
                        "cpu_timing": "median CPU time of all the process's threads per frame (Linux; null elsewhere)",
                        "memory_bytes": memory.thesis_bytes(),
                        "reference_size": renderer.reference_size(),
                        "volume_dims": volume.dims,
                        "triangles": scene.mesh.triangles.len(),
                        "adapter": adapter,
                    })
                );
            } else {
                println!(
                    "{samples:>3} {:>11} {ms:>12.2} {:>9.1} {:>7}",
                    format!("{size}x{size}"),
                    1e3 / ms,
                    frames
                );
            }
        }
    }
    if !args.json {
        println!(
            "memory: reference images with mips {} bytes + volume with mips {} bytes = {:.2} MB (thesis: ~3 MB)",
            memory.reference_images,
            memory.volume,
            memory.thesis_bytes() as f64 / 1e6
        );
    }
    Ok(())
}
