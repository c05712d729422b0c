//! The view-ray scenes the single-scattering tests share (included by `single_scattering.rs`
//! and `light_paths.rs`).

use lucent_core::bssrdf::{Material, Profile, ProfileKind};
use lucent_core::irradiance::{Environment, SceneLight};
use lucent_core::mesh::bvh::Bvh;
use lucent_core::mesh::{Mesh, generate};
use lucent_core::shading::single_scattering::ViewRayScene;

/// A cube 2 units wide of a material with a mean free path of a thousandth of a unit: a
/// half-space seen from the middle of a face. Albedos 0.3, 0.9, 0.99.
pub fn half_space(eta: f64) -> (Mesh, Profile) {
    let sigma_s = [3.0, 9.0, 9.9];
    let sigma_a = [7.0, 1.0, 0.1];
    let m = Material::custom("test", sigma_s, sigma_a, eta).unwrap();
    // 10 mm^-1 total, 100 mm per unit: σ_t = 1000 per unit.
    (generate::cube(8), Profile::of_kind(&m, 100.0, ProfileKind::Pbd, false))
}

/// `f` of the view-ray scene of `mesh` (its vertex normals, a BVH over it).
pub fn with_scene<R>(
    mesh: &Mesh,
    d: &Profile,
    lights: &[SceneLight],
    env: Option<&Environment>,
    f: impl FnOnce(&ViewRayScene) -> R,
) -> R {
    let normals = mesh.vertex_normals();
    let bvh = Bvh::build(mesh);
    f(&ViewRayScene {
        mesh,
        normals: &normals,
        bvh: &bvh,
        offset: 1e-5,
        profile: d,
        lights,
        environment: env,
        lit: None,
    })
}
