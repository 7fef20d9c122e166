//! Spatial splits for the MBVH build (the SBVH of Stich, Friedrich and Dietrich 2009): a node's box cut into
//! [`BINS`] equal slabs per axis, each triangle reference chopped into every slab it crosses, and the plane
//! between two slabs priced by the SAH like an object split. The references such a plane cuts go to both
//! children, clipped exactly to each ([`split_clipped_bounds`], the kd-tree's perfect-split clipping).

use glam::Vec3;
use rayon::prelude::*;

use super::sah::{BINS, C_TRAV, Context, Extent, PARALLEL_MIN, Parts, Ref, leaf_cost};
use crate::aabb::{Aabb, coord, coord_mut};
use crate::kdtree::clip::split_clipped_bounds;

/// Splits `refs` by the plane of `s`: a reference on one side goes there, one the plane cuts goes to both,
/// clipped to each; `None` when one side would be empty.
pub(super) fn partition_space(ctx: &Context, refs: &[Ref], s: &SpatialSplit) -> Option<Parts> {
    let (mut left, mut right) = (Vec::with_capacity(s.left_n), Vec::with_capacity(s.right_n));
    for r in refs {
        if coord(&r.bounds.max, s.axis) <= s.pos {
            left.push(*r);
        } else if coord(&r.bounds.min, s.axis) >= s.pos {
            right.push(*r);
        } else {
            match split_clipped_bounds(&ctx.tris[r.id as usize], &r.bounds, s.axis, s.pos) {
                (None, None) => left.push(*r),
                (l, rr) => {
                    left.extend(l.map(|bounds| Ref { bounds, id: r.id }));
                    right.extend(rr.map(|bounds| Ref { bounds, id: r.id }));
                }
            }
        }
    }
    if left.is_empty() || right.is_empty() {
        return None;
    }
    let (le, re) = (Extent::of(&left), Extent::of(&right));
    Some((left, le, right, re))
}

/// Equal slabs of a node's box along one axis: slab `b` spans `[plane(b), plane(b + 1)]`.
#[derive(Clone, Copy)]
struct Slabs {
    axis: usize,
    lo: f32,
    width: f32,
}

impl Slabs {
    /// The plane between slabs `b - 1` and `b`.
    fn plane(&self, b: usize) -> f32 {
        self.lo + self.width * b as f32
    }

    /// The slab holding coordinate `x` (the end slabs take what lies beyond them).
    fn of(&self, x: f32) -> usize {
        (((x - self.lo) / self.width) as usize).min(BINS - 1)
    }

    /// Grows `boxes[first..=last]` by the parts of triangle `tri` (within `bounds`) in those slabs: each
    /// part's box is spanned by the corners in its slab and the edges' crossings of its two planes, each
    /// plane's crossings found once for the slabs on both sides. Single precision and only for the spatial
    /// bins' estimates; the references a split makes are clipped exactly ([`split_clipped_bounds`]).
    fn chop(&self, tri: &[Vec3; 3], bounds: &Aabb, first: usize, last: usize, boxes: &mut [Aabb; BINS]) {
        let mut parts = [Aabb::EMPTY; BINS];
        for &v in tri {
            let b = self.of(coord(&v, self.axis)).clamp(first, last);
            parts[b] = parts[b].grow(v);
        }
        let edges: [(Vec3, Vec3, f32, f32); 3] = std::array::from_fn(|k| {
            let (v, w) = (tri[k], tri[(k + 1) % 3]);
            let (x, y) = (coord(&v, self.axis), coord(&w, self.axis));
            (v, w - v, x, y)
        });
        for b in first + 1..=last {
            let p = self.plane(b);
            let mut cross = Aabb::EMPTY;
            for &(v, d, x, y) in &edges {
                if (x < p) != (y < p) {
                    let mut c = v + d * ((p - x) / (y - x));
                    *coord_mut(&mut c, self.axis) = p;
                    cross = cross.grow(c);
                }
            }
            parts[b - 1] = parts[b - 1].union(cross);
            parts[b] = parts[b].union(cross);
        }
        for (slab_box, part) in boxes[first..=last].iter_mut().zip(&parts[first..=last]) {
            let part = part.intersection(*bounds);
            if !part.is_empty() {
                *slab_box = slab_box.union(part);
            }
        }
    }
}

/// A spatial split: the plane `coord[axis] = pos`, with the references each side would get.
pub(super) struct SpatialSplit {
    pub(super) axis: usize,
    pub(super) pos: f32,
    /// SAH cost in units of 4-box tests.
    pub(super) cost: f32,
    pub(super) left_n: usize,
    pub(super) right_n: usize,
}

/// One axis's spatial bins: each slab's box of reference parts, and how many references enter (start) and
/// leave (end) in it.
#[derive(Clone, Copy)]
struct SpatialBins {
    boxes: [Aabb; BINS],
    enter: [usize; BINS],
    leave: [usize; BINS],
}

impl SpatialBins {
    const EMPTY: Self = Self { boxes: [Aabb::EMPTY; BINS], enter: [0; BINS], leave: [0; BINS] };

    /// Adds reference `r` of triangle `tri`.
    fn add(&mut self, slabs: &Slabs, tri: &[Vec3; 3], r: &Ref) {
        let (first, last) = (slabs.of(coord(&r.bounds.min, slabs.axis)), slabs.of(coord(&r.bounds.max, slabs.axis)));
        self.enter[first] += 1;
        self.leave[last] += 1;
        if first == last {
            self.boxes[first] = self.boxes[first].union(r.bounds);
        } else {
            slabs.chop(tri, &r.bounds, first, last, &mut self.boxes);
        }
    }

    /// The bins of both sets of references.
    fn merge(mut self, o: &Self) -> Self {
        for b in 0..BINS {
            self.boxes[b] = self.boxes[b].union(o.boxes[b]);
            self.enter[b] += o.enter[b];
            self.leave[b] += o.leave[b];
        }
        self
    }
}

/// The spatial bins of `refs` on each axis that has slabs; large nodes bin their references in parallel.
fn bin_space(ctx: &Context, refs: &[Ref], slabs: &[Option<Slabs>; 3]) -> [SpatialBins; 3] {
    let bin = |refs: &[Ref]| {
        let mut bins = [SpatialBins::EMPTY; 3];
        for (bins, slabs) in bins.iter_mut().zip(slabs) {
            if let Some(slabs) = slabs {
                for r in refs {
                    bins.add(slabs, &ctx.tris[r.id as usize], r);
                }
            }
        }
        bins
    };
    if refs.len() < PARALLEL_MIN {
        return bin(refs);
    }
    refs.par_chunks(PARALLEL_MIN / 2)
        .map(bin)
        .reduce(|| [SpatialBins::EMPTY; 3], |a, b| std::array::from_fn(|k| a[k].merge(&b[k])))
}

/// The cheapest plane between [`BINS`] equal slabs of `bounds` on any axis (Stich et al.'s spatial binning):
/// each reference is cut into every slab it crosses ([`Slabs::chop`]), and counted where it enters and where it
/// leaves.
pub(super) fn best_spatial(ctx: &Context, refs: &[Ref], bounds: &Aabb) -> Option<SpatialSplit> {
    let total = bounds.surface_area().max(f32::MIN_POSITIVE);
    let slabs: [Option<Slabs>; 3] = std::array::from_fn(|axis| {
        let lo = coord(&bounds.min, axis);
        let width = (coord(&bounds.max, axis) - lo) / BINS as f32;
        (width > 0.0 && width.is_finite()).then_some(Slabs { axis, lo, width })
    });
    let bins = bin_space(ctx, refs, &slabs);
    let mut best: Option<SpatialSplit> = None;
    for (slabs, bins) in slabs.iter().zip(&bins) {
        let Some(slabs) = slabs else { continue };
        let mut right = [(Aabb::EMPTY, 0usize); BINS];
        let (mut acc, mut n) = (Aabb::EMPTY, 0);
        for b in (1..BINS).rev() {
            (acc, n) = (acc.union(bins.boxes[b]), n + bins.leave[b]);
            right[b] = (acc, n);
        }
        let (mut acc, mut n) = (Aabb::EMPTY, 0);
        for b in 0..BINS - 1 {
            (acc, n) = (acc.union(bins.boxes[b]), n + bins.enter[b]);
            let (right_box, right_n) = right[b + 1];
            if n == 0 || right_n == 0 {
                continue;
            }
            let cost =
                C_TRAV + (acc.surface_area() * leaf_cost(n) + right_box.surface_area() * leaf_cost(right_n)) / total;
            if best.as_ref().is_none_or(|s| cost < s.cost) {
                best = Some(SpatialSplit { axis: slabs.axis, pos: slabs.plane(b + 1), cost, left_n: n, right_n });
            }
        }
    }
    best
}
