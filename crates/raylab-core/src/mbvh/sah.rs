//! The binned SAH's vocabulary, shared by the MBVH build's object splits and its spatial splits: triangle
//! references, extents, costs and the build context.

use glam::Vec3;

use crate::aabb::Aabb;

/// SAH bins per node and axis, for object and for spatial splits.
pub(super) const BINS: usize = 16;
/// SAH cost of a node: one 4-box test, the unit of the SAH costs here.
pub(super) const C_TRAV: f32 = 1.0;

/// SAH cost of one ray against a four-triangle block ([`tri4`](crate::tri4)'s watertight test). Counting leaves by
/// blocks rather than triangles makes leaves of up to four triangles, which one block test covers: fewer box
/// tests per ray for a few more triangle tests, a net gain for single rays and streams alike.
pub(super) const C_BLOCK: f32 = 2.0;

/// Nodes with at least this many references build their halves in parallel.
pub(super) const PARALLEL_MIN: usize = 4096;

/// A triangle reference: a triangle and the part of its box inside the node that holds it (the whole box,
/// unless spatial splits cut the triangle).
#[derive(Clone, Copy)]
pub(super) struct Ref {
    pub(super) bounds: Aabb,
    pub(super) id: u32,
}

impl Ref {
    pub(super) fn centroid(&self) -> Vec3 {
        self.bounds.center()
    }
}

/// What every level of the build reads.
pub(super) struct Context<'a> {
    pub(super) tris: &'a [[Vec3; 3]],
    /// Surface area of the root's box, against which split overlaps are measured.
    pub(super) root_area: f32,
    /// Nodes with fewer references make object splits only.
    pub(super) spatial_min: usize,
}

/// The box of some references and the box of their centroids.
#[derive(Clone, Copy)]
pub(super) struct Extent {
    pub(super) bounds: Aabb,
    pub(super) centroids: Aabb,
}

impl Extent {
    /// The extent of `refs`, by a pass over them.
    pub(super) fn of(refs: &[Ref]) -> Self {
        refs.iter().fold(Extent { bounds: Aabb::EMPTY, centroids: Aabb::EMPTY }, |e, r| Extent {
            bounds: e.bounds.union(r.bounds),
            centroids: e.centroids.grow(r.centroid()),
        })
    }
}

/// Two children's references and extents.
pub(super) type Parts = (Vec<Ref>, Extent, Vec<Ref>, Extent);

/// SAH cost of a leaf of `n` triangles: its four-triangle blocks, as leaves are padded to whole blocks and a
/// ray tests one block at a time, so one to four triangles cost the same.
pub(super) fn leaf_cost(n: usize) -> f32 {
    n.div_ceil(4) as f32 * C_BLOCK
}
