//! lucent against the committed Mitsuba 3 references of `validation/` (no Mitsuba needed):
//! every case of `validation/cases.json` is rendered with the default profile at the case's
//! resolution, and its median per-pixel error, bias of means and worst 8x8 block against the
//! mean of the two reference halves must stay within `validation/bounds.json` (the figures
//! measured by `validation/lucent_validation.py compare --write-bounds fit`, plus margins). A
//! change that moves lucent away from the path tracer fails here.
//!
//! The `test` cases (lights and cameras the fit cases do not have, issue 50) are held to
//! `bounds.json`'s `test_guard`: their figures when last recorded (2026-12-06, with the slab
//! and curved terms), plus the same margins (`compare --split test --write-bounds test`). That is a regression guard, not the issue's
//! targets (many test cases are 20-60% off there); a test case without a guard entry is not run.

mod common;

use common::figures::{figures, interior, read_exr};

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
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
