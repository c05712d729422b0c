//! # lucent-scene
//!
//! The scene description every front end of lucent shares, with no GPU dependency: the
//! scene-file format and its resolution with the command line's flags into one [`scene::Scene`]
//! ([`scene`]), and the accepted range of every numeric parameter ([`ranges`]). The command-line
//! program and the viewer (`crates/lucent`, which re-exports both modules) and the fuzz harness
//! (`crates/lucent-fuzz`) parse scene files through this crate; keeping it free of wgpu keeps
//! the fuzzer's build small.

pub mod ranges;
pub mod scene;
