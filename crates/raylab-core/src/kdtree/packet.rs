//! Omni-directional packet traversal (Tsakok 2008, 4.1.2, Listing 4.1): the rays of a packet descend the
//! tree together, one SIMD lane each, with no restriction on direction signs and no packet splitting.
//!
//! The thesis's two changes to classic packet traversal are kept: the child on the origin's side of the
//! split is visited first, and negative plane distances count as infinite (the plane is behind the ray).
//! Lanes whose origins lie on different sides of a split get their own intervals for both children, so
//! packets of secondary rays with different origins stay exact. Each lane keeps an interval `[t_near,
//! t_far]`; a child is entered when any lane's interval in it is non-empty, and a popped cell is skipped
//! when every lane's part of it starts beyond that lane's closest hit.
//!
//! Edge-width walks need each lane's leaves front to back, which the origin rule does not give when lanes
//! start on both sides of a plane; their packets share direction signs and take the near child by sign
//! (`Front::Signs`), the classic rule, under which every lane's cells come in its own distance order.
//! Closest-hit and occlusion packets whose rays happen to share their signs (most coherent ones) walk the
//! same way, with the classic interval step when no direction component is zero: the same intervals as the
//! general step for such lanes, without its per-lane selects.

use raylab_simd::{VMask, Vf32};

use super::mono::SPLIT_SLACK;
use super::{KdNode, KdParams, KdTree};
use crate::packet::{PacketHits, PacketTester, RayPacket, slab_interval};
use crate::stats::TraversalStats;

#[derive(Clone, Copy)]
struct Entry<V: Vf32> {
    node: u32,
    t_near: V,
    t_far: V,
}

/// What a packet walk does at a leaf. A trait rather than a closure so that it is always inlined into the
/// walk, and so compiled with the kernel's target features (see [`raylab_simd::Kernel`]).
pub(super) trait PacketLeaf<V: Vf32> {
    /// Tests the leaf's triangles `ids` for the `active` lanes, whose intervals in the leaf end at `t_far`;
    /// returns each lane's current limit (its closest hit, or `tmax`) and the lanes that are finished.
    fn visit(&mut self, ids: std::ops::Range<usize>, active: V::Mask, t_far: V) -> (V, V::Mask);
}

/// Which child of an inner node a packet enters first.
#[derive(Clone, Copy)]
pub(super) enum Front {
    /// The child on the first active lane's origin side (Listing 4.1; any mix of directions).
    Origin,
    /// The child the shared direction signs meet first: bit `k` set when every lane's direction is
    /// negative on axis `k` (clear when every lane's is positive), as the sign of its inverse says.
    Signs(usize),
}

impl Front {
    /// [`Front::Signs`] when the packet's rays share their direction signs (every lane's cells then come in
    /// its own distance order, as with the origin rule), else [`Front::Origin`].
    #[inline(always)]
    pub(super) fn of<V: Vf32>(p: &RayPacket<V>) -> Front {
        let (valid, zero) = (p.valid.bits(), V::splat(0.0));
        let mut neg = 0;
        for k in 0..3 {
            match (p.inv[k].lt(zero) & p.valid).bits() {
                0 => {}
                bits if bits == valid => neg |= 1 << k,
                _ => return Front::Origin,
            }
        }
        Front::Signs(neg)
    }
}

/// Closest hits, kept in `hits`.
struct ClosestHits<'a, V: Vf32> {
    tree: &'a KdTree,
    p: &'a RayPacket<V>,
    hits: &'a mut PacketHits<V>,
    tests: u64,
}

impl<V: Vf32> PacketLeaf<V> for ClosestHits<'_, V> {
    #[inline(always)]
    fn visit(&mut self, ids: std::ops::Range<usize>, active: V::Mask, _: V) -> (V, V::Mask) {
        let ids = &self.tree.tri_ids()[ids];
        self.tests += ids.len() as u64;
        PacketTester::new(self.p).intersect_each(self.hits, self.tree.triangles(), ids, active);
        (crate::packet::hit_reach_lanes(self.hits.t), V::Mask::from_bits(0))
    }
}

/// Any hit: a lane is finished once something blocks it.
struct Blockers<'a, V: Vf32> {
    tree: &'a KdTree,
    p: &'a RayPacket<V>,
    blocked: V::Mask,
    tests: u64,
}

impl<V: Vf32> PacketLeaf<V> for Blockers<'_, V> {
    #[inline(always)]
    fn visit(&mut self, ids: std::ops::Range<usize>, active: V::Mask, _: V) -> (V, V::Mask) {
        let open = active & !self.blocked;
        if open.any() {
            let ids = &self.tree.tri_ids()[ids];
            let (hit, tests) = PacketTester::new(self.p).occlude_each(self.tree.triangles(), ids, open);
            self.tests += tests as u64;
            self.blocked = self.blocked | hit;
        }
        (self.p.tmax, self.blocked)
    }
}

/// A packet walk's traversal stack, kept by the caller and reused from packet to packet: an array on the
/// walk's own stack would be initialised for every packet (a few kilobytes with eight-lane entries, more
/// than the whole walk of a coherent shadow packet costs), while this one is allocated once and grows to
/// the tree's depth (each inner node pushes at most one entry).
pub struct PacketStack<V: Vf32> {
    entries: Vec<Entry<V>>,
}

impl<V: Vf32> Default for PacketStack<V> {
    fn default() -> Self {
        Self { entries: Vec::with_capacity(KdParams::DEPTH_LIMIT as usize + 4) }
    }
}

/// Lanes whose interval is non-empty, allowing the same slack as single-ray traversal.
#[inline(always)]
fn nonempty<V: Vf32>(t_near: V, t_far: V) -> V::Mask {
    (t_near * V::splat(1.0 - SPLIT_SLACK)).le(t_far * V::splat(1.0 + SPLIT_SLACK))
}

/// The children of inner node `n` in the order a packet walks them, and each lane's interval in both: the
/// child entered first, its intervals, the other child's intervals.
type Step<V> = (usize, (V, V), (V, V));

/// The general step (Listing 4.1 with the thesis's two modifications), for any mix of directions.
#[inline(always)]
fn origin_step<V: Vf32>(n: KdNode, p: &RayPacket<V>, front: Front, active: V::Mask, t_near: V, t_far: V) -> Step<V> {
    let axis = n.axis();
    let zero = V::splat(0.0);
    let dist = V::splat(n.split()) - p.org[axis];
    let d = dist * p.inv[axis];
    // Modification 1: a plane behind the ray is never reached.
    let d = V::select(d.lt(zero), V::splat(f32::INFINITY), d);
    // Modification 2: the front child is on the origin's side; the first active lane decides for the packet,
    // and lanes with origins on the other side swap their two intervals. An origin on the plane belongs to
    // the side its ray leaves (crossing at t = 0 into the other). Under shared signs the near child is the
    // front one, and a lane starting beyond the plane (which it never reaches) has all its interval in the
    // far child.
    let origin_right = dist.lt(zero) | (dist.eq(zero) & p.dir[axis].lt(zero));
    let front_right = match front {
        Front::Origin => origin_right.bits() >> active.bits().trailing_zeros() & 1 == 1,
        Front::Signs(neg) => (neg >> axis) & 1 == 1,
    };
    let same = if front_right { origin_right } else { !origin_right };
    let before = d.min(t_far);
    let after = d.max(t_near);
    (
        n.left() | front_right as usize,
        (V::select(same, t_near, after), V::select(same, before, t_far)),
        (V::select(same, after, t_near), V::select(same, t_far, before)),
    )
}

/// The classic step for lanes that share direction signs `neg` and have no zero direction component: the
/// near child by sign, the near interval up to the plane and the far one from it. For such lanes it gives
/// exactly [`origin_step`]'s intervals (a plane behind a lane leaves its near interval empty by itself)
/// without the per-lane side selects.
#[inline(always)]
fn signs_step<V: Vf32>(n: KdNode, p: &RayPacket<V>, neg: usize, t_near: V, t_far: V) -> Step<V> {
    let axis = n.axis();
    let d = (V::splat(n.split()) - p.org[axis]) * p.inv[axis];
    (n.left() | ((neg >> axis) & 1), (t_near, d.min(t_far)), (d.max(t_near), t_far))
}

impl KdTree {
    /// Closest hits of a packet's rays, written to `hits` (whose `t` may start below the rays' `tmax` to
    /// search only closer hits). Counts nodes, leaves and tests; the caller counts rays and packets.
    #[inline(always)]
    pub fn intersect_packet<V: Vf32>(
        &self,
        p: &RayPacket<V>,
        hits: &mut PacketHits<V>,
        stack: &mut PacketStack<V>,
        stats: &mut TraversalStats,
    ) {
        let mut leaf = ClosestHits { tree: self, p, hits, tests: 0 };
        self.traverse_packet(p, Front::of(p), stack, stats, &mut leaf);
        stats.isect_tests += leaf.tests;
    }

    /// The lanes whose rays are blocked within `(tmin, tmax]`.
    #[inline(always)]
    pub fn occluded_packet<V: Vf32>(
        &self,
        p: &RayPacket<V>,
        stack: &mut PacketStack<V>,
        stats: &mut TraversalStats,
    ) -> V::Mask {
        let mut leaf = Blockers { tree: self, p, blocked: V::Mask::from_bits(0), tests: 0 };
        self.traverse_packet(p, Front::of(p), stack, stats, &mut leaf);
        stats.isect_tests += leaf.tests;
        leaf.blocked
    }

    /// Walks the leaves the packet's rays cross, handing each to `leaf`; `front` picks the child entered first.
    #[inline(always)]
    pub(super) fn traverse_packet<V: Vf32>(
        &self,
        p: &RayPacket<V>,
        front: Front,
        stack: &mut PacketStack<V>,
        stats: &mut TraversalStats,
        leaf: &mut impl PacketLeaf<V>,
    ) {
        if self.triangles().is_empty() || p.valid.none() {
            return;
        }
        let (mut t_near, mut t_far) = slab_interval(p, &self.bounds(), p.tmin, p.tmax);
        let mut active = p.valid & nonempty(t_near, t_far);
        if active.none() {
            return;
        }
        let nodes = self.nodes();
        let inf = V::splat(f32::INFINITY);
        let stack = &mut stack.entries;
        stack.clear();
        let mut node = 0usize;
        let (mut visited, mut leaves) = (0u64, 0u64);
        let mut done = V::Mask::from_bits(0);
        'walk: loop {
            let n = nodes[node];
            visited += 1;
            if !n.is_leaf() {
                let (first, (f_near, f_far), (b_near, b_far)) = match front {
                    Front::Signs(neg) if p.finite_inv => signs_step(n, p, neg, t_near, t_far),
                    _ => origin_step(n, p, front, active, t_near, t_far),
                };
                let f_active = active & nonempty(f_near, f_far);
                let b_active = active & nonempty(b_near, b_far);
                let back = first ^ 1;
                if f_active.none() {
                    (node, t_near, t_far, active) = (back, b_near, b_far, b_active);
                    if b_active.none() {
                        match self.pop_packet(stack, p, done, &mut t_near, &mut t_far, &mut active, inf) {
                            Some(next) => node = next,
                            None => break 'walk,
                        }
                    }
                    continue;
                }
                if b_active.any() {
                    stack.push(Entry { node: back as u32, t_near: b_near, t_far: b_far });
                }
                (node, t_near, t_far, active) = (first, f_near, f_far, f_active);
                continue;
            }
            leaves += 1;
            let (limit, finished) = leaf.visit(n.leaf_range(), active & !done, t_far);
            done = done | finished;
            if (p.valid & !done).none() {
                break;
            }
            match self.pop_packet(stack, p, done, &mut t_near, &mut t_far, &mut active, limit) {
                Some(next) => node = next,
                None => break,
            }
        }
        stats.nodes += visited;
        stats.leaves += leaves;
    }

    /// Pops the next stack entry in which some unfinished lane's interval starts no later than its limit.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn pop_packet<V: Vf32>(
        &self,
        stack: &mut Vec<Entry<V>>,
        p: &RayPacket<V>,
        done: V::Mask,
        t_near: &mut V,
        t_far: &mut V,
        active: &mut V::Mask,
        limit: V,
    ) -> Option<usize> {
        while let Some(e) = stack.pop() {
            let a = p.valid & !done & nonempty(e.t_near, e.t_far) & nonempty(e.t_near, limit);
            if a.any() {
                (*t_near, *t_far, *active) = (e.t_near, e.t_far, a);
                return Some(e.node as usize);
            }
        }
        None
    }
}
