//! The parts of the `lucent` front end that other crates use: the scene-file format
//! ([`scene`]) and the accepted ranges of every numeric parameter ([`ranges`]), both from
//! `lucent-scene` (the fuzz harness, `crates/lucent-fuzz`, uses that crate directly so it builds
//! without wgpu), and one still image from a resolved scene ([`still`]: the solve, then the GPU
//! frame of [`frame`], read back as an [`output`] image), which the Python module
//! (`crates/lucent-py`) renders through; the command-line program (`src/main.rs`) uses the same
//! modules.

pub mod frame;
pub mod output;
pub mod still;

pub use lucent_scene::{ranges, scene};
