//! The 4-wide bounding volume hierarchy ("MBVH") of the MBVH RS paper (Tsakok 2009, seed 001): build, node
//! layout, single-ray traversal, ray stream tracing (MBVH RS) and refitting for moving geometry.

mod build;
mod node;
mod refit;
mod sah;
mod single;
mod spatial;
mod stream;

pub use node::{EMPTY, MbvhNode};
pub use refit::RefitError;
pub use stream::{StreamLeaves, StreamOptions};

use std::time::{Duration, Instant};

use glam::Vec3;
use serde::Serialize;

use crate::aabb::Aabb;
use crate::scene::Scene;
use crate::tri4::{PAD, Tri4, blocks_of};
use crate::triangle::TriangleSoup;

/// A 4-wide BVH over a scene's triangles.
#[derive(Clone, Debug)]
pub struct Mbvh {
    nodes: Vec<MbvhNode>,
    tri_ids: Vec<u32>,
    /// The triangles in leaf order: `tris.get(s)` is scene triangle `tri_ids[s]`, so a leaf's corners are
    /// contiguous and a test needs no indirection (padding slots hold NaN corners).
    tris: TriangleSoup,
    /// The same triangles four to a block: block `b` holds slots `4b .. 4b + 4`.
    blocks: Vec<Tri4>,
    /// Inverse of `tri_ids`: the slot of each scene triangle.
    slot_of: Vec<u32>,
    bounds: Aabb,
    build_time: Duration,
    binary_nodes: usize,
    /// Triangle references in the leaves (spatial splits put a triangle in several).
    references: usize,
    /// Levels of 4-wide nodes (the root is 1), which sizes the traversal stack.
    depth: usize,
}

/// How the MBVH build uses spatial splits (see the build module: SAH binning with the SBVH's spatial splits).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MbvhParams {
    /// Nodes with fewer triangle references than this make object splits only. Spatial splits pay most at
    /// the top of the tree, where one long triangle stretches a big box; further down they cost more build
    /// time than they save: splitting everywhere cuts box tests a little more, for several times the build
    /// time and more references. `usize::MAX` turns them off.
    pub spatial_min_refs: usize,
    /// References the whole tree may hold per triangle (at least 1): spatial splits stop once a subtree has
    /// used its share.
    pub split_budget: f32,
}

impl Default for MbvhParams {
    fn default() -> Self {
        Self { spatial_min_refs: 4096, split_budget: 1.3 }
    }
}

/// Size and shape of an MBVH.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct MbvhStats {
    /// Seconds the build took.
    pub build_seconds: f64,
    /// 4-wide nodes.
    pub nodes: usize,
    /// Nodes of the binary BVH it was collapsed from.
    pub binary_nodes: usize,
    /// Leaves (lanes holding triangles).
    pub leaves: usize,
    /// Triangle references in the leaves: the triangles plus the copies spatial splits made.
    pub references: usize,
    /// Used lanes over all lanes, in percent.
    pub lane_fill_percent: f64,
    /// Mean triangles per leaf.
    pub avg_tris_per_leaf: f64,
    /// Deepest level of 4-wide nodes (the root is 1).
    pub depth: usize,
    /// Bytes of nodes, triangle ids and four-triangle blocks.
    pub bytes: usize,
}

impl Mbvh {
    /// Builds the MBVH of `scene` on the current rayon pool, with the default [`MbvhParams`].
    pub fn build(scene: &Scene) -> Self {
        Self::build_with(scene, &MbvhParams::default())
    }

    /// Builds the MBVH of `scene` on the current rayon pool.
    pub fn build_with(scene: &Scene, params: &MbvhParams) -> Self {
        let start = Instant::now();
        let corners: Vec<[Vec3; 3]> = (0..scene.triangle_count()).map(|i| scene.vertices(i)).collect();
        let built = build::build(&corners, params);
        let tris = TriangleSoup::gather(scene, &built.tri_ids);
        let ((blocks, slot_of), depth) = rayon::join(
            || rayon::join(|| blocks_of(&tris), || inverse(&built.tri_ids, scene.triangle_count())),
            || depth_of(&built.nodes),
        );
        Self {
            blocks,
            slot_of,
            nodes: built.nodes,
            tri_ids: built.tri_ids,
            bounds: scene.bounds(),
            tris,
            build_time: start.elapsed(),
            binary_nodes: built.binary_nodes,
            references: built.references,
            depth,
        }
    }

    /// The nodes, the root first.
    pub fn nodes(&self) -> &[MbvhNode] {
        &self.nodes
    }

    /// Triangle ids indexed by leaves; each leaf starts at a multiple of four, and the padding slots after a
    /// leaf hold [`PAD`].
    pub fn tri_ids(&self) -> &[u32] {
        &self.tri_ids
    }

    /// The triangles in leaf order (slot `s` holds scene triangle `tri_ids()[s]`).
    pub fn triangles(&self) -> &TriangleSoup {
        &self.tris
    }

    /// Bounds of the scene.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// How long the build took.
    pub fn build_time(&self) -> Duration {
        self.build_time
    }

    /// Node statistics.
    pub fn stats(&self) -> MbvhStats {
        let (mut leaves, mut used, mut tris) = (0usize, 0usize, 0usize);
        for n in &self.nodes {
            for k in 0..4 {
                if !n.is_empty(k) {
                    used += 1;
                }
                if n.is_leaf(k) {
                    leaves += 1;
                    tris += n.count[k] as usize;
                }
            }
        }
        MbvhStats {
            build_seconds: self.build_time.as_secs_f64(),
            nodes: self.nodes.len(),
            binary_nodes: self.binary_nodes,
            leaves,
            references: self.references,
            lane_fill_percent: 100.0 * used as f64 / (4 * self.nodes.len()).max(1) as f64,
            avg_tris_per_leaf: tris as f64 / leaves.max(1) as f64,
            depth: self.depth,
            bytes: self.nodes.len() * std::mem::size_of::<MbvhNode>()
                + self.tri_ids.len() * 4
                + self.blocks.len() * std::mem::size_of::<Tri4>(),
        }
    }
}

/// The slot of each of the `n` triangles in the padded leaf order `ids`.
fn inverse(ids: &[u32], n: usize) -> Vec<u32> {
    let mut slot_of = vec![0u32; n];
    for (slot, &id) in ids.iter().enumerate().filter(|(_, id)| **id != PAD) {
        slot_of[id as usize] = slot as u32;
    }
    slot_of
}

/// Levels of 4-wide nodes below and including the root.
fn depth_of(nodes: &[MbvhNode]) -> usize {
    let mut depth = 0;
    let mut stack = vec![(0usize, 1usize)];
    while let Some((i, d)) = stack.pop() {
        depth = depth.max(d);
        let n = &nodes[i];
        stack.extend((0..4).filter(|&k| !n.is_empty(k) && !n.is_leaf(k)).map(|k| (n.child[k] as usize, d + 1)));
    }
    depth
}
