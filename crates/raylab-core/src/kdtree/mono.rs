//! Single-ray ("mono") kd-tree traversal (Tsakok 2008, Listing 2.2).
//!
//! Iterative, with an explicit stack of `(node, t_near, t_far)` entries and the inverse direction computed
//! once per ray. The near child is chosen by the direction's sign on the split axis; a split distance past
//! the interval visits only the near child, one before it only the far child. Both are visited when the
//! plane cuts the interval, and also when the distance is NaN (origin on the plane with a zero direction
//! component: the ray runs inside the plane, and triangles of either child may touch it). Leaves come front
//! to back, so once a hit is found every stack entry that starts beyond it is skipped. Distance comparisons
//! allow [`SPLIT_SLACK`] so that rounding never skips a cell a ray only grazes.

use std::ops::Range;

use crate::intersector::Intersector;
use crate::ray::{Hit, Ray, hit_reach};
use crate::stats::TraversalStats;
use crate::triangle::RayShear;

use super::{KdNode, KdParams, KdTree};

/// What a leaf visitor tells the traversal.
pub(super) enum Next {
    /// Keep going; stack entries that start beyond the given distance are skipped.
    Continue(f32),
    /// Stop the traversal.
    Stop,
}

#[derive(Clone, Copy, Default)]
struct Entry {
    node: u32,
    t_near: f32,
    t_far: f32,
}

const STACK: usize = KdParams::DEPTH_LIMIT as usize + 4;

/// Relative slack on split distances: 8 ulps. `(split - o) * inv` carries about 1.5 ulps of rounding, so
/// two planes that the ray crosses at the same point (a cell corner, where a triangle's vertex may sit) can
/// come out in either order; the slack makes such near-coincident crossings visit both children instead of
/// skipping the cell between them.
pub const SPLIT_SLACK: f32 = 8.0 * f32::EPSILON;

impl KdTree {
    /// The closest hit along `ray` in `(tmin, tmax]`, traced alone.
    pub fn intersect(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<Hit> {
        let shear = RayShear::new(ray);
        let mut best: Option<Hit> = None;
        let mut best_t = ray.tmax;
        // How far cells may still hold a closer hit, updated with `best_t` (most leaves add no hit).
        let mut reach = hit_reach(best_t);
        let mut tests = 0u64;
        self.traverse(ray, stats, |ids, _, _| {
            for slot in ids {
                tests += 1;
                if let Some(h) = shear.intersect(self.ref_triangles().get(slot as u32), ray.tmin, best_t) {
                    let id = self.tri_ids()[slot];
                    let h = Hit { t: h.t, tri: id, u: h.u, v: h.v };
                    if h.beats(best) {
                        best_t = h.t;
                        reach = hit_reach(best_t);
                        best = Some(h);
                    }
                }
            }
            Next::Continue(reach)
        });
        stats.isect_tests += tests;
        best
    }

    /// True when anything blocks `ray` in `(tmin, tmax]`; stops at the first blocker found.
    pub fn occluded(&self, ray: &Ray, stats: &mut TraversalStats) -> bool {
        self.occluder(ray, stats).is_some()
    }

    /// The first blocker found along `ray` in `(tmin, tmax]` (not necessarily the nearest), for the shadow
    /// cache.
    pub fn occluder(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<u32> {
        let shear = RayShear::new(ray);
        let mut blocker = None;
        let mut tests = 0u64;
        self.traverse(ray, stats, |ids, _, _| {
            for slot in ids {
                tests += 1;
                if shear.intersect(self.ref_triangles().get(slot as u32), ray.tmin, ray.tmax).is_some() {
                    blocker = Some(self.tri_ids()[slot]);
                    return Next::Stop;
                }
            }
            Next::Continue(ray.tmax)
        });
        stats.isect_tests += tests;
        blocker
    }

    /// True when triangle `tri` blocks `ray` in `(tmin, tmax]` (one test, not counted).
    pub fn blocks(&self, ray: &Ray, tri: u32) -> bool {
        (tri as usize) < self.triangles().len()
            && ray.is_valid()
            && RayShear::new(ray).intersect(self.triangles().get(tri), ray.tmin, ray.tmax).is_some()
    }

    /// Walks the leaves that `ray` crosses, front to back, calling `leaf(ids, t_near, t_far)` for each.
    #[inline(always)]
    pub(super) fn traverse(
        &self,
        ray: &Ray,
        stats: &mut TraversalStats,
        mut leaf: impl FnMut(Range<usize>, f32, f32) -> Next,
    ) {
        stats.rays += 1;
        stats.packets += 1;
        if self.triangles().is_empty() || !ray.is_valid() {
            return;
        }
        let inv = ray.inv_dir();
        let Some((mut t_near, mut t_far)) = self.bounds().clip_ray(ray.origin, inv, ray.tmin, ray.tmax) else {
            return;
        };
        let (origin, inv) = (ray.origin.to_array(), inv.to_array());
        // Bit k is set when the direction is negative on axis k; then the right child is the near one. (Taken
        // from a register: a per-axis table would put a load on the node-to-node dependency chain.)
        let neg = inv.iter().enumerate().fold(0u32, |m, (k, v)| m | ((v.is_sign_negative() as u32) << k));
        let signs = KdNode::sign_pattern(neg);
        // Origin and inverse direction side by side, so a node's axis fetches both in one load.
        let line: [[f32; 2]; 3] = std::array::from_fn(|k| [origin[k], inv[k]]);
        let nodes = self.nodes();
        let mut stack = [Entry::default(); STACK];
        let mut sp = 0usize;
        let mut node = 0usize;
        let (mut visited, mut leaves) = (0u64, 0u64);
        'walk: loop {
            let n = nodes[node];
            visited += 1;
            if !n.is_leaf() {
                let axis = n.axis();
                let [o, iv] = line[axis];
                let t_split = (n.split() - o) * iv;
                let near = n.near_child(signs);
                let far = near ^ 1;
                if t_split > t_far * (1.0 + SPLIT_SLACK) {
                    node = near;
                } else if t_split < t_near * (1.0 - SPLIT_SLACK) {
                    node = far;
                } else {
                    // Plain selects rather than `f32::max`/`min`: a NaN split distance (ray inside the plane)
                    // keeps the current bounds, as it must, and each compiles to one `maxss`/`minss`.
                    let far_near = if t_split > t_near { t_split } else { t_near };
                    stack[sp] = Entry { node: far as u32, t_near: far_near, t_far };
                    sp += 1;
                    t_far = if t_split < t_far { t_split } else { t_far };
                    node = near;
                }
                continue;
            }
            leaves += 1;
            let limit = match leaf(n.leaf_range(), t_near, t_far) {
                Next::Stop => break 'walk,
                Next::Continue(limit) => limit,
            };
            // Entries that start beyond the best hit are skipped, not a reason to stop: a ray lying in a split
            // plane pushes a far child whose interval overlaps the near one, so one may sit deeper in the
            // stack than entries that start later.
            loop {
                if sp == 0 {
                    break 'walk;
                }
                sp -= 1;
                let e = stack[sp];
                if e.t_near * (1.0 - SPLIT_SLACK) <= limit {
                    (node, t_near, t_far) = (e.node as usize, e.t_near, e.t_far);
                    break;
                }
            }
        }
        stats.nodes += visited;
        stats.leaves += leaves;
    }
}

impl Intersector for KdTree {
    fn intersect(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<Hit> {
        KdTree::intersect(self, ray, stats)
    }
    fn occluded(&self, ray: &Ray, stats: &mut TraversalStats) -> bool {
        KdTree::occluded(self, ray, stats)
    }
}
