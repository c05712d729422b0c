//! What the integration tests share: skipping where the machine lacks what a test needs. The
//! rule lives in `lucent_gpu::test_support`: on a developer's machine the test prints
//! `SKIPPED ...` with the command that installs the missing piece and passes; under CI (`CI`
//! set) it fails.

#![allow(dead_code)]

pub mod figures;

use std::path::PathBuf;

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
