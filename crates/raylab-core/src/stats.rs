//! Traversal counters, defined as in the thesis tables (Tsakok 2008, Tables 4.1-4.6).
//!
//! A kernel bumps plain local integers and adds them to a [`TraversalStats`] once per ray, packet or tile;
//! tiles merge with `+=`. No atomics are touched per node.

use std::ops::AddAssign;

use serde::{Deserialize, Serialize};

/// Work counted while tracing.
///
/// `nodes` counts every kd-tree node a ray, packet or frustum visits, inner nodes and leaves alike, and
/// `isect_tests` counts triangle tests; a visit or a test by a whole packet or frustum counts once. Divided by
/// `packets` (2x2 ray packets; a single ray counts as one) they are the thesis's N and I (Table 4.1).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct TraversalStats {
    /// Rays traced.
    pub rays: u64,
    /// Nodes visited (inner nodes and leaves).
    pub nodes: u64,
    /// Leaves visited (included in `nodes`).
    pub leaves: u64,
    /// Ray/triangle intersection tests (packet/triangle tests for packet kernels).
    pub isect_tests: u64,
    /// Packets traced: 2x2 packets holding at least one ray for coherent kernels, one per ray for single-ray
    /// kernels.
    pub packets: u64,
    /// Packets skipped at a leaf because none of their rays overlaps its box (thesis 4.1.4).
    pub packets_culled: u64,
    /// Packet visits to non-empty leaves that went on to triangle tests (culled ones excluded).
    pub packets_tested: u64,
    /// SIMD tests of a ray against a node's four boxes (MBVH traversal; MBVH RS paper, Figure 4).
    #[serde(default)]
    pub box_tests: u64,
    /// Rays packed into temporary packets at MBVH RS leaves.
    #[serde(default)]
    pub leaf_rays: u64,
    /// Lanes of those packets at SIMD widths 4, 8 and 16 (`leaf_rays` over these is the SIMD utilisation;
    /// MBVH RS paper, Figure 6).
    #[serde(default)]
    pub leaf_slots: [u64; 3],
    /// Shadow rays that first tested a cached blocker (the shadow cache).
    #[serde(default)]
    pub cache_lookups: u64,
    /// Cache lookups whose cached triangle blocked the ray, so no traversal was needed.
    #[serde(default)]
    pub cache_hits: u64,
}

impl AddAssign for TraversalStats {
    fn add_assign(&mut self, o: Self) {
        self.rays += o.rays;
        self.nodes += o.nodes;
        self.leaves += o.leaves;
        self.isect_tests += o.isect_tests;
        self.packets += o.packets;
        self.packets_culled += o.packets_culled;
        self.packets_tested += o.packets_tested;
        self.box_tests += o.box_tests;
        self.leaf_rays += o.leaf_rays;
        for (a, b) in self.leaf_slots.iter_mut().zip(o.leaf_slots) {
            *a += b;
        }
        self.cache_lookups += o.cache_lookups;
        self.cache_hits += o.cache_hits;
    }
}

impl TraversalStats {
    /// Average nodes visited per ray (0 when no ray was traced).
    pub fn nodes_per_ray(&self) -> f64 {
        ratio(self.nodes, self.rays)
    }

    /// Average leaves visited per ray.
    pub fn leaves_per_ray(&self) -> f64 {
        ratio(self.leaves, self.rays)
    }

    /// Average triangle tests per ray.
    pub fn isects_per_ray(&self) -> f64 {
        ratio(self.isect_tests, self.rays)
    }

    /// SIMD utilisation of MBVH RS leaf packets at widths 4, 8 and 16, in percent.
    pub fn leaf_utilisation(&self) -> [f64; 3] {
        self.leaf_slots.map(|s| 100.0 * ratio(self.leaf_rays, s))
    }

    /// Share of shadow-cache lookups that hit (0 when there were none).
    pub fn cache_hit_rate(&self) -> f64 {
        ratio(self.cache_hits, self.cache_lookups)
    }

    /// The thesis's N: nodes visited per packet.
    pub fn nodes_per_packet(&self) -> f64 {
        ratio(self.nodes, self.packets)
    }

    /// The thesis's I: intersection tests per packet.
    pub fn isects_per_packet(&self) -> f64 {
        ratio(self.isect_tests, self.packets)
    }

    /// Packet visits to leaves that packet/leaf culling skipped, as a percentage of all packet visits to
    /// leaves (culled plus tested; thesis Table 4.2); 0 when there were none.
    pub fn culled_percent(&self) -> f64 {
        100.0 * ratio(self.packets_culled, self.packets_culled + self.packets_tested)
    }
}

fn ratio(a: u64, b: u64) -> f64 {
    if b == 0 { 0.0 } else { a as f64 / b as f64 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merge_and_ratios() {
        let mut a = TraversalStats {
            rays: 2,
            nodes: 10,
            leaves: 4,
            isect_tests: 6,
            packets: 2,
            packets_culled: 0,
            packets_tested: 0,
            box_tests: 0,
            leaf_rays: 0,
            leaf_slots: [0; 3],
            cache_lookups: 1,
            cache_hits: 1,
        };
        a += TraversalStats {
            rays: 2,
            nodes: 2,
            leaves: 0,
            isect_tests: 2,
            packets: 2,
            packets_culled: 1,
            packets_tested: 3,
            box_tests: 0,
            leaf_rays: 0,
            leaf_slots: [0; 3],
            cache_lookups: 3,
            cache_hits: 0,
        };
        assert_eq!(a.nodes_per_ray(), 3.0);
        assert_eq!(a.cache_hit_rate(), 0.25);
        assert_eq!(a.isects_per_ray(), 2.0);
        assert_eq!(a.culled_percent(), 25.0, "one of four packet visits to leaves culled");
        assert_eq!(TraversalStats::default().nodes_per_ray(), 0.0);
        assert_eq!(TraversalStats::default().culled_percent(), 0.0, "no visits, nothing culled");
    }
}
