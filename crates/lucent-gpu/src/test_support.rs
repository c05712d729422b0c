//! For tests that need a GPU adapter or a system program (here and in the `lucent` crate), so
//! that `cargo test` passes on a fresh machine with only the Rust toolchain: there such a test
//! says it was skipped and what to install; under CI (the `CI` environment variable set, as
//! `.ci/run` and CI services do, after installing everything) a skip is a failure.
//!
//! The notes go straight to the process's stderr, past the test harness's capture, so they show
//! in a plain `cargo test` run.

use crate::{GpuContext, GpuError};
use std::io::Write as _;
use std::sync::OnceLock;

/// How to get an adapter on Debian or Ubuntu without a GPU: Mesa's lavapipe (Vulkan) and
/// llvmpipe (GL through EGL).
pub const INSTALL_ADAPTER: &str = "apt-get install mesa-vulkan-drivers libegl1 libgl1-mesa-dri";

/// True when running under CI (`CI` set to anything), where nothing may be skipped.
pub fn under_ci() -> bool {
    std::env::var_os("CI").is_some()
}

/// Reports that the current test cannot run because `missing` (a few words), `install` being
/// the command that provides it. On a developer's machine prints one line,
/// `SKIPPED <test>: <missing>; install it with ...`, to stderr and returns, so the test can
/// return early and pass; under CI panics with the same text.
pub fn skip(missing: &str, install: &str) {
    report(missing, None, install)
}

/// [`skip`], with `detail` (the full error) added under CI, where the failure must be diagnosed.
fn report(missing: &str, detail: Option<&str>, install: &str) {
    let thread = std::thread::current();
    // libtest runs each test on a thread named after it.
    let test = thread.name().filter(|n| *n != "main").unwrap_or("a test");
    let text = format!("{test}: {missing}; install it with `{install}` (.ci/run installs everything)");
    if under_ci() {
        let detail = detail.map(|d| format!(" ({d})")).unwrap_or_default();
        panic!("{text}. CI is set, so this test may not be skipped{detail}");
    }
    let _ = writeln!(std::io::stderr().lock(), "SKIPPED {text}");
}

/// A GPU context for the current test, or `None` when no adapter exists, after [`skip`] said
/// so (under CI: panics). Use as `let Some(ctx) = adapter_or_skip() else { return };`.
pub fn adapter_or_skip() -> Option<GpuContext> {
    GpuContext::new().map_err(|e| no_adapter(&e)).ok()
}

/// Whether an adapter exists, for tests that run a program needing one (the `lucent` binary):
/// false after [`skip`] said so (under CI: panics). The search runs once per process.
pub fn adapter_available_or_skip() -> bool {
    static FOUND: OnceLock<Result<(), GpuError>> = OnceLock::new();
    match FOUND.get_or_init(|| GpuContext::new().map(drop)) {
        Ok(()) => true,
        Err(e) => {
            no_adapter(e);
            false
        }
    }
}

/// Skips for a failed adapter search: one short line on a developer's machine (the full
/// message lists every backend tried), all of it under CI.
fn no_adapter(e: &GpuError) {
    let missing = match e {
        GpuError::NoAdapter { .. } => "no GPU adapter (neither Vulkan nor GL)".to_string(),
        other => format!("no usable GPU adapter ({other})"),
    };
    report(&missing, Some(&e.to_string()), INSTALL_ADAPTER);
}
