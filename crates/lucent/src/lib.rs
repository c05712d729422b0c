//! The parts of the `lucent` front end that other crates use: the scene-file format
//! ([`scene`]) and the accepted ranges of every numeric parameter ([`ranges`]), both from
//! `lucent-scene` (the fuzz harness, `crates/lucent-fuzz`, uses that crate directly so it builds
//! without wgpu); the command-line program (`src/main.rs`) uses the same modules.

pub use lucent_scene::{ranges, scene};
