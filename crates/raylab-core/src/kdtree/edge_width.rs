//! Edge-width shadow rays through the kd-tree (Tsakok 2008, Listing 5.1), one at a time or in packets.
//!
//! A walk is the ordinary traversal; only leaves differ. Every triangle of a leaf is tested without
//! culling (entries and exits both matter), its crossings go to the [`EdgeWidth`] state, and the crossings up
//! to the leaf's far end are committed in order. Leaves come front to back, so the walk can stop as soon as a
//! chord reaches the radius.
//!
//! Packet walks trace several such rays together: each lane has its own state and its own leaf intervals,
//! and lanes stop one by one. The pairing needs every lane's leaves in its own distance order, so a packet
//! holds only rays whose directions share signs and descends near child first by those signs
//! ([`Front::Signs`]). A lane's crossings are those the single walk finds (the packet triangle test repeats
//! the scalar test's arithmetic per lane), so both give the same occlusion.
//!
//! Bundle walks trace all the segments of a tile at once, as one frustum or cone walk from the light the
//! segments end at (the bundles hard shadows use): the tree is descended once for the tile rather
//! than once per packet, and each leaf is tested against the packets that reach its box. Leaves then come
//! in the light's order, not in each lane's, so a lane gathers all its crossings and pairs them once at the
//! end, as the brute-force reference does; the single walk's early stop (a chord of at least R) only skips
//! crossings that cannot lower the occlusion, so all three agree.

use std::ops::Range;

use glam::Vec3;
use raylab_simd::{VMask, Vf32};

use crate::aabb::Aabb;
use crate::edge_width::{Crossing, EdgeWidth};
use crate::packet::{BatchCull, Bundle, PacketTester, PacketTile, RayPacket, map3, overlaps_box};
use crate::ray::Ray;
use crate::stats::TraversalStats;
use crate::triangle::RayShear;

use super::KdTree;
use super::frustum::{FrustumLeaf, Leaf};
use super::mono::{Next, SPLIT_SLACK};
use super::packet::{Front, PacketLeaf, PacketStack};

impl KdTree {
    /// Traces an edge-width shadow ray (from the shaded point toward the light) and returns its occlusion in
    /// `[0, 1]`; `state` holds the radius, the leak-fix switch and reusable buffers.
    pub fn edge_width(&self, ray: &Ray, state: &mut EdgeWidth, stats: &mut TraversalStats) -> f32 {
        state.begin();
        let shear = RayShear::new(ray);
        let tris = self.triangles();
        let mut tests = 0u64;
        self.traverse(ray, stats, |ids, _, t_far| {
            for &id in &self.tri_ids()[ids] {
                if state.seen(id) {
                    continue;
                }
                tests += 1;
                let corners = tris.get(id);
                if let Some(h) = shear.intersect(corners, ray.tmin, ray.tmax) {
                    let n = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
                    state.add(Crossing { t: h.t, tri: id, front: n.dot(ray.dir) < 0.0 });
                }
            }
            if state.commit(t_far * (1.0 + SPLIT_SLACK), tris) { Next::Stop } else { Next::Continue(ray.tmax) }
        });
        stats.isect_tests += tests;
        state.commit(f32::INFINITY, tris);
        state.occlusion()
    }

    /// The edge-width occlusions of `rays`, written to `out`, traced in packets of `V::LANES` rays whose
    /// directions share signs; `states` (at least `V::LANES`, all with the same radius and leak-fix switch)
    /// are the lanes' reusable states, `stack` the walk's. Equal, ray by ray, to [`KdTree::edge_width`].
    #[inline(always)]
    pub fn edge_widths<V: Vf32>(
        &self,
        rays: &[Ray],
        states: &mut [EdgeWidth],
        out: &mut [f32],
        stack: &mut PacketStack<V>,
        stats: &mut TraversalStats,
    ) {
        assert!(rays.len() == out.len() && states.len() >= V::LANES);
        // Rays grouped by direction signs (bit k: component k negative, -0 included, as its inverse is
        // -infinity), keeping their order (neighbours are coherent) within a group.
        let mut order: Vec<(usize, u32)> = rays.iter().map(|r| r.dir.is_negative_bitmask()).enumerate().collect();
        order.sort_by_key(|&(_, s)| s);
        let mut start = 0;
        while start < order.len() {
            let sign = order[start].1;
            let mut end = start + 1;
            while end < order.len() && end - start < V::LANES && order[end].1 == sign {
                end += 1;
            }
            let group = &order[start..end];
            let p = RayPacket::<V>::gather(|lane| group.get(lane).map(|&(i, _)| rays[i]));
            let states = &mut states[..group.len()];
            for s in states.iter_mut() {
                s.begin();
            }
            stats.rays += group.len() as u64;
            stats.packets += 1;
            let mut walk = EdgeWalks { tree: self, p: &p, states: &mut *states, pending: 0, tests: 0 };
            self.traverse_packet(&p, Front::Signs(sign as usize), stack, stats, &mut walk);
            stats.isect_tests += walk.tests;
            for (s, &(i, _)) in states.iter_mut().zip(group) {
                s.commit(f32::INFINITY, self.triangles());
                out[i] = s.occlusion();
            }
            start = end;
        }
    }

    /// The edge-width occlusions of the rays of `tile`, segments that end at the origin of bundle `f` (a
    /// frustum or cone from the light they end at, which bounds them), walked together inside it. The state
    /// and the result of the ray at tile pixel `k` are `states[k]` and `out[k]`; the states share one
    /// radius and leak-fix switch. With `cull`, each leaf tests only the packets that may reach its box
    /// (batched, then per ray). Equal, ray by ray, to [`KdTree::edge_width`].
    #[inline(always)]
    pub fn edge_widths_bundle<B: Bundle, V: Vf32>(
        &self,
        f: &B,
        tile: &PacketTile<V>,
        cull: bool,
        states: &mut [EdgeWidth],
        out: &mut [f32],
        stats: &mut TraversalStats,
    ) {
        // The culling batch sees each segment from the bundle's origin: origin to start point, `s` in [0, 1].
        let light = f.origin();
        let o = [V::splat(light.x), V::splat(light.y), V::splat(light.z)];
        let mut seen_from_light = Vec::with_capacity(tile.packets.len());
        let chunked = tile.packets.len().div_ceil(V::LANES) * V::LANES;
        let mut reach = Vec::with_capacity(chunked);
        for (j, p) in tile.packets.iter().enumerate() {
            tile.for_each_lane(j, |k, _| states[k].begin());
            let rays = p.valid.bits().count_ones() as u64;
            stats.rays += rays;
            stats.packets += (rays > 0) as u64;
            let t0 = p.tmin.max(V::splat(0.0));
            let dir = map3([0, 1, 2], |k| p.org[k] + p.dir[k] * t0 - o[k]);
            seen_from_light.push(RayPacket::from_lanes(o, dir, V::splat(0.0), V::splat(1.0), p.valid.bits()));
            reach.push(if rays > 0 { 1.0 } else { f32::NEG_INFINITY });
        }
        reach.resize(chunked, f32::NEG_INFINITY);
        let batch = BatchCull::new(light, &seen_from_light);
        let mut walk =
            BundleEdges { tree: self, tile, cull, batch: &batch, reach: &reach, pad: f.origin_slack(), states };
        self.traverse_frustum(f, stats, &mut walk);
        let states = walk.states;
        for j in 0..tile.packets.len() {
            tile.for_each_lane(j, |k, _| {
                states[k].commit(f32::INFINITY, self.triangles());
                out[k] = states[k].occlusion();
            });
        }
    }
}

/// The edge-width walks of a packet's lanes, one state per lane.
struct EdgeWalks<'a, V: Vf32> {
    tree: &'a KdTree,
    p: &'a RayPacket<V>,
    states: &'a mut [EdgeWidth],
    /// The lanes whose states hold crossings not yet committed: only they can change, or finish, at the end
    /// of a leaf, and most leaves end with none.
    pending: u32,
    tests: u64,
}

impl<V: Vf32> PacketLeaf<V> for EdgeWalks<'_, V> {
    #[inline(always)]
    fn visit(&mut self, ids: Range<usize>, active: V::Mask, t_far: V) -> (V, V::Mask) {
        let tris = self.tree.triangles();
        let ids = &self.tree.tri_ids()[ids];
        self.tests += ids.len() as u64;
        self.pending |= leaf_crossings(self.tree, self.p, ids, active, self.states, |i| i);
        let mut finished = 0u32;
        let mut bits = active.bits() & self.pending;
        if bits != 0 {
            let mut far = V::array_from_fn(|_| 0.0);
            t_far.write_to(far.as_mut());
            let far = far.as_ref();
            while bits != 0 {
                let i = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                let state = &mut self.states[i];
                if state.commit(far[i] * (1.0 + SPLIT_SLACK), tris) {
                    finished |= 1 << i;
                }
                if !state.has_pending() {
                    self.pending &= !(1 << i);
                }
            }
        }
        (self.p.tmax, V::Mask::from_bits(finished))
    }
}

/// The edge-width crossings of a bundle walk's packets, gathered per lane (tile pixel) and paired after the
/// walk.
struct BundleEdges<'a, V: Vf32> {
    tree: &'a KdTree,
    tile: &'a PacketTile<V>,
    cull: bool,
    /// The packets' segments seen from the light, for batched culling.
    batch: &'a BatchCull,
    /// The batch's end parameter per packet (1, or -inf for an empty packet), padded to whole chunks.
    reach: &'a [f32],
    /// How far the segments' ends may miss the light: leaf boxes grow by it for the batched test.
    pad: f32,
    states: &'a mut [EdgeWidth],
}

impl<V: Vf32> FrustumLeaf for BundleEdges<'_, V> {
    #[inline(always)]
    fn visit(&mut self, leaf: &Leaf, stats: &mut TraversalStats) -> (f32, bool) {
        let ids = &self.tree.tri_ids()[leaf.node.leaf_range()];
        if ids.is_empty() {
            return (f32::INFINITY, false);
        }
        let bounds = self.tree.leaf_bounds(leaf.node);
        let grown = Aabb::new(bounds.min - Vec3::splat(self.pad), bounds.max + Vec3::splat(self.pad));
        let (pw, width) = (PacketTile::<V>::PACKET_W, self.tile.width);
        for chunk in 0..self.tile.packets.len().div_ceil(V::LANES) {
            let mut maybe =
                if self.cull { self.batch.maybe_inside::<V>(chunk, &grown, self.reach, SPLIT_SLACK) } else { u32::MAX };
            let first = chunk * V::LANES;
            let count = (self.tile.packets.len() - first).min(V::LANES);
            stats.packets_culled += (count as u32 - (maybe & lane_bits(count)).count_ones()) as u64;
            maybe &= lane_bits(count);
            while maybe != 0 {
                let j = first + maybe.trailing_zeros() as usize;
                maybe &= maybe - 1;
                let p = &self.tile.packets[j];
                let active = if self.cull { overlaps_box(p, &bounds, p.tmax, SPLIT_SLACK) } else { p.valid };
                if active.none() {
                    stats.packets_culled += 1;
                    continue;
                }
                stats.packets_tested += 1;
                stats.isect_tests += ids.len() as u64;
                let (x0, y0) = self.tile.origin_pixel[j];
                leaf_crossings(self.tree, p, ids, active, self.states, |i| (y0 + i / pw) * width + x0 + i % pw);
            }
        }
        (f32::INFINITY, false)
    }
}

/// The low `count` bits set.
#[inline(always)]
fn lane_bits(count: usize) -> u32 {
    if count >= 32 { u32::MAX } else { (1u32 << count) - 1 }
}

/// Tests the `active` lanes of `p` against triangles `ids` and adds each crossing to its lane's state,
/// `states[slot(lane)]`, once per ray (a triangle referenced by several leaves is met in each). Returns the
/// lanes that got a new crossing.
#[inline(always)]
fn leaf_crossings<V: Vf32>(
    tree: &KdTree,
    p: &RayPacket<V>,
    ids: &[u32],
    active: V::Mask,
    states: &mut [EdgeWidth],
    slot: impl Fn(usize) -> usize,
) -> u32 {
    let tris = tree.triangles();
    let mut t = V::array_from_fn(|_| 0.0);
    let mut added = 0;
    let tester = PacketTester::new(p);
    for &id in ids {
        let corners = tris.get(id);
        let (hit, t_hit) = tester.crossing(corners, active);
        if hit.none() {
            continue;
        }
        t_hit.write_to(t.as_mut());
        let n = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
        let mut bits = hit.bits();
        while bits != 0 {
            let i = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            let state = &mut states[slot(i)];
            if !state.seen(id) {
                let dir = Vec3::new(p.dir[0].lane(i), p.dir[1].lane(i), p.dir[2].lane(i));
                state.add(Crossing { t: t.as_ref()[i], tri: id, front: n.dot(dir) < 0.0 });
                added |= 1 << i;
            }
        }
    }
    added
}
