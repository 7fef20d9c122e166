//! Traversal methods selectable by name, behind one interface.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

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
    /// Omni-directional 2x2 ray packets (thesis 4.1.2, Listing 4.1).
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
    /// Every ray against every triangle; for testing only.
    Reference,
}

impl Method {
    /// All methods, in the order menus list them.
    pub const ALL: [Method; 9] = [
        Method::Mono,
        Method::Packet,
        Method::Frustum,
        Method::Mft,
        Method::Cone,
        Method::MftCone,
        Method::Mbvh,
        Method::MbvhRs,
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
            Method::Reference => "reference",
        }
    }

    /// True for the methods that trace tiles as 2x2 packets (and so need rows of pixels).
    pub fn uses_packets(self) -> bool {
        matches!(self, Method::Packet | Method::Frustum | Method::Mft | Method::Cone | Method::MftCone)
    }

    /// True for the methods whose cost depends on the tile size (frustums, and ray streams, whose group is
    /// the tile).
    pub fn uses_tiles(self) -> bool {
        matches!(self, Method::Frustum | Method::Mft | Method::Cone | Method::MftCone | Method::MbvhRs)
    }

    /// True for the methods that trace with the MBVH.
    pub fn uses_mbvh(self) -> bool {
        matches!(self, Method::Mbvh | Method::MbvhRs)
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
