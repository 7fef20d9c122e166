//! kd-tree invariants: every triangle that overlaps a leaf's box is in that leaf, the SAH tree beats a
//! middle-split tree, nodes are well-formed, and the build is deterministic.

use glam::{DVec3, Vec3};
use raylab_core::aabb::Aabb;
use raylab_core::kdtree::{KdParams, KdTree, SplitStrategy};
use raylab_core::scene::Scene;
use raylab_scene::builtin::{self, Detail};

/// Separating-axis test of triangle `t` against the box `[lo, hi]` (Akenine-Moller 2001, "Fast 3D
/// Triangle-Box Overlap Testing"), in double precision. Independent of the builder's clipping code on purpose.
fn overlaps(t: &[Vec3; 3], lo: DVec3, hi: DVec3) -> bool {
    let c = (lo + hi) * 0.5;
    let h = (hi - lo) * 0.5;
    let v = t.map(|p| p.as_dvec3() - c);
    let e = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
    let separated_on = |axis: glam::DVec3| {
        if axis.length_squared() < 1e-30 {
            return false;
        }
        let p = v.map(|q| q.dot(axis));
        let r = h.x * axis.x.abs() + h.y * axis.y.abs() + h.z * axis.z.abs();
        p.iter().cloned().fold(f64::INFINITY, f64::min) > r || p.iter().cloned().fold(f64::NEG_INFINITY, f64::max) < -r
    };
    let units = [glam::DVec3::X, glam::DVec3::Y, glam::DVec3::Z];
    for u in units {
        if separated_on(u) {
            return false;
        }
        for edge in e {
            if separated_on(u.cross(edge)) {
                return false;
            }
        }
    }
    !separated_on(e[0].cross(e[1]))
}

fn check_leaf_coverage(scene: &Scene, tree: &KdTree, name: &str) {
    let tris: Vec<[Vec3; 3]> = (0..scene.triangle_count()).map(|i| scene.vertices(i)).collect();
    let tri_boxes: Vec<Aabb> = tris.iter().map(|t| Aabb::from_points(t.iter().copied())).collect();
    let mut leaves = 0;
    tree.visit(|_, bounds, node| {
        if !node.is_leaf() {
            return;
        }
        leaves += 1;
        // Shrink the leaf a little (in double precision, where the shrink survives): triangles that only
        // touch its boundary may sit in the neighbour.
        let shrink = bounds.extent().as_dvec3() * 1e-4;
        let (lo, hi) = (bounds.min.as_dvec3() + shrink, bounds.max.as_dvec3() - shrink);
        let held: std::collections::HashSet<u32> = tree.tri_ids()[node.leaf_range()].iter().copied().collect();
        for (i, t) in tris.iter().enumerate() {
            if tri_boxes[i].intersection(*bounds).is_empty() || held.contains(&(i as u32)) {
                continue;
            }
            assert!(!overlaps(t, lo, hi), "{name}: triangle {i} overlaps leaf {bounds:?} but is not in it");
        }
    });
    assert!(leaves > 1, "{name}: the tree was split");
}

#[test]
fn every_overlapping_triangle_is_in_the_leaf() {
    for name in builtin::names() {
        let scene = builtin::build(name, Detail::Test).unwrap();
        let tree = KdTree::build(&scene, &KdParams::default()).unwrap();
        check_leaf_coverage(&scene, &tree, name);
    }
}

#[test]
fn sah_tree_costs_less_than_a_middle_split_tree() {
    for name in builtin::names() {
        let scene = builtin::build(name, Detail::Test).unwrap();
        let sah = KdTree::build(&scene, &KdParams::default()).unwrap().stats();
        let mid = KdTree::build(&scene, &KdParams { strategy: SplitStrategy::Middle, ..KdParams::default() })
            .unwrap()
            .stats();
        assert!(sah.sah_cost < mid.sah_cost, "{name}: SAH {} vs middle {}", sah.sah_cost, mid.sah_cost);
    }
}

#[test]
fn stats_are_consistent_and_build_is_deterministic() {
    let scene = builtin::build("kitchen", Detail::Test).unwrap();
    let params = KdParams { parallel_min_tris: 256, ..KdParams::default() };
    let a = KdTree::build(&scene, &params).unwrap();
    let b = KdTree::build(&scene, &KdParams { parallel_min_tris: usize::MAX, ..params }).unwrap();
    assert_eq!(a.nodes(), b.nodes(), "parallel and sequential builds give the same tree");
    assert_eq!(a.tri_ids(), b.tri_ids());
    let s = a.stats();
    assert_eq!(s.nodes, s.inner + s.leaves);
    assert_eq!(s.leaves, s.inner + 1, "a binary tree has one more leaf than inner nodes");
    assert_eq!(s.tri_refs, a.tri_ids().len());
    assert!(s.max_depth <= params.depth_for(scene.triangle_count()));
    assert!(s.tri_refs >= scene.triangle_count(), "every triangle is in at least one leaf");
    assert_eq!(std::mem::size_of::<raylab_core::kdtree::KdNode>(), 8);
    // The leaf-order copy of the corners holds each reference's triangle.
    assert_eq!(a.ref_triangles().len(), a.tri_ids().len());
    for (r, &id) in a.tri_ids().iter().enumerate() {
        assert_eq!(a.ref_triangles().get(r as u32), a.triangles().get(id), "reference {r}");
    }
    // Children are adjacent and even-aligned.
    for n in a.nodes() {
        if !n.is_leaf() {
            assert_eq!(n.left() % 2, 0);
            assert!(n.left() + 1 < a.nodes().len());
        }
    }
}

#[test]
fn bad_parameters_are_refused() {
    let scene = builtin::build("arena", Detail::Test).unwrap();
    for p in [
        KdParams { c_isect: 0.0, ..KdParams::default() },
        KdParams { c_trav: f32::NAN, ..KdParams::default() },
        KdParams { empty_bonus: 1.0, ..KdParams::default() },
    ] {
        let e = KdTree::build(&scene, &p).unwrap_err().to_string();
        assert!(e.contains("invalid kd-tree parameters"), "{e}");
    }
}
