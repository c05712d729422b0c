//! lucent against the committed Mitsuba 3 references of `validation/` (no Mitsuba needed):
//! every case of `validation/cases.json` is rendered with the default profile at the case's
//! resolution, and its median per-pixel error, bias of means and worst 8x8 block against the
//! mean of the two reference halves must stay within `validation/bounds.json` (the figures
//! measured by `validation/lucent_validation.py compare --write-bounds fit`, plus margins). A
//! change that moves lucent away from the path tracer fails here.
//!
//! The `test` cases (lights and cameras the fit cases do not have, issue 50) are held to
//! `bounds.json`'s `test_guard`: their figures when they were added, plus the same margins
//! (`compare --split test --write-bounds test`). That is a regression guard, not the issue's
//! targets (many test cases are 20-60% off there); a test case without a guard entry is not run.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// RGBA pixels of an EXR, rows top first.
fn read_exr(path: &Path) -> (usize, usize, Vec<[f32; 4]>) {
    let img = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |res, _| (res.width(), res.height(), vec![[0.0f32; 4]; res.width() * res.height()]),
        |(w, _, v): &mut (usize, usize, Vec<[f32; 4]>), p, (r, g, b, a): (f32, f32, f32, f32)| {
            v[p.y() * *w + p.x()] = [r, g, b, a]
        },
    )
    .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    img.layer_data.channel_data.pixels
}

/// Fully covered pixels whose four neighbours are too.
fn interior(w: usize, h: usize, px: &[[f32; 4]]) -> Vec<bool> {
    let full = |x: usize, y: usize| px[y * w + x][3] > 0.999;
    (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            x > 0
                && y > 0
                && x + 1 < w
                && y + 1 < h
                && full(x, y)
                && full(x - 1, y)
                && full(x + 1, y)
                && full(x, y - 1)
                && full(x, y + 1)
        })
        .collect()
}

struct Figures {
    median: f64,
    bias: f64,
    worst_block: f64,
}

/// The compare script's statistics on the channel sum (`validation/lucent_validation.py`).
fn figures(w: usize, h: usize, ours: &[[f32; 4]], a: &[[f32; 4]], b: &[[f32; 4]], mask: &[bool]) -> Figures {
    let lum = |p: &[f32; 4]| (p[0] + p[1] + p[2]) as f64;
    let r: Vec<f64> = a.iter().zip(b).map(|(a, b)| 0.5 * (lum(a) + lum(b))).collect();
    let noise: Vec<f64> = a.iter().zip(b).map(|(a, b)| 0.5 * (lum(a) - lum(b)).abs()).collect();
    let o: Vec<f64> = ours.iter().map(lum).collect();
    let sel: Vec<bool> = (0..w * h).map(|i| mask[i] && r[i] > 1e-6).collect();
    let mut rel: Vec<f64> = (0..w * h).filter(|&i| sel[i]).map(|i| (o[i] - r[i]) / r[i]).collect();
    rel.sort_by(|x, y| x.total_cmp(y));
    let median = if rel.is_empty() { f64::NAN } else { rel[rel.len() / 2] };
    let (so, sr) = (0..w * h).filter(|&i| sel[i]).fold((0.0, 0.0), |(so, sr), i| (so + o[i], sr + r[i]));
    let mut worst = 0.0f64;
    for by in (0..h.saturating_sub(7)).step_by(8) {
        for bx in (0..w.saturating_sub(7)).step_by(8) {
            let idx: Vec<usize> =
                (0..64).map(|k| (by + k / 8) * w + bx + k % 8).filter(|&i| sel[i]).collect();
            if idx.len() < 32 {
                continue;
            }
            let n = idx.len() as f64;
            let (mo, mr) =
                (idx.iter().map(|&i| o[i]).sum::<f64>() / n, idx.iter().map(|&i| r[i]).sum::<f64>() / n);
            let nb = idx.iter().map(|&i| noise[i] * noise[i]).sum::<f64>().sqrt() / n;
            worst = worst.max(((mo - mr).abs() - 2.0 * nb).max(0.0) / mr);
        }
    }
    Figures { median, bias: so / sr - 1.0, worst_block: worst }
}

#[test]
fn every_case_stays_within_its_recorded_bound_against_the_path_tracer() {
    if !common::gpu_or_skip() {
        return;
    }
    let root = root();
    let cases: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(root.join("validation/cases.json")).unwrap()).unwrap();
    let bounds: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(root.join("validation/bounds.json")).expect(
            "validation/bounds.json: run `lucent_validation.py compare --split fit --write-bounds fit`",
        ))
        .unwrap();
    let [w, h] = [0, 1].map(|k| cases["resolution"][k].as_u64().unwrap());
    let out = std::env::temp_dir().join(format!("lucent-validation-{}", std::process::id()));
    std::fs::create_dir_all(&out).unwrap();
    let mut failures = Vec::new();
    for case in cases["cases"].as_array().unwrap() {
        let name = case["name"].as_str().unwrap();
        let section = if case["split"].as_str() == Some("test") { "test_guard" } else { "cases" };
        if section == "test_guard" && bounds[section][name].is_null() {
            println!("{name}: a test case with no regression guard in bounds.json; not run");
            continue;
        }
        // A scanned mesh that is fetched, not committed (the Stanford dragon's terms): measured
        // where it has been fetched, as `compare` does; the committed cases run everywhere.
        if let Some(how) = case["fetched"].as_str() {
            let mesh = root.join(format!("validation/scenes/{}.obj", case["mesh"].as_str().unwrap()));
            if !mesh.exists() {
                println!("{name}: its mesh is not here ({how}); the committed cases still run");
                continue;
            }
        }
        let exr = out.join(format!("{name}.exr"));
        let status = Command::new(env!("CARGO_BIN_EXE_lucent"))
            .arg("render")
            .arg("--scene")
            .arg(root.join(format!("validation/scenes/{name}.toml")))
            .args(["--width", &w.to_string(), "--height", &h.to_string(), "--no-surface", "--out"])
            .arg(&exr)
            .output()
            .unwrap();
        assert!(status.status.success(), "{name}: {}", String::from_utf8_lossy(&status.stderr));
        let (w, h, ours) = read_exr(&exr);
        let part = |p: &str| read_exr(&root.join(format!("validation/references/{name}.{p}.exr"))).2;
        let (mut a, mut b) = (part("half_a"), part("half_b"));
        if case["eta"].as_f64().unwrap() != 1.0 {
            // The surface reflection alone (absorbing interior), subtracted from both halves.
            let surface = part("surface");
            for (p, s) in a.iter_mut().chain(b.iter_mut()).zip(surface.iter().cycle()) {
                (0..3).for_each(|c| p[c] -= s[c]);
            }
        }
        let f = figures(w, h, &ours, &a, &b, &interior(w, h, &ours));
        let bound = &bounds[section][name];
        let limit =
            |k: &str| bound[k].as_f64().unwrap_or_else(|| panic!("bounds.json: {section}.{name}.{k}"));
        println!(
            "{name} ({section}): median {:+.1}% (bound {:.1}%), bias {:+.1}% ({:.1}%), worst 8x8 {:.1}% ({:.1}%)",
            100.0 * f.median,
            100.0 * limit("median"),
            100.0 * f.bias,
            100.0 * limit("bias"),
            100.0 * f.worst_block,
            100.0 * limit("worst_block")
        );
        if !(f.median.abs() <= limit("median")
            && f.bias.abs() <= limit("bias")
            && f.worst_block <= limit("worst_block"))
        {
            failures.push(name.to_string());
        }
    }
    let _ = std::fs::remove_dir_all(&out);
    assert!(failures.is_empty(), "beyond their recorded bounds: {failures:?}");
}
