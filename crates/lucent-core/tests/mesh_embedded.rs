//! The embedded bunny parses and is the closed genus-0 mesh the asset's source describes.

use lucent_core::mesh::embedded::bunny;

#[test]
fn bunny_is_closed_genus_0() {
    let m = bunny();
    // Counts from the source (npm `bunny` 1.0.1, see assets/README.md).
    assert_eq!(m.positions.len(), 1839);
    assert_eq!(m.triangles.len(), 3674);
    let t = m.topology();
    assert!(t.is_closed_manifold(), "{t}");
    assert_eq!(t.components, 1);
    assert_eq!(t.euler_characteristic, 2);
    assert!(m.signed_volume() > 0.0, "outward faces");
    assert_eq!(bunny(), m, "second call returns the same mesh");
}
