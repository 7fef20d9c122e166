//! The SAH kd-tree (Tsakok 2008, chapters 2-3): build, compact layout, statistics and traversal kernels.

mod build;
pub(crate) mod clip;
mod edge_width;
pub mod frustum;
mod leaf_bounds;
pub mod mft;
pub mod mono;
mod node;
pub mod packet;
mod params;
mod stats;

pub use node::{KdNode, MAX_INDEX};
pub use params::{KdParams, SplitStrategy};
pub use stats::KdStats;

use std::time::{Duration, Instant};

use crate::aabb::{Aabb, coord_mut};
use crate::scene::Scene;
use crate::triangle::TriangleSoup;
use build::BuildNode;
use leaf_bounds::LeafBounds;

/// Why a kd-tree could not be built.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum KdBuildError {
    /// A parameter is out of range; the message names it.
    Params(String),
    /// The scene or the tree has more triangles or nodes than the 8-byte node can index.
    TooLarge {
        /// What overflowed.
        what: &'static str,
        /// Its size.
        count: usize,
    },
}

impl std::fmt::Display for KdBuildError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Params(m) => write!(f, "invalid kd-tree parameters: {m}"),
            Self::TooLarge { what, count } => {
                write!(f, "kd-tree too large: {count} {what} (at most {MAX_INDEX})")
            }
        }
    }
}

impl std::error::Error for KdBuildError {}

/// A kd-tree over a scene's triangles, in the traversal layout: 8-byte nodes with adjacent children, leaves
/// indexing a contiguous triangle-id array, and two copies of the triangle corners for the intersection
/// kernels: by triangle id, and by reference in leaf order.
#[derive(Clone, Debug)]
pub struct KdTree {
    nodes: Vec<KdNode>,
    tri_ids: Vec<u32>,
    tris: TriangleSoup,
    /// The corners of each reference's triangle, side by side in leaf order (`ref_tris.get(r)` is triangle
    /// `tri_ids[r]`): single rays test a leaf without first loading its ids, and the leaf's corners share
    /// cache lines (Sponza: 327,571 references, 11.8 MB).
    ref_tris: TriangleSoup,
    bounds: Aabb,
    leaf_bounds: LeafBounds,
    params: KdParams,
    build_time: Duration,
}

impl KdTree {
    /// Relative padding of the root box, so that rays grazing the scene's bounding planes enter the tree.
    pub const ROOT_PADDING: f32 = 1e-6;

    /// Builds the tree for `scene` with `params`.
    pub fn build(scene: &Scene, params: &KdParams) -> Result<Self, KdBuildError> {
        params.validate().map_err(KdBuildError::Params)?;
        let start = Instant::now();
        let tris = TriangleSoup::from_scene(scene);
        if tris.len() > MAX_INDEX {
            return Err(KdBuildError::TooLarge { what: "triangles", count: tris.len() });
        }
        let scene_bounds = scene.bounds();
        let out = if tris.is_empty() {
            build::BuildOutput { nodes: vec![BuildNode::Leaf { first: 0, count: 0 }], tri_ids: vec![] }
        } else {
            build::build(tris.as_slice(), scene_bounds, params)
        };
        if out.nodes.len() > MAX_INDEX || out.tri_ids.len() > MAX_INDEX {
            return Err(KdBuildError::TooLarge { what: "nodes or triangle references", count: out.nodes.len() });
        }
        // The builder puts every child pair at an odd index; one padding node after the root moves them to
        // even indices, so a pair fills one aligned 16-byte block and `far = near ^ 1`.
        let shift = |i: u32| if i == 0 { 0 } else { i + 1 };
        let mut nodes: Vec<KdNode> = Vec::with_capacity(out.nodes.len() + 1);
        for (i, n) in out.nodes.iter().enumerate() {
            nodes.push(match *n {
                BuildNode::Inner { axis, split, left } => KdNode::inner(axis as usize, split, shift(left)),
                BuildNode::Leaf { first, count } => KdNode::leaf(first, count),
            });
            if i == 0 {
                nodes.push(KdNode::leaf(0, 0));
            }
        }
        let bounds = if tris.is_empty() { Aabb::EMPTY } else { scene_bounds.padded(Self::ROOT_PADDING) };
        let leaf_bounds = LeafBounds::default();
        let mut tree = Self {
            nodes,
            ref_tris: TriangleSoup::gather(scene, &out.tri_ids),
            tri_ids: out.tri_ids,
            tris,
            bounds,
            leaf_bounds,
            params: *params,
            build_time: Duration::ZERO,
        };
        tree.leaf_bounds = LeafBounds::new(&tree.tri_ids, &tree.tris, |f| {
            tree.visit(|_, cell, n| f(cell, n));
        });
        tree.build_time = start.elapsed();
        Ok(tree)
    }

    /// The box a ray must reach to hit anything in leaf `n`, which must be a non-empty leaf: its cell
    /// intersected with its triangles' bounds, padded a little (for packet/leaf culling).
    #[inline(always)]
    pub fn leaf_bounds(&self, n: KdNode) -> Aabb {
        self.leaf_bounds.get(n)
    }

    /// The nodes; the root is node 0.
    pub fn nodes(&self) -> &[KdNode] {
        &self.nodes
    }

    /// Triangle ids referenced by the leaves.
    pub fn tri_ids(&self) -> &[u32] {
        &self.tri_ids
    }

    /// The triangle corners the kernels test.
    pub fn triangles(&self) -> &TriangleSoup {
        &self.tris
    }

    /// The corners of the triangle each reference names, in leaf order: reference `r` is triangle
    /// `tri_ids()[r]`.
    pub fn ref_triangles(&self) -> &TriangleSoup {
        &self.ref_tris
    }

    /// The (slightly padded) box of the root node; empty for an empty scene.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// The parameters the tree was built with.
    pub fn params(&self) -> &KdParams {
        &self.params
    }

    /// Wall time of [`KdTree::build`].
    pub fn build_time(&self) -> Duration {
        self.build_time
    }

    /// Walks the finished tree and gathers its statistics.
    pub fn stats(&self) -> KdStats {
        KdStats::gather(self)
    }

    /// Calls `f(depth, bounds, node)` for every node, parents before children.
    pub fn visit(&self, mut f: impl FnMut(u32, &Aabb, KdNode)) {
        if self.tris.is_empty() {
            f(0, &self.bounds, self.nodes[0]);
            return;
        }
        let mut stack = vec![(0usize, 0u32, self.bounds)];
        while let Some((i, depth, b)) = stack.pop() {
            let n = self.nodes[i];
            f(depth, &b, n);
            if !n.is_leaf() {
                let (mut lb, mut rb) = (b, b);
                *coord_mut(&mut lb.max, n.axis()) = n.split();
                *coord_mut(&mut rb.min, n.axis()) = n.split();
                stack.push((n.left() + 1, depth + 1, rb));
                stack.push((n.left(), depth + 1, lb));
            }
        }
    }
}
