//! SAH kd-tree construction with perfect splits in O(N log N) (Tsakok 2008, sections 2.2.1 and 3.2.1;
//! Wald and Havran 2006, "On building fast kd-Trees for Ray Tracing, and on doing that in O(N log N)").
//!
//! Every triangle contributes, per axis, a start and an end event at the bounds of its part inside the node
//! (a single "planar" event when that part is flat along the axis). The three event lists are sorted once at
//! the root. A node sweeps each list to evaluate the SAH at every candidate plane, then classifies its
//! triangles as left, right or both. Left-only and right-only events keep their order when copied to the
//! children; only the straddling triangles are clipped to the child boxes ("perfect splits"), and their few
//! new events are sorted and merged in. No list is ever sorted again, hence O(N log N).
//!
//! The build is iterative with an explicit stack; nodes with many triangles hand their two children to
//! rayon tasks, whose subtrees are then spliced into one array with children kept adjacent.

use glam::Vec3;

use super::clip::split_clipped_bounds;
use super::params::{KdParams, SplitStrategy};
use crate::aabb::{Aabb, coord, coord_mut};

/// A node of the builder's tree. Children of an inner node are adjacent: `left` and `left + 1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum BuildNode {
    Inner { axis: u8, split: f32, left: u32 },
    Leaf { first: u32, count: u32 },
}

/// The builder's result: nodes (root first) and the leaves' triangle ids.
#[derive(Debug, Default)]
pub(super) struct BuildOutput {
    pub nodes: Vec<BuildNode>,
    pub tri_ids: Vec<u32>,
}

const END: u32 = 0;
const PLANAR: u32 = 1;
const START: u32 = 2;
const LEFT: u8 = 0;
const RIGHT: u8 = 1;
const BOTH: u8 = 2;

/// A split-candidate event: a plane position on one axis, its kind and the triangle it belongs to, packed
/// into one integer that is also its sort key: `position << 32 | kind << 30 | triangle`, the position as
/// [`ordered_bits`]. Events sort by position, then end < planar < start as the sweep expects (then by
/// triangle, which only makes the order total), with plain integer compares.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
struct Event(u64);

/// The bits of a finite `f32` as an integer that orders like the float (-0.0 and +0.0 coincide).
fn ordered_bits(x: f32) -> u32 {
    // `+ 0.0` turns -0.0 into +0.0 so that equal positions sort together.
    let b = (x + 0.0).to_bits();
    if b >> 31 == 1 { !b } else { b | 0x8000_0000 }
}

impl Event {
    /// A placeholder for slots about to be overwritten.
    const BLANK: Self = Self(0);

    fn new(pos: f32, tri: u32, kind: u32) -> Self {
        debug_assert!(tri < 1 << 30 && kind < 3);
        Self((ordered_bits(pos) as u64) << 32 | (kind as u64) << 30 | tri as u64)
    }
    /// The position as [`ordered_bits`]: compares as the position does.
    fn pos_key(self) -> u32 {
        (self.0 >> 32) as u32
    }
    fn pos(self) -> f32 {
        let o = self.pos_key();
        f32::from_bits(if o >> 31 == 1 { o & 0x7fff_ffff } else { !o })
    }
    fn tri(self) -> usize {
        (self.0 & ((1 << 30) - 1)) as usize
    }
    fn kind(self) -> u32 {
        (self.0 >> 30) as u32 & 3
    }
}

type Events = [Vec<Event>; 3];

/// Buffers reused from node to node, so a build allocates a few times per thread instead of about fifteen
/// times per node: the side of each triangle, the straddling triangles, their new events, and a free list of
/// event vectors that children take and consumed parents give back.
struct Scratch {
    side: Vec<u8>,
    straddlers: Vec<u32>,
    new_l: Events,
    new_r: Events,
    free: Vec<Vec<Event>>,
}

impl Scratch {
    /// Most vectors kept on the free list.
    const MAX_FREE: usize = 64;

    fn new(n_tris: usize) -> Self {
        Self {
            side: vec![0; n_tris],
            straddlers: Vec::new(),
            new_l: Default::default(),
            new_r: Default::default(),
            free: Vec::new(),
        }
    }

    /// A vector of `len` events whose values are left over from earlier use (the caller overwrites them):
    /// only the part beyond what the reused vector held is initialised. (The most recently freed vector is
    /// taken even when an older one is long enough: it is still in the cache, which matters more.)
    fn take(&mut self, len: usize) -> Vec<Event> {
        let mut v = self.free.pop().unwrap_or_default();
        v.resize(len, Event::BLANK);
        v
    }

    fn give(&mut self, events: Events) {
        for v in events {
            if v.capacity() > 0 && self.free.len() < Self::MAX_FREE {
                self.free.push(v);
            }
        }
    }
}

struct Task {
    bounds: Aabb,
    events: Events,
    n: usize,
    depth: u32,
}

struct Split {
    axis: usize,
    pos: f32,
    planar_left: bool,
}

struct Ctx<'a> {
    tris: &'a [[Vec3; 3]],
    params: &'a KdParams,
    max_depth: u32,
}

/// Builds the tree over `tris` inside `bounds` (which must hold every triangle).
pub(super) fn build(tris: &[[Vec3; 3]], bounds: Aabb, params: &KdParams) -> BuildOutput {
    let ctx = Ctx { tris, params, max_depth: params.depth_for(tris.len()) };
    let mut events: Events = Default::default();
    for (a, list) in events.iter_mut().enumerate() {
        list.reserve(2 * tris.len());
        for (i, t) in tris.iter().enumerate() {
            let b = Aabb::from_points(t.iter().copied());
            push_events(list, a, i as u32, &b);
        }
    }
    events.iter_mut().for_each(sort_root_events);
    build_parallel(&ctx, Task { bounds, events, n: tris.len(), depth: 0 })
}

/// Sorts an event list built in triangle order, in three passes of a least-significant-digit radix sort
/// over the position and kind bits (12-bit digits, the top two overlapping the ones below, which still
/// orders by all 34 bits). The sort is stable, so events with equal position and kind stay in triangle
/// order: the same order as sorting the whole integers.
fn sort_root_events(v: &mut Vec<Event>) {
    const DIGIT: u32 = 12;
    let mut out = vec![Event::BLANK; v.len()];
    let mut count = vec![0usize; 1 << DIGIT];
    for shift in [30, 41, 52] {
        let digit = |e: &Event| (e.0 >> shift) as usize & ((1 << DIGIT) - 1);
        count.fill(0);
        for e in v.iter() {
            count[digit(e)] += 1;
        }
        let mut sum = 0;
        for c in count.iter_mut() {
            (*c, sum) = (sum, sum + *c);
        }
        for e in v.iter() {
            let d = digit(e);
            out[count[d]] = *e;
            count[d] += 1;
        }
        std::mem::swap(v, &mut out);
    }
    debug_assert!(v.is_sorted());
}

fn push_events(list: &mut Vec<Event>, axis: usize, tri: u32, b: &Aabb) {
    if coord(&b.min, axis) == coord(&b.max, axis) {
        list.push(Event::new(coord(&b.min, axis), tri, PLANAR));
    } else {
        list.push(Event::new(coord(&b.min, axis), tri, START));
        list.push(Event::new(coord(&b.max, axis), tri, END));
    }
}

/// Splits large nodes here and builds their children in parallel; small ones go to [`build_sequential`].
fn build_parallel(ctx: &Ctx, task: Task) -> BuildOutput {
    if task.n < ctx.params.parallel_min_tris {
        return build_sequential(ctx, task);
    }
    let Some(split) = find_split(ctx, &task) else {
        return build_sequential(ctx, task);
    };
    let mut scratch = Scratch::new(ctx.tris.len());
    let axis = split.axis as u8;
    let pos = split.pos;
    let (l, r) = partition(ctx, task, &split, &mut scratch);
    drop(scratch);
    let (lo, ro) = rayon::join(|| build_parallel(ctx, l), || build_parallel(ctx, r));
    splice(axis, pos, lo, ro)
}

/// Joins two subtrees under a new root: `[root, left root, right root, left rest.., right rest..]`.
fn splice(axis: u8, split: f32, lo: BuildOutput, ro: BuildOutput) -> BuildOutput {
    let mut nodes = Vec::with_capacity(1 + lo.nodes.len() + ro.nodes.len());
    nodes.push(BuildNode::Inner { axis, split, left: 1 });
    let lo_rest = 3;
    let ro_rest = lo_rest + lo.nodes.len() as u32 - 1;
    let map = |i: u32, root: u32, rest: u32| if i == 0 { root } else { rest + i - 1 };
    let relocate = |n: BuildNode, root: u32, rest: u32, tri_base: u32| match n {
        BuildNode::Inner { axis, split, left } => BuildNode::Inner { axis, split, left: map(left, root, rest) },
        BuildNode::Leaf { first, count } => BuildNode::Leaf { first: first + tri_base, count },
    };
    let tri_base = lo.tri_ids.len() as u32;
    nodes.push(relocate(lo.nodes[0], 1, lo_rest, 0));
    nodes.push(relocate(ro.nodes[0], 2, ro_rest, tri_base));
    nodes.extend(lo.nodes[1..].iter().map(|&n| relocate(n, 1, lo_rest, 0)));
    nodes.extend(ro.nodes[1..].iter().map(|&n| relocate(n, 2, ro_rest, tri_base)));
    let mut tri_ids = lo.tri_ids;
    tri_ids.extend_from_slice(&ro.tri_ids);
    BuildOutput { nodes, tri_ids }
}

/// Builds a subtree depth-first with an explicit stack.
fn build_sequential(ctx: &Ctx, root: Task) -> BuildOutput {
    let mut out = BuildOutput { nodes: vec![BuildNode::Leaf { first: 0, count: 0 }], tri_ids: Vec::new() };
    let mut scratch = Scratch::new(ctx.tris.len());
    let mut stack = vec![(0usize, root)];
    while let Some((idx, task)) = stack.pop() {
        match find_split(ctx, &task) {
            None => {
                let first = out.tri_ids.len() as u32;
                out.tri_ids.extend(task.events[0].iter().filter(|e| e.kind() != END).map(|e| e.tri() as u32));
                out.nodes[idx] = BuildNode::Leaf { first, count: task.n as u32 };
                scratch.give(task.events);
            }
            Some(split) => {
                let left = out.nodes.len();
                out.nodes.push(BuildNode::Leaf { first: 0, count: 0 });
                out.nodes.push(BuildNode::Leaf { first: 0, count: 0 });
                out.nodes[idx] = BuildNode::Inner { axis: split.axis as u8, split: split.pos, left: left as u32 };
                let (l, r) = partition(ctx, task, &split, &mut scratch);
                stack.push((left + 1, r));
                stack.push((left, l));
            }
        }
    }
    out
}

/// The node-constant parts of the SAH cost (thesis Eq. 2.1) for planes on one axis.
struct AxisCost {
    min: f32,
    max: f32,
    /// Area of the two faces parallel to the plane.
    cap: f32,
    /// Perimeter of those faces: a side's area grows by `ring` per unit of width.
    ring: f32,
    c_trav: f32,
    /// `c_isect` divided by the node's area.
    c_isect_per_sa: f32,
    empty_factor: f32,
}

impl AxisCost {
    fn new(p: &KdParams, b: &Aabb, axis: usize) -> Self {
        let e = b.extent();
        let (e1, e2) = (e[(axis + 1) % 3], e[(axis + 2) % 3]);
        Self {
            min: coord(&b.min, axis),
            max: coord(&b.max, axis),
            cap: 2.0 * e1 * e2,
            ring: 2.0 * (e1 + e2),
            c_trav: p.c_trav,
            c_isect_per_sa: p.c_isect / b.surface_area(),
            empty_factor: 1.0 - p.empty_bonus,
        }
    }

    /// Cost of the plane at `pos` with `nl` and `nr` triangles on the two sides.
    #[inline]
    fn cost(&self, pos: f32, nl: u32, nr: u32) -> f32 {
        let sa_l = self.cap + (pos - self.min) * self.ring;
        let sa_r = self.cap + (self.max - pos) * self.ring;
        let cost = self.c_trav + self.c_isect_per_sa * (sa_l * nl as f32 + sa_r * nr as f32);
        let factor = if nl == 0 || nr == 0 { self.empty_factor } else { 1.0 };
        cost * factor
    }
}

/// The best split of the node, or `None` when it should be a leaf.
fn find_split(ctx: &Ctx, task: &Task) -> Option<Split> {
    let p = ctx.params;
    if task.n == 0 || task.depth >= ctx.max_depth {
        return None;
    }
    let b = &task.bounds;
    let sa = b.surface_area();
    if sa <= 0.0 || sa.is_nan() {
        return None;
    }
    let mut best_cost = p.c_isect * task.n as f32;
    let mut best = None;
    let mut consider = |ac: &AxisCost, axis: usize, pos: f32, nl: u32, np: u32, nr: u32| {
        let c = ac.cost(pos, nl + np, nr);
        if c < best_cost {
            best_cost = c;
            best = Some(Split { axis, pos, planar_left: true });
        }
        if np > 0 {
            let c = ac.cost(pos, nl, nr + np);
            if c < best_cost {
                best_cost = c;
                best = Some(Split { axis, pos, planar_left: false });
            }
        }
    };
    match p.strategy {
        SplitStrategy::Sah => {
            for axis in 0..3 {
                let (lo, hi) = (coord(&b.min, axis), coord(&b.max, axis));
                if hi <= lo {
                    continue;
                }
                let ac = AxisCost::new(p, b, axis);
                let ev = &task.events[axis];
                // Counts fit `u32`: triangle ids do (see `KdNode`).
                let (mut nl, mut nr) = (0u32, task.n as u32);
                let mut i = 0;
                while i < ev.len() {
                    // Only the counts at a position matter, so its events are tallied by kind without a branch
                    // on the kind (ends and starts interleave at random).
                    let (pos, key) = (ev[i].pos(), ev[i].pos_key());
                    let (mut ne, mut np, mut ns) = (0u32, 0u32, 0u32);
                    while i < ev.len() && ev[i].pos_key() == key {
                        let kind = ev[i].kind();
                        ne += (kind == END) as u32;
                        np += (kind == PLANAR) as u32;
                        ns += (kind == START) as u32;
                        i += 1;
                    }
                    nr -= ne + np;
                    if pos > lo && pos < hi {
                        consider(&ac, axis, pos, nl, np, nr);
                    }
                    nl += ns + np;
                }
            }
        }
        SplitStrategy::Middle => {
            let axis = b.longest_axis();
            let pos = b.center()[axis];
            if pos > coord(&b.min, axis) && pos < coord(&b.max, axis) {
                let (mut nl, mut np, mut nr) = (0u32, 0u32, 0u32);
                for e in &task.events[axis] {
                    match e.kind() {
                        START if e.pos() < pos => nl += 1,
                        END if e.pos() > pos => nr += 1,
                        PLANAR if e.pos() < pos => nl += 1,
                        PLANAR if e.pos() > pos => nr += 1,
                        PLANAR => np += 1,
                        _ => {}
                    }
                }
                consider(&AxisCost::new(p, b, axis), axis, pos, nl, np, nr);
            }
        }
    }
    best
}

/// Distributes the node's events to its children (Wald and Havran 2006, section 4.3).
fn partition(ctx: &Ctx, task: Task, split: &Split, scratch: &mut Scratch) -> (Task, Task) {
    let (axis, pos) = (split.axis, split.pos);
    let pos_key = ordered_bits(pos);
    let side = &mut scratch.side;
    // One sweep classifies every triangle: a start event comes before its end event, so the start sets the
    // side to right-only or both, and the end turns "both" into left-only when it lies at or before `pos`.
    // Starts and ends interleave at random, so the kind picks among precomputed sides without a branch.
    // A triangle's side is final at its end or planar event, where it is counted.
    let straddlers = &mut scratch.straddlers;
    straddlers.clear();
    let (mut nl, mut nr) = (0, 0);
    for e in &task.events[axis] {
        let s = &mut side[e.tri()];
        let at = e.pos_key();
        let at_start = if at >= pos_key { RIGHT } else { BOTH };
        let at_end = if at <= pos_key { LEFT } else { *s };
        let planar = if at < pos_key || (at == pos_key && split.planar_left) { LEFT } else { RIGHT };
        let kind = e.kind();
        *s = if kind == START {
            at_start
        } else if kind == END {
            at_end
        } else {
            planar
        };
        let counted = kind != START;
        nl += (counted && *s == LEFT) as usize;
        nr += (counted && *s == RIGHT) as usize;
        if counted && *s == BOTH {
            straddlers.push(e.tri() as u32);
        }
    }
    let (mut lb, mut rb) = (task.bounds, task.bounds);
    *coord_mut(&mut lb.max, axis) = pos;
    *coord_mut(&mut rb.min, axis) = pos;

    // Triangles wholly on one side: each has at most two events per axis.
    let (only_l, only_r) = (nl, nr);
    let (mut new_l, mut new_r) = (std::mem::take(&mut scratch.new_l), std::mem::take(&mut scratch.new_r));
    new_l.iter_mut().chain(new_r.iter_mut()).for_each(Vec::clear);
    for &t in straddlers.iter() {
        let (l, r) = split_clipped_bounds(&ctx.tris[t as usize], &task.bounds, axis, pos);
        if let Some(b) = l {
            nl += 1;
            for (a, list) in new_l.iter_mut().enumerate() {
                push_events(list, a, t, &b);
            }
        }
        if let Some(b) = r {
            nr += 1;
            for (a, list) in new_r.iter_mut().enumerate() {
                push_events(list, a, t, &b);
            }
        }
    }
    let mut left: Events = Default::default();
    let mut right: Events = Default::default();
    for a in 0..3 {
        new_l[a].sort_unstable();
        new_r[a].sort_unstable();
        let old = task.events[a].len();
        left[a] = scratch.take(old.min(2 * only_l) + 1);
        right[a] = scratch.take(old.min(2 * only_r) + 1);
        split_events(&task.events[a], &scratch.side, &new_l[a], &new_r[a], &mut left[a], &mut right[a]);
    }
    (scratch.new_l, scratch.new_r) = (new_l, new_r);
    scratch.give(task.events);
    let depth = task.depth + 1;
    (Task { bounds: lb, events: left, n: nl, depth }, Task { bounds: rb, events: right, n: nr, depth })
}

/// Sends each event of `old` to the side of its triangle (dropping the straddlers' old events) and merges in
/// the straddlers' new, sorted events, keeping both outputs sorted. `left` and `right`
/// come with at least one slot more than the old events they keep and leave with their events.
///
/// The sides of the other axes' events are in no order a branch predictor could learn, so every event is
/// written to both outputs and only the counts advance by its side; the few new events are then merged in
/// from the back, which moves only the events that sort after the first of them.
fn split_events(
    old: &[Event],
    side: &[u8],
    new_l: &[Event],
    new_r: &[Event],
    left: &mut Vec<Event>,
    right: &mut Vec<Event>,
) {
    let (mut nl, mut nr) = (0, 0);
    for &e in old {
        let s = side[e.tri()];
        left[nl] = e;
        right[nr] = e;
        nl += (s == LEFT) as usize;
        nr += (s == RIGHT) as usize;
    }
    merge_from_back(left, nl, new_l);
    merge_from_back(right, nr, new_r);
}

/// Makes `v` the sorted merge of its first `n` events (sorted) and `new` (sorted).
fn merge_from_back(v: &mut Vec<Event>, n: usize, new: &[Event]) {
    v.resize(n + new.len(), Event::BLANK);
    let (mut i, mut j) = (n, new.len());
    while j > 0 {
        let k = i + j - 1;
        if i > 0 && v[i - 1] > new[j - 1] {
            v[k] = v[i - 1];
            i -= 1;
        } else {
            v[k] = new[j - 1];
            j -= 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small deterministic pseudo-random sequence (xorshift).
    fn numbers(seed: u32, n: usize) -> Vec<u32> {
        let mut x = seed.max(1);
        (0..n)
            .map(|_| {
                x ^= x << 13;
                x ^= x >> 17;
                x ^= x << 5;
                x
            })
            .collect()
    }

    #[test]
    fn events_order_by_position_then_kind_and_keep_their_fields() {
        let positions = [-3.5e30f32, -2.0, -1.0, -f32::MIN_POSITIVE, 0.0, f32::MIN_POSITIVE, 1.0, 7.25e29];
        let mut events = Vec::new();
        for (k, &p) in positions.iter().enumerate() {
            for kind in [START, END, PLANAR] {
                events.push(Event::new(p, (k as u32 * 7919) % (1 << 30), kind));
            }
        }
        for e in &events {
            let k = positions.iter().position(|&p| p == e.pos()).unwrap();
            assert_eq!(e.tri(), (k * 7919) % (1 << 30));
        }
        assert_eq!(Event::new(-0.0, 5, START), Event::new(0.0, 5, START), "-0 and +0 are one position");
        let mut sorted = events.clone();
        sorted.sort_unstable();
        for w in sorted.windows(2) {
            let (a, b) = (w[0], w[1]);
            assert!(a.pos() <= b.pos(), "{} then {}", a.pos(), b.pos());
            if a.pos() == b.pos() {
                assert!(a.kind() <= b.kind(), "end < planar < start at one position");
            }
        }
        assert_eq!(Event::new(1.0, (1 << 30) - 1, START).tri(), (1 << 30) - 1);
    }

    #[test]
    fn the_radix_sort_gives_the_comparison_sort_order() {
        let r = numbers(7, 30_000);
        // Few distinct positions, so that many events share position and kind and the stability shows.
        let mut v: Vec<Event> =
            (0..r.len()).map(|i| Event::new((r[i] % 97) as f32 * 0.37 - 18.0, i as u32, r[i] % 3)).collect();
        let mut expected = v.clone();
        expected.sort_unstable();
        sort_root_events(&mut v);
        assert_eq!(v, expected);
    }

    #[test]
    fn split_events_sends_each_side_its_events_and_merges_the_new_ones_in_order() {
        let r = numbers(11, 4000);
        let n_tris = 500;
        let mut old: Vec<Event> =
            (0..2000).map(|i| Event::new((r[i] % 300) as f32 - 150.0, r[i + 2000] % n_tris, r[i] % 3)).collect();
        old.sort_unstable();
        let side: Vec<u8> = (0..n_tris as usize).map(|t| (r[t] % 3) as u8).collect();
        let fresh = |seed: u32| {
            let mut v: Vec<Event> =
                numbers(seed, 60).iter().map(|&x| Event::new((x % 400) as f32 - 200.0, x % n_tris, x % 3)).collect();
            v.sort_unstable();
            v
        };
        let (new_l, new_r) = (fresh(3), fresh(5));
        let (mut left, mut right) = (vec![Event::BLANK; old.len() + 1], vec![Event::BLANK; old.len() + 1]);
        split_events(&old, &side, &new_l, &new_r, &mut left, &mut right);
        for (out, new, keep) in [(&left, &new_l, LEFT), (&right, &new_r, RIGHT)] {
            let mut expected: Vec<Event> = old.iter().copied().filter(|e| side[e.tri()] == keep).collect();
            expected.extend_from_slice(new);
            expected.sort_unstable();
            assert_eq!(*out, expected);
        }
    }
}
