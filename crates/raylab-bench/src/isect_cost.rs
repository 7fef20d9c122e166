//! The cost of one triangle test, measured on a scene's own data, to split Table 3.1's trace stages into
//! traversal and intersection.
//!
//! A frame's kernels interleave node steps and triangle tests too finely to time apart (a clock read per leaf
//! would cost more than the tests). Instead the renderer counts the tests of each trace stage, and this module
//! times the same kernel on the same kind of work alone: packets (2x2, 4x2 or 4x4, as wide as the lanes) of the view's
//! primary rays, each tested against the triangles of the kd-tree leaves its rays end in (the leaves a
//! traversal tests last, holding both the hit and its neighbours' misses). The caches are warm here, so the
//! intersection share it gives is a lower bound.

use std::hint::black_box;
use std::ops::Range;
use std::time::{Duration, Instant};

use glam::Vec3;
use raylab_core::kdtree::KdTree;
use raylab_core::packet::{PacketHits, RayPacket, intersect_packet};
use raylab_core::ray::Ray;
use raylab_core::scene::Camera;
use raylab_core::stats::TraversalStats;
use raylab_simd::{Backend, Kernel, Vf32};

/// Seconds one packet-triangle test with `backend`'s packets takes on `tree`'s triangles, seen through
/// `camera` at `width x height` (`None` when no packet's rays hit anything).
pub fn seconds_per_packet_test(
    tree: &KdTree,
    camera: &Camera,
    width: u32,
    height: u32,
    backend: Backend,
) -> Option<f64> {
    raylab_simd::dispatch(backend, Measure { tree, camera, width, height })
}

/// Pixels between sampled packets, each way.
const STRIDE: u32 = 8;
/// Least time spent timing.
const MIN_TIME: Duration = Duration::from_millis(50);

/// The timing run as a [`Kernel`], so it uses the packets of the backend being measured.
struct Measure<'a> {
    tree: &'a KdTree,
    camera: &'a Camera,
    width: u32,
    height: u32,
}

impl Kernel for Measure<'_> {
    type Output = Option<f64>;
    #[inline(always)]
    fn run<V: Vf32>(self) -> Option<f64> {
        measure::<V>(self.tree, self.camera, self.width, self.height)
    }
}

#[inline(always)]
fn measure<V: Vf32>(tree: &KdTree, camera: &Camera, width: u32, height: u32) -> Option<f64> {
    let raster = camera.raster(width, height);
    let pw = V::LANES as u32 / 2;
    let mut work: Vec<(RayPacket<V>, Vec<u32>)> = Vec::new();
    for y in (0..height.saturating_sub(1)).step_by(STRIDE as usize) {
        for x in (0..width.saturating_sub(pw - 1)).step_by(STRIDE as usize) {
            let rays: Vec<Ray> = (0..V::LANES as u32).map(|i| raster.primary(x + i % pw, y + i / pw)).collect();
            let mut tris: Vec<u32> = rays
                .iter()
                .filter_map(|r| tree.intersect(r, &mut TraversalStats::default()).map(|h| leaves_at_hit(tree, r, h.t)))
                .flatten()
                .flat_map(|l| tree.tri_ids()[l].to_vec())
                .collect();
            tris.sort_unstable();
            tris.dedup();
            if !tris.is_empty() {
                let lanes: Vec<Option<Ray>> = rays.into_iter().map(Some).collect();
                work.push((RayPacket::new(&lanes), tris));
            }
        }
    }
    if work.is_empty() {
        return None;
    }
    let (mut tests, start) = (0u64, Instant::now());
    while start.elapsed() < MIN_TIME {
        for (p, tris) in &work {
            let mut hits = PacketHits::new(p);
            for &id in tris {
                intersect_packet(p, &mut hits, tree.triangles().get(id), id, p.valid);
            }
            black_box(&hits);
            tests += tris.len() as u64;
        }
    }
    Some(start.elapsed().as_secs_f64() / tests as f64)
}

/// The leaves just before and just after the hit at `t` along `r`: perfect splits often put a split plane
/// through the triangle hit, which then belongs to the cell on either side.
fn leaves_at_hit<'a>(tree: &'a KdTree, r: &'a Ray, t: f32) -> impl Iterator<Item = Range<usize>> + 'a {
    [1.0 - 1e-4, 1.0 + 1e-4].into_iter().map(move |k| leaf_at(tree, r.at(t * k)))
}

/// The triangle-id range of the leaf holding point `p` (on a split plane, the right-hand one).
fn leaf_at(tree: &KdTree, p: Vec3) -> Range<usize> {
    let nodes = tree.nodes();
    let mut i = 0;
    loop {
        let n = nodes[i];
        if n.is_leaf() {
            return n.leaf_range();
        }
        i = n.left() + (p[n.axis()] >= n.split()) as usize;
    }
}

#[cfg(test)]
mod tests {
    use raylab_core::kdtree::KdParams;
    use raylab_scene::builtin::{self, Detail};

    use super::*;

    /// A packet-triangle test takes some nanoseconds, not nothing and not microseconds; the leaf found for a
    /// the leaves on either side of a hit point hold the triangle hit (all but a few, at cell corners).
    #[test]
    fn a_test_costs_nanoseconds_and_leaves_hold_their_hits() {
        let scene = builtin::build("arena", Detail::Test).unwrap();
        let tree = KdTree::build(&scene, &KdParams::default()).unwrap();
        let camera = scene.views[0].camera;
        for backend in Backend::available() {
            let s = seconds_per_packet_test(&tree, &camera, 64, 48, backend).expect("the view sees the arena");
            assert!(s > 1e-10 && s < 1e-5, "{backend:?}: {s}");
        }
        let raster = camera.raster(64, 48);
        let (mut hits, mut held) = (0, 0);
        for y in 0..48 {
            for x in 0..64 {
                let r = raster.primary(x, y);
                if let Some(h) = tree.intersect(&r, &mut TraversalStats::default()) {
                    hits += 1;
                    held += leaves_at_hit(&tree, &r, h.t).any(|l| tree.tri_ids()[l].contains(&h.tri)) as u32;
                }
            }
        }
        assert!(hits > 1000 && held * 10 >= hits * 9, "{held} of {hits}");
    }
}
