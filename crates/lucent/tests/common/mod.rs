//! What the integration tests share: skipping where the machine lacks what a test needs. The
//! rule lives in `lucent_gpu::test_support`: on a developer's machine the test prints
//! `SKIPPED ...` with the command that installs the missing piece and passes; under CI (`CI`
//! set) it fails.

#![allow(dead_code)]

pub mod figures;

use std::path::PathBuf;
use std::process::{Command, Output};

/// Runs the `lucent` binary under test with `args` and the extra environment `envs`.
pub fn lucent_env(args: &[&str], envs: &[(&str, &str)]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_lucent"));
    cmd.args(args).envs(envs.iter().copied());
    cmd.output().expect("run lucent")
}

/// Runs the `lucent` binary under test with `args`.
pub fn lucent(args: &[&str]) -> Output {
    lucent_env(args, &[])
}

/// A fresh, empty directory `name` for one test of the test file `suite`.
pub fn scratch(suite: &str, name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(suite).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// stderr's non-blank lines, without the notice Mesa's drivers print on headless machines.
pub fn stderr_lines(out: &Output) -> Vec<String> {
    String::from_utf8_lossy(&out.stderr)
        .lines()
        .filter(|l| !l.contains("XDG_RUNTIME_DIR") && !l.trim().is_empty())
        .map(str::to_string)
        .collect()
}

/// Whether a GPU adapter exists for the `lucent` binary the test runs (searched once per test
/// binary); false after saying the test is skipped. Use as `if !common::gpu_or_skip() { return; }`.
pub fn gpu_or_skip() -> bool {
    lucent_gpu::test_support::adapter_available_or_skip()
}

/// `xvfb-run` (a virtual X server for the viewer), or `None` after saying the test is skipped.
pub fn xvfb_run_or_skip() -> Option<PathBuf> {
    let found = std::env::var_os("PATH")
        .and_then(|path| std::env::split_paths(&path).map(|dir| dir.join("xvfb-run")).find(|p| p.is_file()));
    if found.is_none() {
        lucent_gpu::test_support::skip(
            "xvfb-run is not installed (the viewer test needs a virtual X server)",
            "apt-get install xvfb xauth",
        );
    }
    found
}
