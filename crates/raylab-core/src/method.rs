//! Traversal methods selectable by name, behind one interface.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

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

    /// True for divide-and-conquer ray tracing, which needs a [`Dacrt`](crate::dacrt::Dacrt) instead of a stored structure.
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

/// A structure a method traces through; [`crate::structures::Structures`] builds them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Structure {
    /// The kd-tree with the thesis's cost model (thesis 2.2.1, Eq. 2.1, `c_trav` 1).
    ThesisKd,
    /// The kd-tree with the packet methods' cost model (`c_trav` [`crate::kdtree::KdParams::PACKET_C_TRAV`]).
    PacketKd,
    /// The 4-wide BVH (MBVH RS paper, section 2).
    Mbvh,
    /// The triangles prepared for divide-and-conquer tracing (seed 003).
    Dacrt,
    /// The brute-force reference.
    Reference,
}

impl Structure {
    /// The name reports and errors use.
    pub fn name(self) -> &'static str {
        match self {
            Structure::ThesisKd => "kd-tree",
            Structure::PacketKd => "packet kd-tree",
            Structure::Mbvh => "MBVH",
            Structure::Dacrt => "DACRT preparation",
            Structure::Reference => "brute-force reference",
        }
    }
}

/// What a set of structures is for: tracing rays only, or rendering frames, whose shadow techniques walk more.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Purpose {
    /// Closest and any hits of ray tiles (`raylab-bench trace`).
    Rays,
    /// Whole frames: also edge-width soft shadows and sampled shadows' bundles.
    Frames,
}

impl Method {
    /// The structure this method's ray kernels walk.
    pub fn kernel_structure(self) -> Structure {
        match self {
            Method::Mono => Structure::ThesisKd,
            Method::Packet | Method::Frustum | Method::Mft | Method::Cone | Method::MftCone => Structure::PacketKd,
            Method::Mbvh | Method::MbvhRs => Structure::Mbvh,
            Method::Dacrt => Structure::Dacrt,
            Method::Reference => Structure::Reference,
        }
    }

    /// The kd-tree this method's frames walk besides its kernel's structure: the edge-width walks (thesis
    /// Listing 5.1) and sampled shadows' packet and frustum walks (thesis chapter 5) need leaves in distance order,
    /// which the MBVH and DACRT do not give, so those methods walk the thesis's kd-tree for them. The kd-tree
    /// methods use their own tree, and the reference answers every query itself.
    pub fn frame_kd(self) -> Option<Structure> {
        match self.kernel_structure() {
            Structure::ThesisKd | Structure::PacketKd => Some(self.kernel_structure()),
            Structure::Mbvh | Structure::Dacrt => Some(Structure::ThesisKd),
            Structure::Reference => None,
        }
    }

    /// The structures this method needs for `purpose`: its kernel's, and for frames its [`Method::frame_kd`].
    pub fn structures(self, purpose: Purpose) -> impl Iterator<Item = Structure> {
        let frame_kd = if purpose == Purpose::Frames { self.frame_kd() } else { None };
        std::iter::once(self.kernel_structure()).chain(frame_kd)
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
