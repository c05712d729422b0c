//! The parts of the `lucent` front end that other crates use: the scene-file format
//! ([`scene`]) and the accepted ranges of every numeric parameter ([`ranges`]). The fuzz harness
//! (`crates/lucent-fuzz`) parses scene files through this library; the command-line program
//! (`src/main.rs`) uses the same modules.

pub mod ranges;
pub mod scene;
