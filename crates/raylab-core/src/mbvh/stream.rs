//! MBVH ray stream tracing, "MBVH RS" (Tsakok 2009, Algorithm 1 and Listing 1): a whole group of rays walks
//! the 4-wide tree breadth-first. Each task is (node, lane, count): the `count` ray ids on top of lane
//! `lane`'s active-ray stack reached `node`. Every such ray is tested against the node's four boxes at once and
//! its id pushed onto the stack of each lane it hits; tasks for the children then go on the task stack,
//! ordered by the hit distances accumulated per lane (nearest last, so it is walked first). Shadow rays
//! leave the stream at their first hit.
//!
//! Leaves are tested one of two ways ([`StreamLeaves`]). The paper's: the active rays packed four at a time
//! into temporary SoA packets, each tested against one triangle per step, with one or two rays left over after
//! the whole packets testing the leaf's triangles four at a time instead (the single-ray leaf test), since a
//! packet of them would leave most lanes idle. The default: a vector's worth of rays at a time against the
//! leaf's four-triangle blocks, each group of four lanes one ray against four triangles
//! ([`crate::tri4::ShearGroups`]), with every ray's shear computed once per stream. Few rays reach a leaf
//! together in a scattered group (a handful per leaf visit, fewer in smaller groups), so
//! the paper's packets run part empty, while a block is full whenever the leaf is; and a packet gathers its
//! rays' constants anew at every leaf. The leaf counters (Figure 6's primitive tests) count SIMD tests:
//! packet against triangle, or ray against four triangles.
//!
//! What the box tests read of each ray (origin, inverse direction, `tmin`, current limit) lives in a 32-byte
//! record apart from the rest, so a 2^12-ray group's box data stays in the L2 cache. With eight SIMD lanes
//! (AVX2) two rays are tested against a node's four boxes at once, each in its own half; leaves still pack
//! rays four at a time. A task's rays go a vector's worth at a time (eight or four): their hit flags are
//! regrouped per child by a 4x4 transpose, and each child's hitting rays are left-packed onto its stack with
//! one vector store ([`Vf32::pack_u32`]) rather than one store and one branch-free add per ray and child.
//! When a leaf child gets rays, its triangles are prefetched, in the form its tests will read, while the
//! siblings before it on the task stack are walked.

use std::ops::Range;

use raylab_simd::{Backend, Kernel, VMask, Vf32};
use serde::{Deserialize, Serialize};

use super::Mbvh;
use super::node::MbvhNode;
use super::single::FAR_SLACK;
use crate::packet::{PacketHits, PacketTester, RayPacket};
use crate::ray::{Hit, Ray, hit_reach};
use crate::stats::TraversalStats;
use crate::tri4::{ShearGroups, ShearRecord, ShearX4};
use crate::triangle::RayShear;

/// Rays left over after whole packets of four, up to this many, are tested alone against the leaf.
const ALONE_MAX: usize = 2;

/// How MBVH RS tests the rays that reach a leaf against its triangles.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum StreamLeaves {
    /// The paper's leaves (Listing 1): the active rays packed four at a time into temporary SoA packets, each
    /// packet tested against one triangle per step; one or two rays left over test the leaf's triangles four
    /// at a time alone.
    Packets,
    /// A vector's worth of rays at a time against four-triangle blocks: two rays per eight-lane test, one per
    /// four-lane test ([`ShearGroups`]), every lane busy with a ray/triangle pair whatever the number of rays,
    /// and each ray's shear computed once per stream instead of at every leaf it reaches.
    #[default]
    Blocks,
}

impl StreamLeaves {
    /// Both, in the order menus list them.
    pub const ALL: [StreamLeaves; 2] = [StreamLeaves::Blocks, StreamLeaves::Packets];

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            StreamLeaves::Packets => "packets",
            StreamLeaves::Blocks => "blocks",
        }
    }
}

impl std::str::FromStr for StreamLeaves {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        StreamLeaves::ALL
            .into_iter()
            .find(|l| l.name() == s)
            .ok_or_else(|| format!("unknown MBVH RS leaf test '{s}' (valid: blocks, packets)"))
    }
}

/// How a stream is walked: the child ordering heuristic and the leaf test.
#[derive(Clone, Copy, Debug)]
pub struct StreamOptions {
    /// Order child tasks by accumulated hit length (the paper's heuristic); off walks them in lane order.
    pub ordered: bool,
    /// The leaf test.
    pub leaves: StreamLeaves,
}

/// How many of a leaf's `rays` are tested alone: the rays left after whole packets of four, when there are at
/// most [`ALONE_MAX`] of them.
fn alone_of(rays: usize) -> usize {
    if rays % 4 <= ALONE_MAX { rays % 4 } else { 0 }
}

/// A pending task: `count` rays on top of lane `lane`'s stack reached child `child` (a node, or a leaf when
/// `tris > 0`).
#[derive(Clone, Copy)]
struct Task {
    child: u32,
    tris: u32,
    lane: u8,
    count: u32,
}

/// What the box tests read of a ray, 32 bytes, kept apart from the rest so that a group of 2^12 rays' box
/// data stays in the L2 cache: two rows of four floats, origin and `tmin`, then inverse direction and the
/// current far limit (`tmax`, then [`Slot::reach`] of the closest hit so far; [`BLOCKED`] once a shadow ray
/// is blocked).
#[derive(Clone, Copy)]
#[repr(C, align(32))]
struct Hot {
    rows: [[f32; 4]; 2],
}

/// `Hot`'s far limit of a blocked shadow ray: below every `tmin`, so its box tests all fail.
const BLOCKED: f32 = f32::NEG_INFINITY;

impl Hot {
    fn new(ray: &Ray) -> Self {
        let (o, i) = (ray.origin, ray.inv_dir());
        Self { rows: [[o.x, o.y, o.z, ray.tmin], [i.x, i.y, i.z, ray.tmax]] }
    }

    fn limit(&self) -> f32 {
        self.rows[1][3]
    }

    fn limit_mut(&mut self) -> &mut f32 {
        &mut self.rows[1][3]
    }

    fn blocked(&self) -> bool {
        self.limit() == BLOCKED
    }
}

/// Entry distances and hit masks of `B::LANES / 4` rays (one or two: `rays[0]`, then `rays[1]`) against the
/// four boxes of `node`, ray `j` in lanes `4j..4j + 4`: per lane exactly the operations of the single-ray slab
/// test (`RaySlab::test`), the planes put in entry order by the direction's signs with selects instead of
/// branches, as rays in a group differ.
#[inline(always)]
fn test_boxes<B: Vf32>(node: &MbvhNode, rays: [&Hot; 2]) -> (B, B::Mask) {
    let per_test = B::LANES / 4;
    let [ox, oy, oz, tmin] = B::splat_rows(&[&rays[0].rows[0], &rays[1].rows[0]][..per_test]);
    let [ix, iy, iz, best] = B::splat_rows(&[&rays[0].rows[1], &rays[1].rows[1]][..per_test]);
    let (org, inv) = ([ox, oy, oz], [ix, iy, iz]);
    let zero = B::splat(0.0);
    let (mut near, mut far) = (tmin, best);
    for a in 0..3 {
        let lo = (B::repeat4(&node.min[a]) - org[a]) * inv[a];
        let hi = (B::repeat4(&node.max[a]) - org[a]) * inv[a];
        // An inverse is never NaN or -0 for a valid ray, so "negative" is its sign bit.
        let neg = inv[a].lt(zero);
        // SSE rule: a NaN entry/exit (origin on the plane, zero direction) keeps the other operand.
        near = B::select(neg, hi, lo).max(near);
        far = B::select(neg, lo, hi).min(far);
    }
    (near, near.le(far * B::splat(FAR_SLACK)))
}

/// Moves the ids of the rays in `ids` not yet blocked to its front, in order; returns how many there are.
fn keep_open(ids: &mut [u32], hot: &[Hot]) -> usize {
    let mut open = 0;
    for r in 0..ids.len() {
        let id = ids[r];
        ids[open] = id;
        open += usize::from(!hot[id as usize].blocked());
    }
    open
}

/// Every ray's state in a stream, indexed by the ray's position in the group.
struct StreamRays<'a> {
    /// What the box tests read.
    hot: &'a mut [Hot],
    /// The rays and their closest hits.
    slots: &'a mut [Slot],
    /// The leaf tests' constants (filled for [`StreamLeaves::Blocks`] only).
    records: &'a mut [ShearRecord],
}

/// Buffers for [`StreamRays`], kept per thread from group to group and backed by huge pages where the
/// kernel allows ([`raylab_simd::huge_pages`]): a 2^12-ray group's state, about 0.5 MiB, fills much of a
/// core's L2 cache, and with 4 KiB pages its placement, and so its cache conflicts, would change from
/// process to process and from group to group, and the speed with them.
#[derive(Default)]
struct Scratch {
    hot: Vec<Hot>,
    slots: Vec<Slot>,
    records: Vec<ShearRecord>,
}

thread_local! {
    static SCRATCH: std::cell::Cell<Scratch> = std::cell::Cell::new(Scratch::default());
}

/// `n` elements of `buf` starting at a 2 MiB boundary (so that they lie in pages the kernel may make huge),
/// reallocating `buf`, advised and filled with `fill`, when it is too short. Their values are whatever
/// earlier streams left.
fn aligned<T: Copy>(buf: &mut Vec<T>, n: usize, fill: T) -> &mut [T] {
    const HUGE: usize = 2 << 20;
    let size = std::mem::size_of::<T>();
    let lead = HUGE.div_ceil(size) + 1;
    if buf.len() < lead + n.max(lead) {
        let len = 2 * lead + n;
        let mut v = Vec::with_capacity(len);
        raylab_simd::huge_pages(v.spare_capacity_mut());
        v.resize(len, fill);
        *buf = v;
    }
    let start = buf.as_ptr() as usize;
    let offset = (start.next_multiple_of(HUGE) - start).div_ceil(size);
    &mut buf[offset..offset + n]
}

/// The rest of a ray's state in a stream.
#[derive(Clone, Copy)]
struct Slot {
    ray: Ray,
    hit: Option<Hit>,
}

impl Slot {
    /// The distance a closer hit must beat: the closest hit so far, or the ray's `tmax`.
    #[inline(always)]
    fn best_t(&self) -> f32 {
        self.hit.map_or(self.ray.tmax, |h| h.t)
    }

    /// The box tests' far limit: `tmax` until a hit is found, then [`hit_reach`] of it, so boxes starting
    /// just past the hit are still entered (see [`crate::ray::HIT_SLACK`]).
    #[inline(always)]
    fn reach(&self) -> f32 {
        self.hit.map_or(self.ray.tmax, |h| hit_reach(h.t))
    }
}

impl Mbvh {
    /// Closest hits of a group of rays traced together (`None` rays are skipped), in `backend`'s lanes.
    pub fn intersect_stream(
        &self,
        rays: &[Option<Ray>],
        out: &mut [Option<Hit>],
        options: StreamOptions,
        backend: Backend,
        stats: &mut TraversalStats,
    ) {
        let emit = |i: usize, _: &Hot, s: &Slot| out[i] = s.hit;
        raylab_simd::dispatch(
            backend.at_most_eight_lanes(),
            Stream { mbvh: self, rays, shadow: false, options, stats, emit },
        );
    }

    /// Occlusion of a group of rays traced together; each ray leaves the stream at its first blocker.
    pub fn occluded_stream(
        &self,
        rays: &[Option<Ray>],
        out: &mut [bool],
        options: StreamOptions,
        backend: Backend,
        stats: &mut TraversalStats,
    ) {
        let emit = |i: usize, h: &Hot, _: &Slot| out[i] = h.blocked();
        raylab_simd::dispatch(
            backend.at_most_eight_lanes(),
            Stream { mbvh: self, rays, shadow: true, options, stats, emit },
        );
    }

    /// Traces a group with box tests in `B` (one ray per four lanes) and leaf packets in `V` (four lanes).
    #[inline(always)]
    fn stream<B: Vf32, V: Vf32>(
        &self,
        rays: &[Option<Ray>],
        shadow: bool,
        options: StreamOptions,
        stats: &mut TraversalStats,
        mut emit: impl FnMut(usize, &Hot, &Slot),
    ) {
        let blocks = options.leaves == StreamLeaves::Blocks;
        assert_eq!(V::LANES, 4, "MBVH RS packs leaf rays four at a time");
        assert!(B::LANES == 4 || B::LANES == 8, "one or two rays per box test");
        // Every position gets a ray (`None` a placeholder) and state; only valid rays enter the walk.
        let placeholder = Ray::new(glam::Vec3::ZERO, glam::Vec3::Z);
        let mut scratch = SCRATCH.take();
        let n = rays.len();
        let mut state = StreamRays {
            hot: aligned(&mut scratch.hot, n, Hot::new(&placeholder)),
            slots: aligned(&mut scratch.slots, n, Slot { ray: placeholder, hit: None }),
            records: if blocks { aligned(&mut scratch.records, n, ShearRecord::new(&placeholder)) } else { &mut [] },
        };
        for (i, r) in rays.iter().enumerate() {
            let ray = r.unwrap_or(placeholder);
            state.hot[i] = Hot::new(&ray);
            state.slots[i] = Slot { ray, hit: None };
            if blocks {
                state.records[i] = ShearRecord::new(&ray);
            }
        }
        let ids: Vec<u32> =
            (0..rays.len() as u32).filter(|&i| rays[i as usize].is_some_and(|r| r.is_valid())).collect();
        stats.rays += ids.len() as u64;
        stats.packets += ids.len().div_ceil(4) as u64;
        if !self.tri_ids.is_empty() && !ids.is_empty() {
            self.walk_stream::<B, V>(&mut state, ids, shadow, options, stats);
        }
        for (i, (h, s)) in state.hot.iter().zip(state.slots.iter()).enumerate() {
            emit(i, h, s);
        }
        SCRATCH.set(scratch);
    }

    #[inline(always)]
    fn walk_stream<B: Vf32, V: Vf32>(
        &self,
        state: &mut StreamRays<'_>,
        ids: Vec<u32>,
        shadow: bool,
        options: StreamOptions,
        stats: &mut TraversalStats,
    ) {
        let StreamRays { hot, slots, records } = state;
        let blocks = options.leaves == StreamLeaves::Blocks;
        let n = ids.len() as u32;
        // Per lane, an active-ray stack: `lanes[k][..top[k]]` holds it. The storage only grows, so rays are
        // written without a branch on whether they hit the lane's box (the write is kept by advancing `top`).
        let mut top = [ids.len(), 0, 0, 0];
        let mut lanes: [Vec<u32>; 4] = [ids, Vec::new(), Vec::new(), Vec::new()];
        let mut tasks: Vec<Task> = vec![Task { child: 0, tris: 0, lane: 0, count: n }];
        let (mut fetches, mut box_tests, mut leaves, mut tests) = (0u64, 0u64, 0u64, 0u64);
        let (mut leaf_rays, mut slots4, mut slots8, mut slots16) = (0u64, 0u64, 0u64, 0u64);
        while let Some(task) = tasks.pop() {
            let lane = task.lane as usize;
            top[lane] -= task.count as usize;
            let start = top[lane];
            let mut end = start + task.count as usize;
            if shadow {
                // Shadow rays blocked since they were queued leave the stream here.
                end = start + keep_open(&mut lanes[lane][start..end], hot);
            }
            if task.tris > 0 {
                leaves += 1;
                let current = &lanes[lane][start..end];
                let c = current.len() as u64;
                leaf_rays += c;
                slots4 += c.div_ceil(4) * 4;
                slots8 += c.div_ceil(8) * 8;
                slots16 += c.div_ceil(16) * 16;
                let tri_slots = task.child as usize..(task.child + task.tris) as usize;
                if blocks {
                    tests += self.leaf_groups::<B>(hot, slots, records, current, tri_slots, shadow);
                    continue;
                }
                // Whole packets go through the paper's four-rays-per-triangle tests; a remainder of one or
                // two rays would leave most lanes idle, so each such ray takes the leaf's triangles four at a
                // time instead, as a single ray does.
                let alone = alone_of(current.len());
                let (packed, single) = current.split_at(current.len() - alone);
                for group in packed.chunks(4) {
                    tests += self.leaf_packet::<V>(hot, slots, group, tri_slots.clone(), shadow);
                }
                for &id in single {
                    let (h, s) = (&mut hot[id as usize], &mut slots[id as usize]);
                    tests += self.leaf_single::<V>(h, s, tri_slots.clone(), shadow);
                }
                continue;
            }
            fetches += 1;
            let node = &self.nodes[task.child as usize];
            let n = end - start;
            for (k, stack) in lanes.iter_mut().enumerate() {
                // Room for every ray of the task and one vector more: rays are read and pushed a vector at a
                // time (the own lane's `top` is `start`, so its room also covers the task's last read).
                if stack.len() < top[k] + n + B::LANES {
                    stack.resize(top[k] + n + B::LANES, 0);
                }
            }
            box_tests += n as u64;
            // The task's rays are taken `B::LANES` at a time: four box tests of `per_test` (one or two)
            // consecutive rays each, whose hit flags a 4x4 transpose regroups per child lane, so that each
            // lane's hitting rays are left-packed onto its stack by one vector store. That happens in place: a
            // lane's top never passes the next ray to read, since each ray pushes at most one entry per lane,
            // and the vector's rays were copied out before any store.
            let [l0, l1, l2, l3] = &mut lanes;
            let mut stacks = [&mut l0[..], &mut l1[..], &mut l2[..], &mut l3[..]];
            let mut tops = top;
            let (zero, flag) = (B::splat(0.0), B::splat(-1.0));
            let mut lengths = zero;
            let per_test = B::LANES / 4;
            let mut r = start;
            while r < end {
                let rem = (end - r).min(B::LANES);
                let ids = &stacks[lane][r..r + B::LANES];
                // After the transpose, lane `4g + p` of a child's flags is ray `per_test * p + g`'s: the ids in
                // that order, for the packing.
                let order = B::transpose4_ids(ids);
                let mut flags = [zero; 4];
                if rem == B::LANES {
                    for (p, flags) in flags.iter_mut().enumerate() {
                        let a = per_test * p;
                        let (near, hit) =
                            test_boxes::<B>(node, [&hot[ids[a] as usize], &hot[ids[a + per_test - 1] as usize]]);
                        lengths = lengths + B::select(hit, near, zero);
                        *flags = B::select(hit, flag, zero);
                    }
                } else {
                    for (p, flags) in flags.iter_mut().enumerate().take(rem.div_ceil(per_test)) {
                        let a = per_test * p;
                        // A chunk's odd last ray, when two share a test, is tested twice and the copy's hits are
                        // masked off.
                        let second = ids[(a + 1).min(rem - 1)];
                        let (near, mut hit) = test_boxes::<B>(node, [&hot[ids[a] as usize], &hot[second as usize]]);
                        if a + per_test > rem {
                            hit = hit & B::Mask::from_bits(0xF);
                        }
                        lengths = lengths + B::select(hit, near, zero);
                        *flags = B::select(hit, flag, zero);
                    }
                }
                for ((stack, top), hits) in stacks.iter_mut().zip(&mut tops).zip(B::transpose4(flags)) {
                    *top += B::pack_u32(&order, hits.lt(zero).bits(), &mut stack[*top..]);
                }
                r += B::LANES;
            }
            let pushed: [usize; 4] = std::array::from_fn(|k| tops[k] - top[k]);
            top = tops;
            for (k, &rays) in pushed.iter().enumerate() {
                if rays > 0 && node.is_leaf(k) {
                    // The leaf's triangles in the form its tests will read: corners for packets, blocks for
                    // rays alone.
                    let slots = node.child[k] as usize..(node.child[k] + node.count[k]) as usize;
                    let alone = if blocks { rays } else { alone_of(rays) };
                    if rays > alone {
                        raylab_simd::prefetch(self.tris.slice(slots.clone()));
                    }
                    if alone > 0 {
                        self.prefetch_leaf(slots);
                    }
                }
            }
            let mut sums = [0f32; 8];
            lengths.write_to(&mut sums[..B::LANES]);
            let lengths_out: [f32; 4] = std::array::from_fn(|k| sums[k] + sums[k + 4]);
            // Children with the largest accumulated length first on the stack, so the shortest is walked first.
            let mut order = [0usize, 1, 2, 3];
            if options.ordered {
                // Descending by length, ties in lane order: keys of (length bits, reversed lane) through a
                // five-comparator sorting network (lengths are sums of non-negative distances, so their bits
                // order like the values).
                let mut keys: [u64; 4] =
                    std::array::from_fn(|k| (u64::from(lengths_out[k].to_bits()) << 2) | (3 - k as u64));
                for (a, b) in [(0, 1), (2, 3), (0, 2), (1, 3), (1, 2)] {
                    let (hi, lo) = (keys[a].max(keys[b]), keys[a].min(keys[b]));
                    (keys[a], keys[b]) = (hi, lo);
                }
                order = keys.map(|key| 3 - (key & 3) as usize);
            }
            for k in order {
                if pushed[k] > 0 {
                    let count = pushed[k] as u32;
                    tasks.push(Task { child: node.child[k], tris: node.count[k], lane: k as u8, count });
                }
            }
        }
        stats.nodes += fetches;
        stats.box_tests += box_tests;
        stats.leaves += leaves;
        stats.isect_tests += tests;
        stats.leaf_rays += leaf_rays;
        stats.leaf_slots[0] += slots4;
        stats.leaf_slots[1] += slots8;
        stats.leaf_slots[2] += slots16;
    }

    /// Tests one ray against the leaf's triangles, four at a time; returns the number of block tests.
    /// Inlined, like every vector kernel here, so that it is compiled with the entry point's instruction set
    /// (out of line it was built for the x86-64 baseline, SSE2 without VEX).
    #[inline(always)]
    fn leaf_single<V: Vf32>(&self, hot: &mut Hot, slot: &mut Slot, tri_slots: Range<usize>, shadow: bool) -> u64 {
        let shear = ShearX4::<V>::new(&RayShear::new(&slot.ray));
        let blocks = tri_slots.len().div_ceil(4) as u64;
        if shadow {
            if self.blocker_in_leaf(&shear, tri_slots, slot.ray.tmin, slot.ray.tmax).0.is_some() {
                *hot.limit_mut() = BLOCKED;
            }
        } else {
            let mut best_t = slot.best_t();
            self.closest_in_leaf(&shear, tri_slots, slot.ray.tmin, &mut best_t, &mut slot.hit);
            *hot.limit_mut() = slot.reach();
        }
        blocks
    }

    /// Tests the `rays` that reached a leaf against its triangles `V::LANES / 4` rays at a time, each against
    /// a four-triangle block per test ([`ShearGroups`]); returns the number of ray/block tests.
    #[inline(always)]
    fn leaf_groups<V: Vf32>(
        &self,
        hot: &mut [Hot],
        slots: &mut [Slot],
        records: &mut [ShearRecord],
        rays: &[u32],
        tri_slots: Range<usize>,
        shadow: bool,
    ) -> u64 {
        let per = V::LANES / 4;
        let blocks = &self.blocks[tri_slots.start / 4..tri_slots.end.div_ceil(4)];
        let first = tri_slots.start / 4;
        let mut tests = 0;
        for chunk in rays.chunks(per) {
            // Groups past the chunk's rays repeat its last ray; their lanes are masked off.
            let last = chunk.len() - 1;
            let id = [0, 1, 2, 3].map(|g| chunk[g.min(last)] as usize);
            let recs = id.map(|i| &records[i]);
            let groups = ShearGroups::<V>::new(recs);
            let mut limits = ShearGroups::<V>::limits(recs);
            let valid = (1u32 << (4 * chunk.len())) - 1;
            if shadow {
                let mut open = valid;
                for block in blocks {
                    tests += u64::from(open.count_ones() / 4);
                    let mut bits = groups.test(block, limits, |g| slots[id[g]].ray).mask.bits() & open;
                    while bits != 0 {
                        let g = bits.trailing_zeros() / 4;
                        open &= !(0xF << (4 * g));
                        bits &= !(0xF << (4 * g));
                    }
                    if open == 0 {
                        break;
                    }
                }
                for (g, &ray) in chunk.iter().enumerate() {
                    if open >> (4 * g) & 0xF == 0 {
                        *hot[ray as usize].limit_mut() = BLOCKED;
                    }
                }
            } else {
                let mut found = 0u32;
                for (b, block) in blocks.iter().enumerate() {
                    tests += chunk.len() as u64;
                    let h = groups.test(block, limits, |g| slots[id[g]].ray);
                    let mut bits = h.mask.bits() & valid;
                    if bits == 0 {
                        continue;
                    }
                    let (mut t, mut u, mut v) = ([0f32; 16], [0f32; 16], [0f32; 16]);
                    h.t.write_to(&mut t[..V::LANES]);
                    h.u.write_to(&mut u[..V::LANES]);
                    h.v.write_to(&mut v[..V::LANES]);
                    while bits != 0 {
                        let lane = bits.trailing_zeros() as usize;
                        bits &= bits - 1;
                        let g = lane / 4;
                        let tri = self.tri_ids[4 * (first + b) + lane % 4];
                        let record = &mut records[id[g]];
                        if record.beaten_by(t[lane], tri) {
                            record.set_best(t[lane], tri);
                            slots[id[g]].hit = Some(Hit { t: t[lane], tri, u: u[lane], v: v[lane] });
                            found |= 1 << g;
                            limits = V::select(V::Mask::from_bits(0xF << (4 * g)), V::splat(t[lane]), limits);
                        }
                    }
                }
                while found != 0 {
                    let g = found.trailing_zeros() as usize;
                    found &= found - 1;
                    *hot[id[g]].limit_mut() = hit_reach(records[id[g]].tmax());
                }
            }
        }
        tests
    }

    /// Tests up to four rays, packed into a temporary SoA packet, against the leaf's triangles; returns the
    /// number of packet/triangle tests. Inlined for the entry point's instruction set, as [`Self::leaf_single`].
    #[inline(always)]
    fn leaf_packet<V: Vf32>(
        &self,
        hot: &mut [Hot],
        slots: &mut [Slot],
        group: &[u32],
        tri_slots: Range<usize>,
        shadow: bool,
    ) -> u64 {
        // Each lane straight from the slots (every stream ray is valid), limited by its closest hit so far
        // (shadow rays reach leaves only while unblocked, with their own `tmax`).
        let p = RayPacket::<V>::gather(|i| {
            group.get(i).map(|&id| {
                let slot = &slots[id as usize];
                Ray { tmax: if shadow { hot[id as usize].limit() } else { slot.best_t() }, ..slot.ray }
            })
        });
        let mut tests = 0;
        if shadow {
            let mut open = p.valid;
            let tester = PacketTester::new(&p);
            for slot in tri_slots {
                tests += 1;
                open = open & !tester.occlude(self.tris.get(slot as u32), open);
                if open.none() {
                    break;
                }
            }
            let blocked = p.valid.bits() & !open.bits();
            for (k, &id) in group.iter().enumerate() {
                if blocked >> k & 1 == 1 {
                    *hot[id as usize].limit_mut() = BLOCKED;
                }
            }
        } else {
            let mut hits = PacketHits::new(&p);
            let tester = PacketTester::new(&p);
            for slot in tri_slots {
                tests += 1;
                tester.intersect(&mut hits, self.tris.get(slot as u32), self.tri_ids[slot], p.valid);
            }
            let found = hits.to_hits();
            for (k, &id) in group.iter().enumerate() {
                let slot = &mut slots[id as usize];
                if let Some(h) = found.as_ref()[k]
                    && h.beats(slot.hit)
                {
                    slot.hit = Some(h);
                    *hot[id as usize].limit_mut() = slot.reach();
                }
            }
        }
        tests
    }
}

/// A group traced with the backend's lane type ([`raylab_simd::dispatch`]): eight lanes test two rays per node
/// and leave the leaves to SSE's four, four lanes do both. Under AVX-512 streams run as under AVX2
/// ([`raylab_simd::Backend::at_most_eight_lanes`]): four rays per node test leave more lanes idle in a
/// scattered stream than they save.
struct Stream<'a, F> {
    mbvh: &'a Mbvh,
    rays: &'a [Option<Ray>],
    shadow: bool,
    options: StreamOptions,
    stats: &'a mut TraversalStats,
    emit: F,
}

impl<F: FnMut(usize, &Hot, &Slot)> Kernel for Stream<'_, F> {
    type Output = ();
    #[inline(always)]
    fn run<V: Vf32>(self) {
        let Self { mbvh, rays, shadow, options, stats, emit } = self;
        #[cfg(target_arch = "x86_64")]
        if V::LANES == 8 {
            return mbvh.stream::<V, raylab_simd::sse::F32x4>(rays, shadow, options, stats, emit);
        }
        mbvh.stream::<V, V>(rays, shadow, options, stats, emit)
    }
}
