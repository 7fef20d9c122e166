//! Building the 4-wide MBVH: a binary BVH by binned SAH over triangle centroids (16 bins on each of the three
//! centroid axes, the halves built in parallel with rayon), then collapsed top-down into 4-wide nodes by
//! repeatedly opening the child with the largest surface area (Wald et al. 2008, as the MBVH RS paper builds).

use glam::{UVec3, Vec3, Vec3A};

use super::node::{EMPTY, MbvhNode};
use crate::aabb::Aabb;
use crate::tri4;

/// Triangles per leaf above which a node is always split.
pub const MAX_LEAF: usize = 8;
/// SAH bins per node.
const BINS: usize = 16;
/// Cost of a box test relative to a triangle test in the SAH.
const C_TRAV: f32 = 1.0;
/// Binary depth from which lists are halved instead of split by SAH, so that the tree (and the traversal
/// stack) stays shallow whatever the input: at most 48 SAH levels, then log2 of the rest.
const MAX_SAH_DEPTH: u32 = 48;
/// Nodes with at least this many triangles build their halves in parallel.
const PARALLEL_MIN: usize = 4096;

/// A binary build node.
enum Bin {
    Leaf { bounds: Aabb, first: u32, count: u32 },
    Inner { bounds: Aabb, children: Box<[Bin; 2]> },
}

impl Bin {
    fn bounds(&self) -> Aabb {
        match self {
            Bin::Leaf { bounds, .. } | Bin::Inner { bounds, .. } => *bounds,
        }
    }
}

/// The finished arrays: 4-wide nodes (the root first) and the triangle ids the leaves index.
pub struct Built {
    pub nodes: Vec<MbvhNode>,
    /// Each leaf's ids start at a multiple of four; the slots after a leaf up to the next multiple hold
    /// [`tri4::PAD`], so a leaf is a whole number of four-triangle blocks.
    pub tri_ids: Vec<u32>,
    /// Nodes of the binary BVH before collapsing (for statistics).
    pub binary_nodes: usize,
}

/// Builds over triangles given by their bounds and centroids.
pub fn build(boxes: &[Aabb], centroids: &[Vec3]) -> Built {
    let mut ids: Vec<u32> = (0..boxes.len() as u32).collect();
    let mut count = 0usize;
    let root = if ids.is_empty() {
        Bin::Leaf { bounds: Aabb::EMPTY, first: 0, count: 0 }
    } else {
        let extent = Extent::of(boxes, centroids, &ids);
        split(boxes, centroids, &mut ids, extent, 0, 0, &mut count)
    };
    let mut nodes = vec![MbvhNode::empty()];
    match &root {
        Bin::Leaf { bounds, first, count } => {
            if *count > 0 {
                put(&mut nodes[0], 0, bounds, *first, *count);
            }
        }
        Bin::Inner { .. } => collapse(&root, 0, &mut nodes),
    }
    let tri_ids = align_leaves(&mut nodes, &ids);
    Built { nodes, tri_ids, binary_nodes: count }
}

/// Aligns every leaf's ids on a four-triangle block ([`tri4::align_leaves`]).
fn align_leaves(nodes: &mut [MbvhNode], ids: &[u32]) -> Vec<u32> {
    let mut leaves: Vec<(&mut u32, u32)> =
        nodes.iter_mut().flat_map(|n| n.child.iter_mut().zip(n.count)).filter(|(_, count)| *count > 0).collect();
    tri4::align_leaves(ids, &mut leaves)
}

/// Relative padding of stored boxes: the slab test's rounding (a few ulps of the coordinates, amplified for
/// rays leaving a surface, whose hits lie at tiny distances) must never cull a box the ray touches.
const BOX_PAD: f32 = 16.0 * f32::EPSILON;

/// Writes box `b`, padded, into lane `k` of `node`.
pub(super) fn put_box(node: &mut MbvhNode, k: usize, b: &Aabb) {
    for a in 0..3 {
        let pad = BOX_PAD * b.min[a].abs().max(b.max[a].abs()) + f32::MIN_POSITIVE;
        node.min[a][k] = b.min[a] - pad;
        node.max[a][k] = b.max[a] + pad;
    }
}

/// Writes a child's padded box and reference into lane `k` of `node`.
fn put(node: &mut MbvhNode, k: usize, b: &Aabb, first: u32, count: u32) {
    put_box(node, k, b);
    node.child[k] = first;
    node.count[k] = count;
}

/// Fills node `at` from binary inner node `n`: up to four grandchildren, opening the largest inner child
/// first; inner lanes recurse into new nodes.
fn collapse(n: &Bin, at: usize, nodes: &mut Vec<MbvhNode>) {
    let Bin::Inner { children, .. } = n else { return };
    let mut lanes: Vec<&Bin> = vec![&children[0], &children[1]];
    while lanes.len() < 4 {
        let widest = lanes
            .iter()
            .enumerate()
            .filter(|(_, b)| matches!(b, Bin::Inner { .. }))
            .max_by(|a, b| a.1.bounds().surface_area().total_cmp(&b.1.bounds().surface_area()))
            .map(|(i, _)| i);
        let Some(i) = widest else { break };
        let Bin::Inner { children, .. } = lanes.swap_remove(i) else { unreachable!() };
        lanes.push(&children[0]);
        lanes.push(&children[1]);
    }
    for (k, lane) in lanes.into_iter().enumerate() {
        match lane {
            Bin::Leaf { bounds, first, count } => put(&mut nodes[at], k, bounds, *first, *count),
            Bin::Inner { bounds, .. } => {
                let index = nodes.len();
                nodes.push(MbvhNode::empty());
                put(&mut nodes[at], k, bounds, index as u32, 0);
                collapse(lane, index, nodes);
            }
        }
    }
    debug_assert!(nodes[at].child.iter().any(|&c| c != EMPTY));
}

/// The box of some triangles and the box of their centroids.
#[derive(Clone, Copy)]
struct Extent {
    bounds: Aabb,
    centroids: Aabb,
}

impl Extent {
    /// The extent of triangles `ids`, by a pass over them.
    fn of(boxes: &[Aabb], centroids: &[Vec3], ids: &[u32]) -> Self {
        ids.iter().fold(Extent { bounds: Aabb::EMPTY, centroids: Aabb::EMPTY }, |e, &i| Extent {
            bounds: e.bounds.union(boxes[i as usize]),
            centroids: e.centroids.grow(centroids[i as usize]),
        })
    }
}

/// Builds the binary subtree over `ids` (which start at `offset` in the final id array and span `extent`),
/// partitioning `ids` in place. A binned split hands each child its extent: the triangle boxes from the
/// bins, the centroid boxes from the partition pass, so no level makes a pass of its own to find them.
fn split(
    boxes: &[Aabb],
    centroids: &[Vec3],
    ids: &mut [u32],
    extent: Extent,
    offset: u32,
    depth: u32,
    nodes: &mut usize,
) -> Bin {
    *nodes += 1;
    let bounds = extent.bounds;
    let n = ids.len();
    let leaf = Bin::Leaf { bounds, first: offset, count: n as u32 };
    if n <= 2 {
        return leaf;
    }
    // Deep in the tree (lopsided SAH splits on pathological input), the list is halved to bound the depth.
    let binned = if depth >= MAX_SAH_DEPTH {
        None
    } else {
        // Split when it beats a leaf, and always when the leaf would be too big.
        best_split(boxes, centroids, ids, &extent.centroids, bounds).filter(|s| s.cost < n as f32 || n > MAX_LEAF)
    };
    let parts = match binned {
        Some(s) => {
            let (axis, lo) = (s.axis, extent.centroids.min[s.axis]);
            let (mut left_c, mut right_c) = (Aabb::EMPTY, Aabb::EMPTY);
            let mut mid = 0;
            for j in 0..n {
                let c = centroids[ids[j] as usize];
                if bin_of(c[axis], lo, s.scale) <= s.bin {
                    left_c = left_c.grow(c);
                    ids.swap(mid, j);
                    mid += 1;
                } else {
                    right_c = right_c.grow(c);
                }
            }
            (mid > 0 && mid < n).then_some((
                mid,
                Extent { bounds: s.left, centroids: left_c },
                Extent { bounds: s.right, centroids: right_c },
            ))
        }
        None if n <= MAX_LEAF => return leaf,
        None => None,
    };
    let (mid, left_extent, right_extent) = match parts {
        Some(p) => p,
        // All centroids in one bin (or the depth cap): split the list in half.
        None if n > MAX_LEAF => {
            let mid = n / 2;
            (mid, Extent::of(boxes, centroids, &ids[..mid]), Extent::of(boxes, centroids, &ids[mid..]))
        }
        None => return leaf,
    };
    let (left, right) = ids.split_at_mut(mid);
    let (mut nl, mut nr) = (0, 0);
    let right_offset = offset + mid as u32;
    let (l, r) = if n >= PARALLEL_MIN {
        rayon::join(
            || split(boxes, centroids, left, left_extent, offset, depth + 1, &mut nl),
            || split(boxes, centroids, right, right_extent, right_offset, depth + 1, &mut nr),
        )
    } else {
        (
            split(boxes, centroids, left, left_extent, offset, depth + 1, &mut nl),
            split(boxes, centroids, right, right_extent, right_offset, depth + 1, &mut nr),
        )
    };
    *nodes += nl + nr;
    Bin::Inner { bounds, children: Box::new([l, r]) }
}

/// [`Aabb::surface_area`] of the box `[lo, hi]`, on 16-byte vectors (the same operations in the same order).
#[inline]
fn surface_area(lo: Vec3A, hi: Vec3A) -> f32 {
    let e = (hi - lo).max(Vec3A::ZERO);
    2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
}

#[inline]
fn bin_of(c: f32, lo: f32, scale: f32) -> usize {
    (((c - lo) * scale) as usize).min(BINS - 1)
}

/// A binned split: left = bins `0..=bin` on `axis`, whose bins are `1 / scale` wide.
struct Split {
    axis: usize,
    bin: usize,
    scale: f32,
    /// SAH cost in units of triangle tests.
    cost: f32,
    /// The boxes of the triangles on each side.
    left: Aabb,
    right: Aabb,
}

/// The cheapest binned split over all three centroid axes (axes where the centroids do not spread are
/// skipped), or `None` when no axis separates them.
fn best_split(boxes: &[Aabb], centroids: &[Vec3], ids: &[u32], cb: &Aabb, bounds: Aabb) -> Option<Split> {
    let extent = cb.extent();
    let scale: [f32; 3] = std::array::from_fn(|a| {
        let s = BINS as f32 / extent[a];
        if extent[a] > 0.0 && s.is_finite() { s } else { 0.0 }
    });
    if scale == [0.0; 3] {
        return None;
    }
    // Bin boxes as 16-byte vectors, so that growing one by a triangle's box is two SIMD min/max operations.
    let mut bin_lo = [[Vec3A::INFINITY; BINS]; 3];
    let mut bin_hi = [[Vec3A::NEG_INFINITY; BINS]; 3];
    let mut bin_n = [[0u32; BINS]; 3];
    // The three axes' bins at once, with `bin_of`'s arithmetic in each lane (so `partition` agrees).
    let (origin, scale3, last) = (Vec3A::from(cb.min), Vec3A::from_array(scale), UVec3::splat(BINS as u32 - 1));
    for &i in ids {
        let (c, b) = (Vec3A::from(centroids[i as usize]), &boxes[i as usize]);
        let (lo, hi) = (Vec3A::from(b.min), Vec3A::from(b.max));
        let bins = ((c - origin) * scale3).as_uvec3().min(last).to_array();
        for (a, &k) in bins.iter().enumerate() {
            let k = k as usize;
            bin_lo[a][k] = bin_lo[a][k].min(lo);
            bin_hi[a][k] = bin_hi[a][k].max(hi);
            bin_n[a][k] += 1;
        }
    }
    let area = bounds.surface_area().max(f32::MIN_POSITIVE);
    let mut best: Option<Split> = None;
    for a in (0..3).filter(|&a| scale[a] > 0.0) {
        // Sweep from the right to get the right-side boxes, then from the left.
        let mut right = [(Vec3A::INFINITY, Vec3A::NEG_INFINITY); BINS];
        let mut right_n = [0u32; BINS];
        let (mut lo, mut hi, mut cnt) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY, 0);
        for b in (1..BINS).rev() {
            (lo, hi) = (lo.min(bin_lo[a][b]), hi.max(bin_hi[a][b]));
            cnt += bin_n[a][b];
            right[b] = (lo, hi);
            right_n[b] = cnt;
        }
        let (mut lo, mut hi, mut cnt) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY, 0);
        for b in 0..BINS - 1 {
            (lo, hi) = (lo.min(bin_lo[a][b]), hi.max(bin_hi[a][b]));
            cnt += bin_n[a][b];
            if cnt == 0 || right_n[b + 1] == 0 {
                continue;
            }
            let (r_lo, r_hi) = right[b + 1];
            let cost =
                C_TRAV + (surface_area(lo, hi) * cnt as f32 + surface_area(r_lo, r_hi) * right_n[b + 1] as f32) / area;
            if best.as_ref().is_none_or(|s| cost < s.cost) {
                let (left, right) = (Aabb::new(lo.into(), hi.into()), Aabb::new(r_lo.into(), r_hi.into()));
                best = Some(Split { axis: a, bin: b, scale: scale[a], cost, left, right });
            }
        }
    }
    best
}
