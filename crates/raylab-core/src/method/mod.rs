//! Traversal methods selectable by name, each described by its [`MethodEntry`].

mod entry;
mod structure;
mod table;

pub use entry::{BundleShape, MethodEntry, TileRule, Walk};
pub use structure::{Purpose, Structure};

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

/// A way of tracing rays; the CLI's `--method` and the viewer's method list. What each one means lives in its
/// entry ([`Method::entry`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// One ray at a time through the kd-tree (thesis Listing 2.2).
    #[default]
    Mono,
    /// Omni-directional ray packets (thesis 4.1.2, Listing 4.1).
    Packet,
    /// One frustum per tile with interval traversal and packet/leaf culling (Listing 4.2, 4.1.3-4.1.4).
    Frustum,
    /// Multiple Frustum Traversal: four quadrant frustums per tile in SIMD lanes (thesis 4.1.5).
    Mft,
    /// One cone frustum per tile (thesis 4.1.6-4.1.8).
    Cone,
    /// MFT over four cones per tile (thesis 4.1.9).
    MftCone,
    /// One ray at a time through the 4-wide MBVH (MBVH RS paper, section 3.1).
    Mbvh,
    /// MBVH ray stream tracing (MBVH RS paper, Algorithm 1).
    MbvhRs,
    /// Divide-and-conquer ray tracing with no stored structure (seed 003).
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

    /// Everything that depends on this method.
    pub fn entry(self) -> &'static MethodEntry {
        &table::ENTRIES[self as usize]
    }

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        self.entry().name
    }

    /// The structures this method needs for `purpose`: its kernel's, and for frames its
    /// [`MethodEntry::frame_kd`].
    pub fn structures(self, purpose: Purpose) -> impl Iterator<Item = Structure> {
        let e = self.entry();
        let frame_kd = if purpose == Purpose::Frames { e.frame_kd } else { None };
        std::iter::once(e.structure).chain(frame_kd)
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_method_has_its_own_entry() {
        for (i, m) in Method::ALL.into_iter().enumerate() {
            assert_eq!(m as usize, i, "Method::ALL follows the declaration order");
            assert_eq!(m.entry().method, m, "entry {i}");
            assert_eq!(m.name().parse::<Method>(), Ok(m));
            assert!(!m.entry().summary.is_empty() && !m.entry().source.is_empty(), "{m}");
        }
    }

    #[test]
    fn tile_rules() {
        assert_eq!(Method::Mono.entry().tile_edge(8, 1), 8);
        assert_eq!(Method::Mft.entry().tile_edge(0, 1), 1);
        // DACRT's tiles hold at least 16384 rays: 128x128 at one ray per pixel, 32x32 at sixteen.
        assert_eq!(Method::Dacrt.entry().tile_edge(16, 1), 128);
        assert_eq!(Method::Dacrt.entry().tile_edge(16, 16), 32);
        assert_eq!(Method::Dacrt.entry().tile_edge(256, 1), 256);
        let unit = |m: Method, tile| m.entry().unit_size(raylab_simd::Backend::Scalar, tile);
        assert_eq!(
            (unit(Method::Mono, 16), unit(Method::Packet, 16), unit(Method::MbvhRs, 16)),
            ((1, 1), (2, 2), (16, 16))
        );
        assert_eq!((unit(Method::Mft, 8), unit(Method::Dacrt, 128)), ((8, 8), (128, 128)));
    }
}
