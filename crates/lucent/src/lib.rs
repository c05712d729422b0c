//! The parts of the `lucent` front end that other crates use: the scene-file format
//! ([`scene`]), the accepted ranges of every numeric parameter ([`ranges`]), and one still image
//! from a resolved scene ([`still`]: the solve, then the GPU frame of [`frame`], read back as
//! an [`output`] image). The fuzz harness (`crates/lucent-fuzz`) parses scene files through this
//! library, the Python module (`crates/lucent-py`) renders through it; the command-line program
//! (`src/main.rs`) uses the same modules.

pub mod frame;
pub mod output;
pub mod ranges;
pub mod scene;
pub mod still;
