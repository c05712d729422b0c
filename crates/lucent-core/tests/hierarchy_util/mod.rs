//! Checks shared by the subdivision and shrink-wrap hierarchy tests.

use lucent_core::hierarchy::Hierarchy;

/// Every inner cluster with a triangle has four children, the parent's corners each in exactly
/// one child, six distinct corners among them, and the children's areas add up to the
/// parent's. Returns how many such clusters were checked.
pub fn check_quad_tree(h: &Hierarchy) -> usize {
    let poly = |i: usize| &h.polygon_vertices[h.polygon_start[i] as usize..h.polygon_start[i + 1] as usize];
    let mut checked = 0;
    for (i, n) in h.nodes.iter().enumerate() {
        if n.is_leaf() || poly(i).len() != 3 {
            continue;
        }
        assert_eq!(n.child_count, 4, "cluster {i}");
        let kids: Vec<&[u32]> = n.children().iter().map(|&c| poly(c as usize)).collect();
        for &corner in poly(i) {
            assert_eq!(kids.iter().filter(|k| k.contains(&corner)).count(), 1);
        }
        let mut all: Vec<u32> = kids.iter().flat_map(|k| k.iter().copied()).collect();
        all.sort_unstable();
        all.dedup();
        assert_eq!(all.len(), 6);
        let a: f32 = n.children().iter().map(|&c| h.geom[c as usize].area).sum();
        assert!((a - h.geom[i].area).abs() <= 1e-4 * a, "cluster {i}: children {a} vs {}", h.geom[i].area);
        checked += 1;
    }
    checked
}
