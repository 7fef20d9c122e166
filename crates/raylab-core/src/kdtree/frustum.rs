//! Frustum interval traversal (Tsakok 2008, 2.3.2 and Listing 4.2 with the omni-directional changes of
//! 4.1.2) with packet/leaf culling (4.1.4).
//!
//! A whole tile of rays with a common origin walks the tree as one interval `[near, far]` of distances from
//! the origin: at a split the [`Frustum`](crate::packet::Frustum) gives the range of distances at which its rays cross the plane,
//! the child on the origin's side is entered first, and the other child is pushed with the part of the
//! interval that lies beyond the earliest crossing. At a leaf, each 2x2 packet is first tested against the
//! leaf's box (culling, switchable) and then against the leaf's triangles. Entries on the stack that start
//! beyond every ray's closest hit are skipped, which ends the walk once all rays have hit.

use std::ops::Range;

use raylab_simd::{VMask, Vf32};

use super::mono::SPLIT_SLACK;
use super::{KdNode, KdParams, KdTree};
use crate::aabb::{Aabb, coord};
use crate::packet::hit_reach_lanes;
use crate::packet::{Bundle, PacketTester, PacketTile, overlaps_box};
use crate::ray::hit_reach;
use crate::stats::TraversalStats;

#[derive(Clone, Copy)]
struct Entry {
    node: u32,
    near: f32,
    far: f32,
}

const STACK: usize = KdParams::DEPTH_LIMIT as usize + 4;

/// The child of an inner node that a bundle from `origin` meets first (on the origin's side, thesis 4.1.2);
/// the other child is `front ^ 1`.
#[inline(always)]
pub(super) fn front_child(n: KdNode, origin: glam::Vec3) -> usize {
    n.left() | (n.split() - coord(&origin, n.axis()) < 0.0) as usize
}

/// A leaf reached by a frustum walk, and the distance at which the bundle can first be inside it.
#[derive(Clone, Copy)]
pub(super) struct Leaf<'a> {
    pub tree: &'a KdTree,
    pub node: KdNode,
    pub near: f32,
}

impl Leaf<'_> {
    /// Starts loading the leaf's triangles, once per leaf visit and before [`leaf_intersect`] looks up its
    /// box and culls its packets, so the first packet's tests wait less on their corners.
    #[inline(always)]
    pub(super) fn prefetch_triangles(&self) {
        let tris = self.tree.triangles();
        for &id in &self.tree.tri_ids()[self.node.leaf_range()] {
            tris.prefetch(id);
        }
    }
}

/// The batched culling verdicts ([`crate::packet::BatchCull`]) of one leaf for the last `SLOTS` chunks of
/// packets asked about, in a direct-mapped cache: a loop over packets in index order tests each chunk once
/// with one slot, and MFT's four quadrants, whose packets take turns in the same chunks (with eight lanes, a
/// quadrant of a 16x16 tile spans two chunks of eight 4x2 packets, shared with the quadrant beside it), need
/// four. Verdicts
/// stay valid while the leaf's packets find hits: a closer hit only makes a verdict more permissive than it
/// needs to be.
pub(super) struct BatchBits<const SLOTS: usize> {
    chunk: [usize; SLOTS],
    bits: [u32; SLOTS],
}

impl<const SLOTS: usize> Default for BatchBits<SLOTS> {
    fn default() -> Self {
        Self { chunk: [usize::MAX; SLOTS], bits: [0; SLOTS] }
    }
}

impl<const SLOTS: usize> BatchBits<SLOTS> {
    /// Bits (lane `i` for packet `chunk * LANES + i`) of the packets of `tile`'s chunk `chunk` that may have a
    /// ray inside `bounds` before their current hits: all of them when the tile has no batch data.
    #[inline(always)]
    fn may_enter<V: Vf32>(&mut self, tile: &PacketTile<V>, chunk: usize, bounds: &Aabb) -> u32 {
        let Some(batch) = &tile.batch else { return u32::MAX };
        let slot = chunk % SLOTS;
        if self.chunk[slot] != chunk {
            self.chunk[slot] = chunk;
            self.bits[slot] = batch.maybe_inside::<V>(chunk, bounds, &tile.farthest_hit, SPLIT_SLACK);
        }
        self.bits[slot]
    }
}

/// A run of a tile's packets seen as chunks of [`Vf32::LANES`] packets (the chunks of
/// [`crate::packet::BatchCull`]), one bit per member, so a leaf test checks a whole chunk's packets with a few
/// vector and bit operations and visits only those left: at most leaves, most of a frustum's packets are
/// culled (Table 4.2). A bundle bounds a run of its tile's packets (the whole tile, or an MFT quadrant in the
/// tile's quadrant-major order), so a set costs nothing to build.
#[derive(Clone, Debug)]
pub(super) struct ChunkSet {
    packets: Range<usize>,
}

impl ChunkSet {
    /// The packets `packets`.
    #[inline(always)]
    pub fn new(packets: Range<usize>) -> Self {
        Self { packets }
    }

    /// The chunks that hold a member, for lane type `V`.
    #[inline(always)]
    fn chunks<V: Vf32>(&self) -> Range<usize> {
        let Range { start, end } = self.packets;
        if start < end { start / V::LANES..end.div_ceil(V::LANES) } else { 0..0 }
    }

    /// The members of chunk `chunk` (one of [`ChunkSet::chunks`]): bit `i` for packet `chunk * LANES + i`.
    #[inline(always)]
    fn members<V: Vf32>(&self, chunk: usize) -> u32 {
        let base = chunk * V::LANES;
        let (lo, hi) = (self.packets.start.max(base) - base, self.packets.end.min(base + V::LANES) - base);
        ((1u32 << hi) - 1) & !((1u32 << lo) - 1)
    }
}

/// Tests `leaf` against packets `set` of `tile`, culling packets whose rays miss its box when `cull` is on
/// (`batch` holds this leaf's batched verdicts). Returns true when some lane's closest hit changed.
#[inline(always)]
pub(super) fn leaf_intersect<V: Vf32, const SLOTS: usize>(
    leaf: &Leaf,
    tile: &mut PacketTile<V>,
    set: &ChunkSet,
    cull: bool,
    batch: &mut BatchBits<SLOTS>,
    stats: &mut TraversalStats,
) -> bool {
    let tree = leaf.tree;
    let ids = &tree.tri_ids()[leaf.node.leaf_range()];
    if ids.is_empty() {
        return false;
    }
    let bounds = &tree.leaf_bounds(leaf.node);
    let mut changed = false;
    let done_before = leaf.near * (1.0 - SPLIT_SLACK);
    for chunk in set.chunks::<V>() {
        let members = set.members::<V>(chunk);
        // Packets whose rays all hit before the leaf starts (nothing here can be closer), then those whose rays
        // certainly miss its box, leave the chunk's bits.
        let first = chunk * V::LANES;
        let farthest = V::from_slice(&tile.farthest_hit[first..first + V::LANES]);
        let mut left = members & !farthest.lt(V::splat(done_before)).bits();
        if cull && left != 0 {
            left &= batch.may_enter(tile, chunk, bounds);
        }
        stats.packets_culled += (members & !left).count_ones() as u64;
        while left != 0 {
            let j = first + left.trailing_zeros() as usize;
            left &= left - 1;
            changed |= packet_intersect(tree, ids, bounds, tile, j, cull, stats);
        }
    }
    changed
}

/// [`leaf_intersect`] for packet `j`, which the chunk tests kept: culls it against the leaf box `bounds` ray by
/// ray (when `cull` is on), then tests triangles `ids`. Returns true when some lane's closest hit changed.
#[inline(always)]
fn packet_intersect<V: Vf32>(
    tree: &KdTree,
    ids: &[u32],
    bounds: &Aabb,
    tile: &mut PacketTile<V>,
    j: usize,
    cull: bool,
    stats: &mut TraversalStats,
) -> bool {
    let p = &tile.packets[j];
    let hits = &mut tile.hits[j];
    let active = if cull { overlaps_box(p, bounds, hit_reach_lanes(hits.t), SPLIT_SLACK) } else { p.valid };
    if active.none() {
        stats.packets_culled += 1;
        return false;
    }
    stats.packets_tested += 1;
    stats.isect_tests += ids.len() as u64;
    let packet_changed = PacketTester::new(p).intersect_each(hits, tree.triangles(), ids, active);
    if packet_changed {
        tile.farthest_hit[j] = hit_reach(V::select(p.valid, hits.t, V::splat(f32::NEG_INFINITY)).reduce_max());
    }
    packet_changed
}

/// Any-hit counterpart of [`leaf_intersect`]: marks lanes blocked by the leaf's triangles in `blocked`.
/// Returns how many packets of `set` this leaf finished (all their lanes blocked).
#[inline(always)]
pub(super) fn leaf_occlude<V: Vf32, const SLOTS: usize>(
    leaf: &Leaf,
    tile: &PacketTile<V>,
    set: &ChunkSet,
    cull: bool,
    batch: &mut BatchBits<SLOTS>,
    blocked: &mut [V::Mask],
    stats: &mut TraversalStats,
) -> usize {
    let tree = leaf.tree;
    let ids = &tree.tri_ids()[leaf.node.leaf_range()];
    if ids.is_empty() {
        return 0;
    }
    let bounds = &tree.leaf_bounds(leaf.node);
    let mut finished = 0;
    for chunk in set.chunks::<V>() {
        let mut bits = set.members::<V>(chunk);
        while bits != 0 {
            let lane = bits.trailing_zeros();
            bits &= bits - 1;
            let j = chunk * V::LANES + lane as usize;
            let p = &tile.packets[j];
            let mut open = p.valid & !blocked[j];
            if open.none() {
                continue;
            }
            if cull {
                if batch.may_enter(tile, chunk, bounds) >> lane & 1 == 0 {
                    stats.packets_culled += 1;
                    continue;
                }
                open = open & overlaps_box(p, bounds, p.tmax, SPLIT_SLACK);
                if open.none() {
                    stats.packets_culled += 1;
                    continue;
                }
            }
            stats.packets_tested += 1;
            let (hit, tests) = PacketTester::new(p).occlude_each(tree.triangles(), ids, open);
            stats.isect_tests += tests as u64;
            blocked[j] = blocked[j] | hit;
            finished += (p.valid & !blocked[j]).none() as usize;
        }
    }
    finished
}

/// What a frustum walk does at a leaf. A trait rather than a closure so that it is always inlined into the
/// walk, and so compiled with the kernel's target features (see [`raylab_simd::Kernel`]).
pub(super) trait FrustumLeaf {
    /// Whether the walk visits the child on the far side of each split from the origin first: any-hit walks
    /// of bundles built from the light toward the segments' surface ends ([`KdTree::occluded_frustum`]).
    const FAR_FIRST: bool = false;
    /// Tests `leaf`; returns the distance beyond which no ray needs more leaves, and whether the walk can stop.
    fn visit(&mut self, leaf: &Leaf, stats: &mut TraversalStats) -> (f32, bool);
}

/// Closest hits of the packets in `chunks`; `limit` is their farthest current hit.
struct ClosestLeaves<'a, V: Vf32> {
    tile: &'a mut PacketTile<V>,
    chunks: ChunkSet,
    cull: bool,
    limit: f32,
}

impl<V: Vf32> FrustumLeaf for ClosestLeaves<'_, V> {
    #[inline(always)]
    fn visit(&mut self, leaf: &Leaf, stats: &mut TraversalStats) -> (f32, bool) {
        leaf.prefetch_triangles();
        if leaf_intersect(leaf, self.tile, &self.chunks, self.cull, &mut BatchBits::<1>::default(), stats) {
            self.limit = hit_limit(self.tile, &self.chunks);
        }
        (self.limit, false)
    }
}

/// Occlusion of packets `set`: the walk stops once every lane is blocked. `FAR` sets
/// [`FrustumLeaf::FAR_FIRST`].
struct BlockedLeaves<'a, V: Vf32, const FAR: bool> {
    tile: &'a PacketTile<V>,
    set: ChunkSet,
    cull: bool,
    blocked: &'a mut [V::Mask],
    /// Packets of `set` with a lane not blocked yet.
    open: usize,
}

impl<V: Vf32, const FAR: bool> FrustumLeaf for BlockedLeaves<'_, V, FAR> {
    const FAR_FIRST: bool = FAR;

    #[inline(always)]
    fn visit(&mut self, leaf: &Leaf, stats: &mut TraversalStats) -> (f32, bool) {
        let batch = &mut BatchBits::<1>::default();
        self.open -= leaf_occlude(leaf, self.tile, &self.set, self.cull, batch, self.blocked, stats);
        (f32::INFINITY, self.open == 0)
    }
}

/// How many packets of `set` have a lane that is not blocked yet.
#[inline(always)]
pub(super) fn open_packets<V: Vf32>(tile: &PacketTile<V>, set: Range<usize>, blocked: &[V::Mask]) -> usize {
    // A plain loop: an iterator adapter may stay out of line, compiled without the kernel's instruction set
    // (see `crate::packet::map3`).
    let mut open = 0;
    for j in set {
        open += (tile.packets[j].valid & !blocked[j]).any() as usize;
    }
    open
}

/// The largest current hit distance over the lanes of the packets in `set` (infinite while any lane has
/// none), and at least 0: a chunk's farthest hits at a time, since a leaf that moved a hit asks it again.
#[inline(always)]
pub(super) fn hit_limit<V: Vf32>(tile: &PacketTile<V>, set: &ChunkSet) -> f32 {
    let mut limit = V::splat(0.0);
    for chunk in set.chunks::<V>() {
        let first = chunk * V::LANES;
        let farthest = V::from_slice(&tile.farthest_hit[first..first + V::LANES]);
        limit =
            limit.max(V::select(V::Mask::from_bits(set.members::<V>(chunk)), farthest, V::splat(f32::NEG_INFINITY)));
    }
    limit.reduce_max()
}

impl KdTree {
    /// Closest hits of the packets `set` of `tile`, whose rays share the origin of bundle `f` (a pyramid
    /// frustum or a cone) and lie inside it; results accumulate in `tile.hits`.
    #[inline(always)]
    pub fn intersect_frustum<B: Bundle, V: Vf32>(
        &self,
        f: &B,
        tile: &mut PacketTile<V>,
        set: Range<usize>,
        cull: bool,
        stats: &mut TraversalStats,
    ) {
        let chunks = ChunkSet::new(set);
        self.traverse_frustum(f, stats, &mut ClosestLeaves { tile, chunks, cull, limit: f32::INFINITY });
    }

    /// Marks in `blocked` the lanes of packets `set` that something blocks. The frustum `f` must bound the
    /// rays' segments; it may be built from the other end of the segments, e.g. from a light, and then
    /// `far_first` walks the far child of each split first: the blockers of a shadow segment lie mostly
    /// near its surface end, so starting there finishes packets sooner, with fewer triangle tests. From the
    /// surface end (the
    /// bundles of a point's light samples) the near child comes first.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub fn occluded_frustum<B: Bundle, V: Vf32>(
        &self,
        f: &B,
        tile: &PacketTile<V>,
        set: Range<usize>,
        cull: bool,
        far_first: bool,
        blocked: &mut [V::Mask],
        stats: &mut TraversalStats,
    ) {
        let open = open_packets(tile, set.clone(), blocked);
        let set = ChunkSet::new(set);
        if far_first {
            self.traverse_frustum(f, stats, &mut BlockedLeaves::<V, true> { tile, set, cull, blocked, open });
        } else {
            self.traverse_frustum(f, stats, &mut BlockedLeaves::<V, false> { tile, set, cull, blocked, open });
        }
    }

    /// Walks the leaves the frustum overlaps, roughly front to back (back to front where `L::FAR_FIRST`),
    /// handing each to `leaf`.
    #[inline(always)]
    pub(super) fn traverse_frustum<B: Bundle, L: FrustumLeaf>(&self, f: &B, stats: &mut TraversalStats, leaf: &mut L) {
        if self.triangles().is_empty() {
            return;
        }
        let nodes = self.nodes();
        let mut stack = [Entry { node: 0, near: 0.0, far: 0.0 }; STACK];
        let mut sp = 0usize;
        let (t_min, t_max) = f.t_range();
        let origin = f.origin();
        let (mut node, mut near, mut far) = (0usize, t_min, t_max);
        let (mut visited, mut leaves) = (0u64, 0u64);
        'walk: loop {
            let n = nodes[node];
            visited += 1;
            if !n.is_leaf() {
                let (lo, hi) = f.crossing(n.axis(), n.split());
                let front = front_child(n, origin);
                if hi < near * (1.0 - SPLIT_SLACK) {
                    node = front ^ 1;
                } else if lo > far * (1.0 + SPLIT_SLACK) {
                    node = front;
                } else if L::FAR_FIRST {
                    stack[sp] = Entry { node: front as u32, near, far: hi.min(far) };
                    sp += 1;
                    (node, near) = (front ^ 1, lo.max(near));
                } else {
                    stack[sp] = Entry { node: (front ^ 1) as u32, near: lo.max(near), far };
                    sp += 1;
                    (node, far) = (front, hi.min(far));
                }
                continue;
            }
            leaves += 1;
            let (limit, stop) = leaf.visit(&Leaf { tree: self, node: n, near }, stats);
            if stop {
                break;
            }
            loop {
                if sp == 0 {
                    break 'walk;
                }
                sp -= 1;
                let e = stack[sp];
                if e.near * (1.0 - SPLIT_SLACK) <= limit {
                    (node, near, far) = (e.node as usize, e.near, e.far);
                    break;
                }
            }
        }
        stats.nodes += visited;
        stats.leaves += leaves;
    }
}

#[cfg(test)]
mod tests {
    use raylab_simd::scalar::F32x4;

    use super::*;

    /// A run of packets falls into the chunks of four (the scalar lane type's width) that hold it, each
    /// packet once; an empty run has none.
    #[test]
    fn chunk_sets_hold_every_packet_once() {
        for (start, end) in [(0, 16), (5, 13), (3, 4), (4, 8), (7, 9), (0, 1)] {
            let set = ChunkSet::new(start..end);
            let mut got = Vec::new();
            for chunk in set.chunks::<F32x4>() {
                let members = set.members::<F32x4>(chunk);
                assert_ne!(members, 0, "{start}..{end}: chunk {chunk} holds no member");
                got.extend((0..4).filter(|i| members >> i & 1 == 1).map(|i| chunk * 4 + i));
            }
            assert_eq!(got, (start..end).collect::<Vec<_>>(), "{start}..{end}");
        }
        assert!(ChunkSet::new(6..6).chunks::<F32x4>().is_empty());
    }
}
