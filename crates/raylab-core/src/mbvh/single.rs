//! Single-ray MBVH traversal (MBVH RS paper, section 3.1): one ray against the four boxes of a node at once,
//! hit children visited nearest first, leaves' triangles tested one by one with the watertight test.
//!
//! The slab test takes each axis's entry and exit in the order the direction's sign gives and merges them with
//! comparisons that ignore NaN, so a zero direction component (infinite inverse) with the origin on a slab's
//! plane (`0 * inf = NaN`) leaves that axis unconstrained, as it should: the ray runs inside the plane. The far
//! distance is widened by a few ulps, so rounding never culls a box a ray grazes.

use raylab_simd::{VMask, Vf32};

use super::Mbvh;
use super::node::MbvhNode;
use crate::ray::{Hit, Ray};
use crate::stats::TraversalStats;
use crate::triangle::RayShear;

/// Relative widening of a box's far distance (pbrt's `1 + 2 gamma(3)`).
const FAR_SLACK: f32 = 1.0 + 2.0 * 3.0 * f32::EPSILON;
/// A ray's origin and inverse direction, splatted for the slab test, and which box side it enters first.
pub(super) struct RaySlab<V: Vf32> {
    org: [V; 3],
    inv: [V; 3],
    /// Per axis: the direction is positive (or +0), so the lower plane is entered first.
    pos: [bool; 3],
}

impl<V: Vf32> RaySlab<V> {
    pub(super) fn new(ray: &Ray) -> Self {
        let (o, inv) = (ray.origin, ray.inv_dir());
        Self {
            org: [V::splat(o.x), V::splat(o.y), V::splat(o.z)],
            inv: [V::splat(inv.x), V::splat(inv.y), V::splat(inv.z)],
            pos: [inv.x, inv.y, inv.z].map(|i| i.is_sign_positive()),
        }
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
            // A NaN (origin on the plane, zero direction) fails both comparisons and changes nothing.
            near = V::select(enter.gt(near), enter, near);
            far = V::select(leave.lt(far), leave, far);
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

impl Mbvh {
    /// The closest hit along `ray` in `(tmin, tmax]`.
    pub fn intersect(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<Hit> {
        match self.backend {
            #[cfg(target_arch = "x86_64")]
            raylab_simd::Backend::Sse | raylab_simd::Backend::Avx2 => {
                self.intersect_with::<raylab_simd::sse::F32x4>(ray, stats)
            }
            _ => self.intersect_with::<raylab_simd::scalar::F32x4>(ray, stats),
        }
    }

    /// True when anything blocks `ray` in `(tmin, tmax]`.
    pub fn occluded(&self, ray: &Ray, stats: &mut TraversalStats) -> bool {
        match self.backend {
            #[cfg(target_arch = "x86_64")]
            raylab_simd::Backend::Sse | raylab_simd::Backend::Avx2 => {
                self.occluded_with::<raylab_simd::sse::F32x4>(ray, stats)
            }
            _ => self.occluded_with::<raylab_simd::scalar::F32x4>(ray, stats),
        }
    }

    fn intersect_with<V: Vf32>(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<Hit> {
        let shear = RayShear::new(ray);
        let mut best: Option<Hit> = None;
        let mut best_t = ray.tmax;
        let mut tests = 0u64;
        let mut leaf = |ids: &[u32], limit: &mut f32| {
            for &id in ids {
                tests += 1;
                if let Some(h) = shear.intersect(self.tris.get(id), ray.tmin, best_t) {
                    best_t = h.t;
                    best = Some(Hit { t: h.t, tri: id, u: h.u, v: h.v });
                }
            }
            *limit = best_t;
            false
        };
        self.walk_sized::<V>(ray, stats, &mut leaf);
        stats.isect_tests += tests;
        best
    }

    /// True when triangle `tri` blocks `ray` (the shadow cache's test).
    pub fn blocks(&self, ray: &Ray, tri: u32) -> bool {
        ray.is_valid()
            && (tri as usize) < self.tris.len()
            && RayShear::new(ray).intersect(self.tris.get(tri), ray.tmin, ray.tmax).is_some()
    }

    /// The first blocker found along `ray` (not necessarily the nearest), for the shadow cache.
    pub fn occluder(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<u32> {
        match self.backend {
            #[cfg(target_arch = "x86_64")]
            raylab_simd::Backend::Sse | raylab_simd::Backend::Avx2 => {
                self.occluder_with::<raylab_simd::sse::F32x4>(ray, stats)
            }
            _ => self.occluder_with::<raylab_simd::scalar::F32x4>(ray, stats),
        }
    }

    fn occluded_with<V: Vf32>(&self, ray: &Ray, stats: &mut TraversalStats) -> bool {
        self.occluder_with::<V>(ray, stats).is_some()
    }

    fn occluder_with<V: Vf32>(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<u32> {
        let shear = RayShear::new(ray);
        let mut blocker = None;
        let mut tests = 0u64;
        let mut leaf = |ids: &[u32], _: &mut f32| {
            for &id in ids {
                tests += 1;
                if shear.intersect(self.tris.get(id), ray.tmin, ray.tmax).is_some() {
                    blocker = Some(id);
                    return true;
                }
            }
            false
        };
        self.walk_sized::<V>(ray, stats, &mut leaf);
        stats.isect_tests += tests;
        blocker
    }

    /// [`Mbvh::walk`] with the smallest stack this tree needs.
    #[inline(always)]
    fn walk_sized<V: Vf32>(
        &self,
        ray: &Ray,
        stats: &mut TraversalStats,
        leaf: &mut impl FnMut(&[u32], &mut f32) -> bool,
    ) {
        if self.depth <= SHALLOW_DEPTH {
            self.walk::<V, SHALLOW_STACK>(ray, stats, leaf);
        } else {
            self.walk::<V, DEEP_STACK>(ray, stats, leaf);
        }
    }

    /// Walks the leaves `ray` reaches, nearest child first; `leaf(ids, limit)` tests a leaf's triangles,
    /// may lower `limit` (the farthest distance still of interest), and returns true to stop.
    #[inline(always)]
    fn walk<V: Vf32, const STACK: usize>(
        &self,
        ray: &Ray,
        stats: &mut TraversalStats,
        leaf: &mut impl FnMut(&[u32], &mut f32) -> bool,
    ) {
        stats.rays += 1;
        stats.packets += 1;
        if self.tri_ids.is_empty() || !ray.is_valid() {
            return;
        }
        let slab = RaySlab::<V>::new(ray);
        let mut limit = ray.tmax;
        let mut stack = [Entry::default(); STACK];
        let mut sp = 0usize;
        let (mut boxes, mut nodes, mut leaves) = (0u64, 0u64, 0u64);
        let mut node = 0usize;
        'walk: loop {
            // Inner node: test the box packet, push hit children far to near, continue with the nearest.
            nodes += 1;
            boxes += 1;
            let n = &self.nodes[node];
            let (near, mask) = slab.test(n, ray.tmin, limit);
            let bits = mask.bits() & n.used;
            let mut dist = [0f32; 4];
            near.write_to(&mut dist);
            let mut hits: [(f32, u32); 4] = [(0.0, 0); 4];
            let mut k = 0;
            for (lane, &d) in dist.iter().enumerate() {
                if bits >> lane & 1 == 1 {
                    hits[k] = (d, lane as u32);
                    k += 1;
                }
            }
            // Nearest last (popped first): a small insertion sort by distance, descending.
            for i in 1..k {
                let mut j = i;
                while j > 0 && hits[j - 1].0 < hits[j].0 {
                    hits.swap(j - 1, j);
                    j -= 1;
                }
            }
            for &(t, lane) in &hits[..k] {
                let lane = lane as usize;
                stack[sp] = Entry { child: n.child[lane], count: n.count[lane], near: t };
                sp += 1;
            }
            // Pop until an inner node comes up; leaves on the way are tested.
            loop {
                if sp == 0 {
                    break 'walk;
                }
                sp -= 1;
                let e = stack[sp];
                if e.near > limit {
                    continue;
                }
                if e.count == 0 {
                    node = e.child as usize;
                    continue 'walk;
                }
                leaves += 1;
                let ids = &self.tri_ids[e.child as usize..(e.child + e.count) as usize];
                if leaf(ids, &mut limit) {
                    break 'walk;
                }
            }
        }
        stats.nodes += nodes;
        stats.leaves += leaves;
        stats.box_tests += boxes;
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::scene::{SceneBuilder, Triangle};

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
            let mut leaves = (Vec::new(), Vec::new());
            let mut s = TraversalStats::default();
            m.walk::<raylab_simd::scalar::F32x4, SHALLOW_STACK>(&ray, &mut s, &mut |ids: &[u32], _: &mut f32| {
                leaves.0.push(ids[0]);
                false
            });
            m.walk::<raylab_simd::scalar::F32x4, DEEP_STACK>(&ray, &mut s, &mut |ids: &[u32], _: &mut f32| {
                leaves.1.push(ids[0]);
                false
            });
            assert_eq!(leaves.0, leaves.1);
        }
    }
}
