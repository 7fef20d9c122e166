//! What a method is: the one place that answers every question that depends on the method.

use raylab_simd::Backend;

use super::{Method, Structure};

/// Everything that depends on a traversal method. The tracer, the renderers, the benchmark and the viewer ask
/// the method's entry ([`Method::entry`]) instead of matching on the method, so a new method is its kernel and
/// one entry in the method table (`method/table.rs`).
#[derive(Debug)]
pub struct MethodEntry {
    /// The method this entry describes.
    pub method: Method,
    /// The name used on the command line, in reports and in the viewer.
    pub name: &'static str,
    /// One line saying what the method does.
    pub summary: &'static str,
    /// The source section it implements.
    pub source: &'static str,
    /// How its kernels walk: the tracer's entry points choose a kernel by this.
    pub walk: Walk,
    /// The structure the kernel walks; for the kd-tree kernels this picks the cost model the tree is built with.
    pub structure: Structure,
    /// The kd-tree its frames walk besides [`MethodEntry::structure`]: the edge-width walks (thesis Listing 5.1)
    /// and sampled shadows' packet and frustum walks (thesis chapter 5) need leaves in distance order, which the
    /// MBVH and DACRT do not give, so those methods walk the thesis's kd-tree for them. `None` for the
    /// reference, which answers every query itself.
    pub frame_kd: Option<Structure>,
    /// How the tile size the user asks for becomes the tile the renderers trace.
    pub tiles: TileRule,
    /// Why the viewer does not offer it for live frames, when it does not. Every method traces every render
    /// mode (Whitted frames, the distribution tracer, the hybrid mode's reflections) through the same tracer.
    pub not_live: Option<&'static str>,
}

/// The walks the tracer drives, each a kernel of its own. Methods that share a walk differ only in their entry
/// (its structure, tile rule or options); a method that walks in a new way adds a variant here and its arm in
/// the tracer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Walk {
    /// One ray at a time down a kd-tree (thesis Listing 2.2); shadow caches and edge widths ray by ray too.
    KdRay,
    /// SIMD packets of a tile's rays down a kd-tree (thesis 4.1.2, Listing 4.1); edge widths as packets.
    KdPacket,
    /// A tile's packets as one bundle down a kd-tree, and packets where no bundle bounds the rays (thesis 4.1.3
    /// to 4.1.9); edge widths of many segments toward a light as one bundle from the light.
    KdBundle(BundleShape),
    /// One ray at a time through the MBVH, four boxes per test (MBVH RS paper, section 3.1); edge widths and
    /// sampled shadows through [`MethodEntry::frame_kd`]'s packets.
    MbvhRay,
    /// Each tile (or [`crate::trace::TraceOptions::stream_group`] rays of it) as one breadth-first ray stream
    /// through the MBVH (MBVH RS paper, Algorithm 1).
    MbvhStream,
    /// Each tile's rays as one set against the scene's triangles, no stored structure (seed 003); cached
    /// shadows trace their misses as one set too.
    DacrtSet,
    /// Every ray against every triangle, for every query, frames' shadows included.
    BruteForce,
}

/// The bundle a [`Walk::KdBundle`] method bounds a tile's rays with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BundleShape {
    /// One pyramid frustum per tile (thesis Listing 4.2, 4.1.3).
    Frustum,
    /// One cone per tile (thesis 4.1.6-4.1.8, Eq. 4.8).
    Cone,
    /// Four quadrant frustums in SIMD lanes (thesis 4.1.5).
    MftFrustums,
    /// Four quadrant cones in SIMD lanes (thesis 4.1.9).
    MftCones,
}

impl BundleShape {
    /// True for the cone bundles.
    pub fn is_cone(self) -> bool {
        matches!(self, BundleShape::Cone | BundleShape::MftCones)
    }
}

/// How a requested tile edge becomes the traced tile.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TileRule {
    /// The tile is only the threads' work unit: the kernel's cost does not depend on it.
    WorkUnit,
    /// The tile is what the kernel traces as one bundle, stream or set, so its size changes the cost.
    Traced,
    /// As [`TileRule::Traced`], and tiles grow until they hold at least this many rays: below it the per-set
    /// cost (DACRT divides the triangles below the setup's division for every set) outweighs the rays' work.
    AtLeast(u32),
}

impl MethodEntry {
    /// True when the tile size changes the method's cost (its bundles, streams or sets are the tile).
    pub fn tile_matters(&self) -> bool {
        self.tiles != TileRule::WorkUnit
    }

    /// True for the methods that trace a tile as SIMD packets (with or without bundles), which need the tile's
    /// pixels row by row.
    pub fn packets(&self) -> bool {
        matches!(self.walk, Walk::KdPacket | Walk::KdBundle(_))
    }

    /// The bundle shape of a [`Walk::KdBundle`] method.
    pub fn bundle(&self) -> Option<BundleShape> {
        match self.walk {
            Walk::KdBundle(b) => Some(b),
            _ => None,
        }
    }

    /// The fewest rays one traced tile holds ([`TileRule::AtLeast`]), if the method asks for any.
    pub fn min_tile_rays(&self) -> Option<u32> {
        match self.tiles {
            TileRule::AtLeast(n) => Some(n),
            _ => None,
        }
    }

    /// The tile edge the renderers use for a requested `tile` with `rays_per_pixel` rays per pixel: the
    /// request, grown for [`TileRule::AtLeast`] until a tile holds that many rays.
    pub fn tile_edge(&self, tile: u32, rays_per_pixel: u32) -> u32 {
        let tile = tile.max(1);
        match self.tiles {
            TileRule::AtLeast(n) => tile.max((n as f64 / rays_per_pixel.max(1) as f64).sqrt().ceil() as u32),
            TileRule::WorkUnit | TileRule::Traced => tile,
        }
    }

    /// Width and height of the blocks the method traces as one unit with `backend`'s lanes: the whole tile
    /// when the tile is traced, a packet ([`crate::packet::packet_shape`]) for packets, else one ray.
    pub fn unit_size(&self, backend: Backend, tile: u32) -> (u32, u32) {
        if self.tile_matters() {
            (tile, tile)
        } else if self.packets() {
            let (w, h) = crate::packet::packet_shape(backend.lanes());
            (w as u32, h as u32)
        } else {
            (1, 1)
        }
    }
}
