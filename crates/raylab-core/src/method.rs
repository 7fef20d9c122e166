//! Traversal methods selectable by name, behind one interface.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::dacrt::{Dacrt, DacrtParams};
use crate::kdtree::KdTree;
use crate::mbvh::Mbvh;
use crate::ray::{Hit, Ray};
use crate::reference::BruteForce;
use crate::stats::TraversalStats;

/// A way of tracing rays; the CLI's `--method` and the viewer's method list.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// One ray at a time through the kd-tree (thesis Listing 2.2).
    #[default]
    Mono,
    /// Omni-directional ray packets, 2x2 (4x2 with AVX2, 4x4 with AVX-512) (thesis 4.1.2, Listing 4.1).
    Packet,
    /// One frustum per tile with interval traversal and packet/leaf culling (Listing 4.2, 4.1.3-4.1.4).
    Frustum,
    /// Multiple Frustum Traversal: four quadrant frustums per tile in SIMD lanes (thesis 4.1.5).
    Mft,
    /// One cone frustum per tile (thesis 4.1.6-4.1.8, Eq. 4.8, Listings 4.3-4.5).
    Cone,
    /// MFT over four cones per tile (thesis 4.1.9, Table 4.5).
    MftCone,
    /// One ray at a time through the 4-wide MBVH, four boxes per SIMD test (MBVH RS paper, section 3.1).
    Mbvh,
    /// MBVH ray stream tracing: each tile is one group of rays walked breadth-first (MBVH RS paper,
    /// Algorithm 1); the tile size sets the group size (16x16 = 2^8).
    MbvhRs,
    /// Divide-and-conquer ray tracing with no stored structure (seed 003; Mora 2011, Afra 2012): each tile's
    /// rays are traced as one set against the scene's triangles, so larger tiles amortise more.
    Dacrt,
    /// Every ray against every triangle; for testing only.
    Reference,
}

impl Method {
    /// All methods, in the order menus list them.
    pub const ALL: [Method; 10] = [
        Method::Mono,
        Method::Packet,
        Method::Frustum,
        Method::Mft,
        Method::Cone,
        Method::MftCone,
        Method::Mbvh,
        Method::MbvhRs,
        Method::Dacrt,
        Method::Reference,
    ];

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Method::Mono => "mono",
            Method::Packet => "packet",
            Method::Frustum => "frustum",
            Method::Mft => "mft",
            Method::Cone => "cone",
            Method::MftCone => "mft-cone",
            Method::Mbvh => "mbvh",
            Method::MbvhRs => "mbvh-rs",
            Method::Dacrt => "dacrt",
            Method::Reference => "reference",
        }
    }

    /// True for the methods that trace tiles as packets (and so need rows of pixels).
    pub fn uses_packets(self) -> bool {
        matches!(self, Method::Packet | Method::Frustum | Method::Mft | Method::Cone | Method::MftCone)
    }

    /// True for the methods that trace a tile as bundles of packets (pyramid or cone frustums).
    pub fn is_bundled(self) -> bool {
        matches!(self, Method::Frustum | Method::Mft | Method::Cone | Method::MftCone)
    }

    /// True for the methods whose cost depends on the tile size (frustums, ray streams, whose group is the
    /// tile, and DACRT, whose ray set is).
    pub fn uses_tiles(self) -> bool {
        matches!(self, Method::Frustum | Method::Mft | Method::Cone | Method::MftCone | Method::MbvhRs | Method::Dacrt)
    }

    /// True for the methods that trace with the MBVH.
    pub fn uses_mbvh(self) -> bool {
        matches!(self, Method::Mbvh | Method::MbvhRs)
    }
}

impl Method {
    /// Fewest rays the renderers hand DACRT as one set: below this its per-set cost (dividing the triangles
    /// below the division made at setup, whatever the number of rays) outweighs the rays' own work.
    pub const DACRT_MIN_SET: u32 = 16384;

    /// True for divide-and-conquer ray tracing, which needs a [`Dacrt`] instead of a stored structure.
    pub fn uses_dacrt(self) -> bool {
        self == Method::Dacrt
    }

    /// The tile edge the renderers use for a requested `tile` with `rays_per_pixel` rays per pixel: the
    /// request, except for DACRT, whose tiles grow until they hold [`Method::DACRT_MIN_SET`] rays.
    pub fn tile_edge(self, tile: u32, rays_per_pixel: u32) -> u32 {
        let tile = tile.max(1);
        if self != Method::Dacrt {
            return tile;
        }
        let min = (Self::DACRT_MIN_SET as f64 / rays_per_pixel.max(1) as f64).sqrt().ceil() as u32;
        tile.max(min)
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Method {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Method::ALL.into_iter().find(|m| m.name() == s).ok_or_else(|| {
            let names: Vec<_> = Method::ALL.iter().map(|m| m.name()).collect();
            format!("unknown method '{s}' (valid: {})", names.join(", "))
        })
    }
}

/// Closest-hit and any-hit queries on single rays, implemented by every acceleration structure.
pub trait Intersector: Sync {
    /// The closest hit in `(tmin, tmax]`.
    fn intersect(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<Hit>;
    /// True when anything blocks the ray in `(tmin, tmax]`.
    fn occluded(&self, ray: &Ray, stats: &mut TraversalStats) -> bool;
}

impl Intersector for KdTree {
    fn intersect(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<Hit> {
        KdTree::intersect(self, ray, stats)
    }
    fn occluded(&self, ray: &Ray, stats: &mut TraversalStats) -> bool {
        KdTree::occluded(self, ray, stats)
    }
}

impl Intersector for Mbvh {
    fn intersect(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<Hit> {
        Mbvh::intersect(self, ray, stats)
    }
    fn occluded(&self, ray: &Ray, stats: &mut TraversalStats) -> bool {
        Mbvh::occluded(self, ray, stats)
    }
}

impl Intersector for BruteForce {
    fn intersect(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<Hit> {
        BruteForce::intersect(self, ray, stats)
    }
    fn occluded(&self, ray: &Ray, stats: &mut TraversalStats) -> bool {
        BruteForce::occluded(self, ray, stats)
    }
}

/// One ray traced as a set of one with the default parameters: correct, but DACRT's cost is amortised over large sets
/// ([`Dacrt::intersect`]); this serves the shared per-ray tests.
impl Intersector for Dacrt {
    fn intersect(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<Hit> {
        let mut out = [None];
        Dacrt::intersect(self, &DacrtParams::default(), &[Some(*ray)], &mut out, stats);
        out[0]
    }
    fn occluded(&self, ray: &Ray, stats: &mut TraversalStats) -> bool {
        let mut out = [false];
        Dacrt::occluded(self, &DacrtParams::default(), &[Some(*ray)], &mut out, stats);
        out[0]
    }
}
