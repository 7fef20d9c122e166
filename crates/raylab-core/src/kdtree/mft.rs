//! Multiple Frustum Traversal (Tsakok 2008, 4.1.5, Tables 4.3-4.4): a tile split into four quadrant
//! frustums that walk the tree together, one SIMD lane per frustum.
//!
//! Each lane keeps its own interval and the frustums share every node decision, so the tree is walked once
//! as for one large frustum; but a frustum that does not reach a child, or whose rays have all hit before
//! the child's interval starts ("completed"), is masked out there, and its packets skip that child's
//! leaves. The active mask is pushed with every stack entry. The per-lane interval update is the scalar
//! one of [`super::frustum`], done for four frustums at once, in the backend's four-lane vectors
//! ([`Vf32::Quad`]) whatever the width of the packets.

use std::ops::Range;

use raylab_simd::{VMask, Vf32};

use super::frustum::{BatchBits, ChunkSet, Leaf, front_child, hit_limit, leaf_intersect, leaf_occlude, open_packets};
use super::mono::SPLIT_SLACK;
use super::{KdParams, KdTree};
use crate::aabb::coord;
use crate::packet::{Bundle, PacketTile};
use crate::stats::TraversalStats;

/// The four-lane vectors of the frustum lanes when packets have `V`'s width.
type Q<V> = <V as Vf32>::Quad;

/// Four bundles (pyramid frustums or cones) with a common origin, one per SIMD lane, each through its
/// per-sign crossing factors, for the packets of a tile in `V`.
#[derive(Clone, Copy, Debug)]
pub struct Frustum4<V: Vf32> {
    origin: glam::Vec3,
    pos_near: [Q<V>; 3],
    pos_far: [Q<V>; 3],
    neg_near: [Q<V>; 3],
    neg_far: [Q<V>; 3],
    t_min: Q<V>,
    t_max: Q<V>,
    origin_slack: f32,
    /// Lanes that hold a bundle.
    valid: <Q<V> as Vf32>::Mask,
}

impl<V: Vf32> Frustum4<V> {
    /// Packs up to four bundles with the same origin; `None` entries leave a lane empty.
    #[inline(always)]
    pub fn new<B: Bundle>(f: [Option<B>; 4]) -> Option<Self> {
        assert_eq!(Q::<V>::LANES, 4, "MFT traces four bundles");
        let origin = f.iter().flatten().next()?.origin();
        assert!(f.iter().flatten().all(|x| x.origin() == origin), "MFT bundles share their origin");
        // Plain loops into arrays rather than closures per field, which may stay out of line (see `map3`):
        // `axes[k][j]` holds factor `j` of axis `k` ([`Bundle::factors`]) for the four lanes.
        let (inf, ninf) = (f32::INFINITY, f32::NEG_INFINITY);
        let mut axes = [[[inf; 4], [inf; 4], [ninf; 4], [ninf; 4]]; 3];
        let (mut t_min, mut t_max, mut origin_slack, mut valid) = ([inf; 4], [ninf; 4], 0.0f32, 0u32);
        for (i, x) in f.iter().enumerate() {
            if let Some(x) = x {
                for (k, axis) in axes.iter_mut().enumerate() {
                    let [pn, pf, nn, nf] = x.factors(k);
                    (axis[0][i], axis[1][i], axis[2][i], axis[3][i]) = (pn, pf, nn, nf);
                }
                (t_min[i], t_max[i]) = x.t_range();
                origin_slack = origin_slack.max(x.origin_slack());
                valid |= 1 << i;
            }
        }
        let [x, y, z] = &axes;
        Some(Self {
            origin,
            pos_near: [Q::<V>::from_slice(&x[0]), Q::<V>::from_slice(&y[0]), Q::<V>::from_slice(&z[0])],
            pos_far: [Q::<V>::from_slice(&x[1]), Q::<V>::from_slice(&y[1]), Q::<V>::from_slice(&z[1])],
            neg_near: [Q::<V>::from_slice(&x[2]), Q::<V>::from_slice(&y[2]), Q::<V>::from_slice(&z[2])],
            neg_far: [Q::<V>::from_slice(&x[3]), Q::<V>::from_slice(&y[3]), Q::<V>::from_slice(&z[3])],
            t_min: Q::<V>::from_slice(&t_min),
            t_max: Q::<V>::from_slice(&t_max),
            origin_slack,
            valid: <Q<V> as Vf32>::Mask::from_bits(valid),
        })
    }

    /// The origin the four bundles share.
    #[inline(always)]
    pub fn origin(&self) -> glam::Vec3 {
        self.origin
    }

    /// Per lane, the range of distances at which the bundle crosses `coordinate k = split`: the scalar
    /// [`Bundle::crossing`] in every lane, with one branch on the side of the shared origin.
    #[inline(always)]
    fn crossing(&self, k: usize, split: f32) -> (Q<V>, Q<V>) {
        let (dist, slack) = (split - coord(&self.origin, k), self.origin_slack);
        let [pos_near, pos_far, neg_near, neg_far] =
            [self.pos_near[k], self.pos_far[k], self.neg_near[k], self.neg_far[k]];
        if dist > slack {
            (Q::<V>::splat(dist - slack) * pos_near, Q::<V>::splat(dist + slack) * pos_far)
        } else if dist < -slack {
            (Q::<V>::splat(dist + slack) * neg_near, Q::<V>::splat(dist - slack) * neg_far)
        } else {
            (Q::<V>::splat(0.0), Q::<V>::splat(f32::INFINITY))
        }
    }
}

/// What an MFT walk does at a leaf (a trait rather than a closure, like `frustum::FrustumLeaf`).
trait MftLeaf<V: Vf32> {
    /// Whether the walk visits the far child of each split first (see [`KdTree::occluded_mft`]).
    const FAR_FIRST: bool = false;
    /// Tests `leaf` for the frustum lanes in `active` (bits), whose intervals start at `near`; returns each
    /// lane's distance limit and the lanes that are finished.
    fn visit(&mut self, leaf: &Leaf, near: [f32; 4], active: u32, stats: &mut TraversalStats) -> (Q<V>, u32);
}

/// Closest hits: `limit[i]` is the farthest current hit of frustum `i`'s packets.
struct ClosestLeaves<'a, V: Vf32> {
    tile: &'a mut PacketTile<V>,
    chunks: [ChunkSet; 4],
    cull: bool,
    limit: [f32; 4],
}

impl<V: Vf32> MftLeaf<V> for ClosestLeaves<'_, V> {
    #[inline(always)]
    fn visit(&mut self, leaf: &Leaf, near: [f32; 4], active: u32, stats: &mut TraversalStats) -> (Q<V>, u32) {
        // One set of batched verdicts for the four frustums: their packets share chunks.
        let batch = &mut BatchBits::<4>::default();
        leaf.prefetch_triangles();
        for (i, chunks) in self.chunks.iter().enumerate() {
            let leaf = Leaf { near: near[i], ..*leaf };
            if active >> i & 1 == 1 && leaf_intersect(&leaf, self.tile, chunks, self.cull, batch, stats) {
                self.limit[i] = hit_limit(self.tile, chunks);
            }
        }
        (Q::<V>::from_slice(&self.limit), 0)
    }
}

/// Occlusion: a frustum is finished once all its packets' lanes are blocked. `FAR` sets
/// [`MftLeaf::FAR_FIRST`].
struct BlockedLeaves<'a, V: Vf32, const FAR: bool> {
    tile: &'a PacketTile<V>,
    sets: [ChunkSet; 4],
    cull: bool,
    blocked: &'a mut [V::Mask],
    /// Per frustum, the packets with a lane not blocked yet.
    open: [usize; 4],
    done: u32,
}

impl<V: Vf32, const FAR: bool> MftLeaf<V> for BlockedLeaves<'_, V, FAR> {
    const FAR_FIRST: bool = FAR;

    #[inline(always)]
    fn visit(&mut self, leaf: &Leaf, near: [f32; 4], active: u32, stats: &mut TraversalStats) -> (Q<V>, u32) {
        let batch = &mut BatchBits::<4>::default();
        for (i, set) in self.sets.iter().enumerate() {
            if active >> i & 1 == 1 {
                let leaf = Leaf { near: near[i], ..*leaf };
                self.open[i] -= leaf_occlude(&leaf, self.tile, set, self.cull, batch, self.blocked, stats);
                if self.open[i] == 0 {
                    self.done |= 1 << i;
                }
            }
        }
        (Q::<V>::splat(f32::INFINITY), self.done)
    }
}

/// The four frustums' packet runs as [`ChunkSet`]s.
#[inline(always)]
fn chunk_sets(sets: &[Range<usize>; 4]) -> [ChunkSet; 4] {
    let [a, b, c, d] = sets.clone();
    [ChunkSet::new(a), ChunkSet::new(b), ChunkSet::new(c), ChunkSet::new(d)]
}

/// A pending child: its node, the four frustums' intervals there and the frustums that reach it.
#[derive(Clone, Copy)]
struct Entry<Q: Vf32> {
    node: u32,
    near: Q,
    far: Q,
    active: Q::Mask,
}

const STACK: usize = KdParams::DEPTH_LIMIT as usize + 4;

impl KdTree {
    /// Closest hits of the packets of `tile`; `sets[i]` is the run of packets that frustum lane `i` bounds.
    #[inline(always)]
    pub fn intersect_mft<V: Vf32>(
        &self,
        f: &Frustum4<V>,
        tile: &mut PacketTile<V>,
        sets: &[Range<usize>; 4],
        cull: bool,
        stats: &mut TraversalStats,
    ) {
        let chunks = chunk_sets(sets);
        self.traverse_mft(f, stats, &mut ClosestLeaves { tile, chunks, cull, limit: [f32::INFINITY; 4] });
    }

    /// Marks in `blocked` the lanes of `tile`'s packets that something blocks; `sets[i]` is the run of
    /// packets that frustum lane `i` bounds. `far_first` walks the far child of each split first, for
    /// frustums built from the segments' other end, as in [`KdTree::occluded_frustum`].
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub fn occluded_mft<V: Vf32>(
        &self,
        f: &Frustum4<V>,
        tile: &PacketTile<V>,
        sets: &[Range<usize>; 4],
        cull: bool,
        far_first: bool,
        blocked: &mut [V::Mask],
        stats: &mut TraversalStats,
    ) {
        // Written out rather than with `array::from_fn`, which may stay out of line (see `map3`).
        let open = [
            open_packets(tile, sets[0].clone(), blocked),
            open_packets(tile, sets[1].clone(), blocked),
            open_packets(tile, sets[2].clone(), blocked),
            open_packets(tile, sets[3].clone(), blocked),
        ];
        let sets = chunk_sets(sets);
        if far_first {
            self.traverse_mft(f, stats, &mut BlockedLeaves::<V, true> { tile, sets, cull, blocked, open, done: 0 });
        } else {
            self.traverse_mft(f, stats, &mut BlockedLeaves::<V, false> { tile, sets, cull, blocked, open, done: 0 });
        }
    }

    /// Walks the leaves the four frustums overlap, handing each to `leaf`: nearest first from the shared
    /// origin, or farthest first where `L::FAR_FIRST`.
    #[inline(always)]
    fn traverse_mft<V: Vf32, L: MftLeaf<V>>(&self, f: &Frustum4<V>, stats: &mut TraversalStats, leaf: &mut L) {
        if self.triangles().is_empty() || f.valid.none() {
            return;
        }
        type M<V> = <Q<V> as Vf32>::Mask;
        let lo_slack = Q::<V>::splat(1.0 - SPLIT_SLACK);
        let hi_slack = Q::<V>::splat(1.0 + SPLIT_SLACK);
        let nodes = self.nodes();
        let zero = Q::<V>::splat(0.0);
        let mut stack = [Entry { node: 0, near: zero, far: zero, active: M::<V>::from_bits(0) }; STACK];
        let mut sp = 0usize;
        let (t_min, t_max, origin) = (f.t_min, f.t_max, f.origin);
        let (mut node, mut near, mut far) = (0usize, t_min, t_max);
        let mut active = f.valid;
        let mut done = M::<V>::from_bits(0);
        let (mut visited, mut leaves) = (0u64, 0u64);
        'walk: loop {
            let n = nodes[node];
            visited += 1;
            if !n.is_leaf() {
                let (lo, hi) = f.crossing(n.axis(), n.split());
                let front = front_child(n, origin);
                // Per frustum: all its rays cross before its interval (back only) or after it (front only).
                let back_only = hi.lt(near * lo_slack);
                let front_only = lo.gt(far * hi_slack);
                let f_active = active & !back_only;
                let b_active = active & !front_only;
                let (f_far, b_near) = (hi.min(far), lo.max(near));
                if f_active.none() {
                    (node, near, active) = (front ^ 1, b_near, b_active);
                    continue;
                }
                if L::FAR_FIRST && b_active.any() {
                    stack[sp] = Entry { node: front as u32, near, far: f_far, active: f_active };
                    sp += 1;
                    (node, near, active) = (front ^ 1, b_near, b_active);
                    continue;
                }
                if b_active.any() {
                    stack[sp] = Entry { node: (front ^ 1) as u32, near: b_near, far, active: b_active };
                    sp += 1;
                }
                (node, far, active) = (front, f_far, f_active);
                continue;
            }
            leaves += 1;
            let mut near4 = [0.0f32; 4];
            near.write_to(&mut near4);
            // Each frustum lane has its own entry distance: the visitor sets `near` from `near4` per lane.
            let leaf_at = Leaf { tree: self, node: n, near: 0.0 };
            let (limit, finished) = leaf.visit(&leaf_at, near4, (active & !done).bits(), stats);
            done = done | M::<V>::from_bits(finished);
            if (f.valid & !done).none() {
                break;
            }
            loop {
                if sp == 0 {
                    break 'walk;
                }
                sp -= 1;
                let e = stack[sp];
                let a = e.active & !done & (e.near * lo_slack).le(limit);
                if a.any() {
                    (node, near, far, active) = (e.node as usize, e.near, e.far, a);
                    break;
                }
            }
        }
        stats.nodes += visited;
        stats.leaves += leaves;
    }
}
