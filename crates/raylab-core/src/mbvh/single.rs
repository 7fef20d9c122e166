//! Single-ray MBVH traversal (MBVH RS paper, section 3.1): one ray against the four boxes of a node at once,
//! hit children visited nearest first, leaves' triangles tested four at a time with the watertight test
//! ([`crate::tri4`]). A node with one hit child hands it straight on and two are ordered with one comparison;
//! only three or four go through a small sort on the stack.
//!
//! The slab test takes each axis's entry and exit in the order the direction's sign gives and merges them with
//! comparisons that ignore NaN, so a zero direction component (infinite inverse) with the origin on a slab's
//! plane (`0 * inf = NaN`) leaves that axis unconstrained, as it should: the ray runs inside the plane. The far
//! distance is widened by a few ulps, so rounding never culls a box a ray grazes.

use std::ops::Range;

use raylab_simd::{Backend, Kernel, VMask, Vf32};

use super::Mbvh;
use super::node::MbvhNode;
use crate::ray::{Hit, Ray, hit_reach};
use crate::stats::TraversalStats;
use crate::tri4::{self, ShearX4};
use crate::triangle::RayShear;

/// Relative widening of a box's far distance (pbrt's `1 + 2 gamma(3)`).
pub(super) const FAR_SLACK: f32 = 1.0 + 2.0 * 3.0 * f32::EPSILON;
/// A ray's origin and inverse direction, splatted for the slab test, and which box side it enters first.
pub(super) struct RaySlab<V: Vf32> {
    org: [V; 3],
    inv: [V; 3],
    /// Per axis: the direction is positive (or +0), so the lower plane is entered first.
    pos: [bool; 3],
}

impl<V: Vf32> RaySlab<V> {
    pub(super) fn new(ray: &Ray) -> Self {
        let (org, inv) = (ray.origin.to_array(), ray.inv_dir().to_array());
        Self { org: org.map(V::splat), inv: inv.map(V::splat), pos: inv.map(|i| i.is_sign_positive()) }
    }

    /// Entry distances of the four boxes of `node` and the mask of those entered within `[t_min, t_max]`.
    #[inline(always)]
    pub(super) fn test(&self, node: &MbvhNode, t_min: f32, t_max: f32) -> (V, V::Mask) {
        let mut near = V::splat(t_min);
        let mut far = V::splat(t_max);
        for a in 0..3 {
            let (first, second) = if self.pos[a] { (&node.min[a], &node.max[a]) } else { (&node.max[a], &node.min[a]) };
            let enter = (V::from_slice(first) - self.org[a]) * self.inv[a];
            let leave = (V::from_slice(second) - self.org[a]) * self.inv[a];
            // SSE rule: a NaN `enter`/`leave` (origin on the plane, zero direction) keeps the other operand.
            near = enter.max(near);
            far = leave.min(far);
        }
        (near, near.le(far * V::splat(FAR_SLACK)))
    }
}

/// A stack entry: a node or a leaf lane to visit and the distance at which the ray enters it.
#[derive(Clone, Copy, Default)]
struct Entry {
    child: u32,
    count: u32,
    near: f32,
}

/// Stack entries for the deepest tree the build can make (48 SAH levels, then halving: under 81 levels, three
/// entries each).
const DEEP_STACK: usize = 256;
/// Stack entries for trees at most [`SHALLOW_DEPTH`] levels deep (all but pathological ones): a smaller array
/// costs less to set up per ray.
const SHALLOW_STACK: usize = 64;
/// Deepest tree the shallow stack serves (three entries a level, plus the root's four).
const SHALLOW_DEPTH: usize = (SHALLOW_STACK - 4) / 3;

/// What a walk does at each leaf it reaches ([`Mbvh::walk`]). A trait rather than a closure: a closure is
/// compiled on its own, for the x86-64 baseline, and called at every leaf, while this is inlined into the
/// SIMD entry point with the walk.
trait Leaves {
    /// Tests the leaf's triangles in `slots` (positions in `tri_ids` and in the leaf-ordered triangles), may
    /// lower `limit` (the farthest distance still of interest), and returns true to stop the walk.
    fn visit(&mut self, slots: Range<usize>, limit: &mut f32) -> bool;
}

/// Leaves of a closest-hit walk: every leaf may hold a closer hit.
struct Closest<'a, V: Vf32> {
    mbvh: &'a Mbvh,
    shear: ShearX4<V>,
    tmin: f32,
    best_t: f32,
    best: Option<Hit>,
    tests: u64,
}

impl<V: Vf32> Leaves for Closest<'_, V> {
    #[inline(always)]
    fn visit(&mut self, slots: Range<usize>, limit: &mut f32) -> bool {
        self.tests += slots.len() as u64;
        self.mbvh.closest_in_leaf(&self.shear, slots, self.tmin, &mut self.best_t, &mut self.best);
        *limit = hit_reach(self.best_t);
        false
    }
}

/// Leaves of an occlusion walk: the first blocker ends it.
struct Blocker<'a, V: Vf32> {
    mbvh: &'a Mbvh,
    shear: ShearX4<V>,
    tmin: f32,
    tmax: f32,
    found: Option<u32>,
    tests: u64,
}

impl<V: Vf32> Leaves for Blocker<'_, V> {
    #[inline(always)]
    fn visit(&mut self, slots: Range<usize>, _: &mut f32) -> bool {
        let (found, n) = self.mbvh.blocker_in_leaf(&self.shear, slots, self.tmin, self.tmax);
        self.tests += n;
        self.found = found;
        found.is_some()
    }
}

/// What a single-ray walk looks for: its leaves ([`Closest`] or [`Blocker`]) for the lane type the kernel
/// picked, and what it returns.
trait Query {
    type Output;
    fn walk<V: Vf32>(mbvh: &Mbvh, ray: &Ray, stats: &mut TraversalStats) -> Self::Output;
}

/// The closest hit.
struct ClosestHit;

impl Query for ClosestHit {
    type Output = Option<Hit>;
    #[inline(always)]
    fn walk<V: Vf32>(mbvh: &Mbvh, ray: &Ray, stats: &mut TraversalStats) -> Option<Hit> {
        let shear = ShearX4::<V>::new(&RayShear::new(ray));
        let mut leaves = Closest { mbvh, shear, tmin: ray.tmin, best_t: ray.tmax, best: None, tests: 0 };
        mbvh.walk_sized::<V>(ray, stats, &mut leaves);
        stats.isect_tests += leaves.tests;
        leaves.best
    }
}

/// The first blocker found.
struct FirstBlocker;

impl Query for FirstBlocker {
    type Output = Option<u32>;
    #[inline(always)]
    fn walk<V: Vf32>(mbvh: &Mbvh, ray: &Ray, stats: &mut TraversalStats) -> Option<u32> {
        let shear = ShearX4::<V>::new(&RayShear::new(ray));
        let mut leaves = Blocker { mbvh, shear, tmin: ray.tmin, tmax: ray.tmax, found: None, tests: 0 };
        mbvh.walk_sized::<V>(ray, stats, &mut leaves);
        stats.isect_tests += leaves.tests;
        leaves.found
    }
}

/// One ray's walk through [`raylab_simd::dispatch`]: on AVX2 CPUs the four-wide box and triangle tests are
/// compiled inside the AVX2 entry point (VEX encodings, SSE4.1's blends inlined); the node and leaf layouts
/// are four wide, so wider backends run them with SSE's lane type.
struct SingleRay<'a, Q> {
    mbvh: &'a Mbvh,
    ray: &'a Ray,
    stats: &'a mut TraversalStats,
    query: std::marker::PhantomData<Q>,
}

impl<Q: Query> Kernel for SingleRay<'_, Q> {
    type Output = Q::Output;
    #[inline(always)]
    fn run<V: Vf32>(self) -> Q::Output {
        #[cfg(target_arch = "x86_64")]
        if V::LANES > 4 {
            return Q::walk::<raylab_simd::sse::F32x4>(self.mbvh, self.ray, self.stats);
        }
        Q::walk::<V>(self.mbvh, self.ray, self.stats)
    }
}

impl Mbvh {
    /// The closest hit along `ray` in `(tmin, tmax]`, with the box tests in `backend`'s lanes.
    pub fn intersect(&self, ray: &Ray, backend: Backend, stats: &mut TraversalStats) -> Option<Hit> {
        self.single_ray::<ClosestHit>(ray, backend, stats)
    }

    /// True when anything blocks `ray` in `(tmin, tmax]`.
    pub fn occluded(&self, ray: &Ray, backend: Backend, stats: &mut TraversalStats) -> bool {
        self.occluder(ray, backend, stats).is_some()
    }

    /// The first blocker found along `ray` (not necessarily the nearest), for the shadow cache.
    pub fn occluder(&self, ray: &Ray, backend: Backend, stats: &mut TraversalStats) -> Option<u32> {
        self.single_ray::<FirstBlocker>(ray, backend, stats)
    }

    fn single_ray<Q: Query>(&self, ray: &Ray, backend: Backend, stats: &mut TraversalStats) -> Q::Output {
        let kernel = SingleRay::<Q> { mbvh: self, ray, stats, query: std::marker::PhantomData };
        raylab_simd::dispatch(backend.at_most_eight_lanes(), kernel)
    }

    /// [`tri4::closest_in_leaf`] on this tree's blocks.
    #[inline(always)]
    pub(super) fn closest_in_leaf<V: Vf32>(
        &self,
        shear: &ShearX4<V>,
        slots: Range<usize>,
        tmin: f32,
        best_t: &mut f32,
        best: &mut Option<Hit>,
    ) {
        tri4::closest_in_leaf(shear, &self.blocks, &self.tri_ids, slots, tmin, best_t, best);
    }

    /// Starts loading the four-triangle blocks of a leaf's `slots` into the cache.
    #[inline(always)]
    pub(super) fn prefetch_leaf(&self, slots: Range<usize>) {
        raylab_simd::prefetch(&self.blocks[slots.start / 4..slots.end.div_ceil(4)]);
    }

    /// [`tri4::blocker_in_leaf`] on this tree's blocks.
    #[inline(always)]
    pub(super) fn blocker_in_leaf<V: Vf32>(
        &self,
        shear: &ShearX4<V>,
        slots: Range<usize>,
        tmin: f32,
        tmax: f32,
    ) -> (Option<u32>, u64) {
        tri4::blocker_in_leaf(shear, &self.blocks, &self.tri_ids, slots, tmin, tmax)
    }

    /// True when triangle `tri` blocks `ray` (the shadow cache's test).
    pub fn blocks(&self, ray: &Ray, tri: u32) -> bool {
        ray.is_valid()
            && (tri as usize) < self.slot_of.len()
            && RayShear::new(ray).intersect(self.tris.get(self.slot_of[tri as usize]), ray.tmin, ray.tmax).is_some()
    }

    /// [`Mbvh::walk`] with the smallest stack this tree needs.
    #[inline(always)]
    fn walk_sized<V: Vf32>(&self, ray: &Ray, stats: &mut TraversalStats, leaf: &mut impl Leaves) {
        if self.depth <= SHALLOW_DEPTH {
            self.walk::<V, SHALLOW_STACK>(ray, stats, leaf);
        } else {
            self.walk::<V, DEEP_STACK>(ray, stats, leaf);
        }
    }

    /// Walks the leaves `ray` reaches, nearest child first, handing each to `leaf` ([`Leaves::visit`]).
    #[inline(always)]
    fn walk<V: Vf32, const STACK: usize>(&self, ray: &Ray, stats: &mut TraversalStats, leaf: &mut impl Leaves) {
        stats.rays += 1;
        stats.packets += 1;
        if self.tri_ids.is_empty() || !ray.is_valid() {
            return;
        }
        let slab = RaySlab::<V>::new(ray);
        let mut limit = ray.tmax;
        let mut stack = [Entry::default(); STACK];
        let mut sp = 0usize;
        let (mut nodes, mut leaves) = (0u64, 0u64);
        let mut cur = Entry { child: 0, count: 0, near: ray.tmin };
        'walk: loop {
            if cur.count == 0 {
                // Inner node: test its box packet. One hit child is entered directly, two are ordered with one
                // comparison, three or four are pushed and sorted on the stack; the nearest is entered next.
                nodes += 1;
                let n = &self.nodes[cur.child as usize];
                let (near, mask) = slab.test(n, ray.tmin, limit);
                let mut bits = mask.bits();
                if bits != 0 {
                    let mut dist = [0f32; 4];
                    near.write_to(&mut dist);
                    let entry = |k: usize| Entry { child: n.child[k], count: n.count[k], near: dist[k] };
                    let a = entry(bits.trailing_zeros() as usize);
                    bits &= bits - 1;
                    if bits == 0 {
                        cur = a;
                        continue;
                    }
                    let b = entry(bits.trailing_zeros() as usize);
                    bits &= bits - 1;
                    let (first, second) = if b.near < a.near { (b, a) } else { (a, b) };
                    if bits == 0 {
                        stack[sp] = second;
                        sp += 1;
                        cur = first;
                        continue;
                    }
                    // Three or four: push them and insertion-sort the new entries, farthest deepest.
                    let base = sp;
                    stack[sp] = second;
                    stack[sp + 1] = first;
                    sp += 2;
                    while bits != 0 {
                        let mut j = sp;
                        stack[j] = entry(bits.trailing_zeros() as usize);
                        bits &= bits - 1;
                        while j > base && stack[j - 1].near < stack[j].near {
                            stack.swap(j - 1, j);
                            j -= 1;
                        }
                        sp += 1;
                    }
                    sp -= 1;
                    cur = stack[sp];
                    continue;
                }
            } else {
                leaves += 1;
                let slots = cur.child as usize..(cur.child + cur.count) as usize;
                if leaf.visit(slots, &mut limit) {
                    break 'walk;
                }
            }
            // Pop the nearest pending child that may still hold something closer than the best hit.
            loop {
                if sp == 0 {
                    break 'walk;
                }
                sp -= 1;
                cur = stack[sp];
                if cur.near <= limit {
                    break;
                }
            }
        }
        stats.nodes += nodes;
        stats.leaves += leaves;
        stats.box_tests += nodes;
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::scene::{SceneBuilder, Triangle};

    /// Records the first slot of every leaf a walk visits.
    struct Record(Vec<usize>);

    impl Leaves for Record {
        fn visit(&mut self, slots: Range<usize>, _: &mut f32) -> bool {
            self.0.push(slots.start);
            false
        }
    }

    /// The deep-tree stack walks exactly like the shallow one.
    #[test]
    fn both_stack_sizes_walk_alike() {
        let mut b = SceneBuilder::new();
        for k in 0..300u32 {
            let o = Vec3::new((k % 17) as f32, (k / 17) as f32, (k % 5) as f32 * 0.3);
            let base = b.positions.len() as u32;
            b.positions.extend([o, o + Vec3::X * 0.8, o + Vec3::Y * 0.8]);
            b.triangles.push(Triangle { v: [base, base + 1, base + 2], material: 0 });
        }
        let m = Mbvh::build(&b.build());
        for k in 0..200 {
            let a = k as f32 * 0.37;
            let ray = Ray::new(Vec3::new(a.sin() * 3.0 + 8.0, a.cos() * 4.0 + 9.0, 5.0), Vec3::new(0.1, -0.05, -1.0));
            let (mut shallow, mut deep) = (Record(Vec::new()), Record(Vec::new()));
            let mut s = TraversalStats::default();
            m.walk::<raylab_simd::scalar::F32x4, SHALLOW_STACK>(&ray, &mut s, &mut shallow);
            m.walk::<raylab_simd::scalar::F32x4, DEEP_STACK>(&ray, &mut s, &mut deep);
            assert!(k > 0 || !shallow.0.is_empty(), "the first ray reaches leaves");
            assert_eq!(shallow.0, deep.0);
        }
    }
}
