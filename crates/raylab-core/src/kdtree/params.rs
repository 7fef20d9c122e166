//! Cost-model and termination parameters of the kd-tree builder.

use serde::{Deserialize, Serialize};

/// How a node's split plane is chosen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum SplitStrategy {
    /// Minimum surface-area-heuristic cost over all perfect split candidates (thesis 2.2.1, Eq. 2.1).
    #[default]
    Sah,
    /// The spatial median of the longest axis (thesis Figure 2.9), kept only where its SAH cost beats a leaf.
    /// A baseline for tests and comparisons.
    Middle,
}

/// Parameters of [`super::KdTree::build`].
///
/// Cost of a split (thesis Eq. 2.1): `c_trav + c_isect * (N_l * SA_l / SA + N_r * SA_r / SA)`, multiplied by
/// `1 - empty_bonus` when one side holds no triangle (Wald and Havran 2006's bonus for cutting off empty
/// space). A node becomes a leaf when no split costs less than `c_isect * N`, when it reaches `max_depth`, or
/// when it is empty.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct KdParams {
    /// Cost of one traversal step.
    pub c_trav: f32,
    /// Cost of one triangle test; the thesis uses `5 * c_trav`.
    pub c_isect: f32,
    /// Fraction of the cost saved when a split cuts off empty space, in `[0, 1)`.
    pub empty_bonus: f32,
    /// Maximum depth; `None` uses `8 + 1.3 * log2(N)` (at most [`KdParams::DEPTH_LIMIT`]).
    pub max_depth: Option<u32>,
    /// Split-plane strategy.
    pub strategy: SplitStrategy,
    /// Nodes with at least this many triangles are split in parallel tasks.
    pub parallel_min_tris: usize,
}

impl Default for KdParams {
    fn default() -> Self {
        Self {
            c_trav: 1.0,
            c_isect: 5.0,
            empty_bonus: 0.8,
            max_depth: None,
            strategy: SplitStrategy::Sah,
            parallel_min_tris: 8192,
        }
    }
}

impl KdParams {
    /// Hard limit on the depth; the traversal stacks are sized from it.
    pub const DEPTH_LIMIT: u32 = 60;

    /// `c_trav` of the trees that the packet methods (packets, frustum, MFT, cone, MFT over cones) walk,
    /// against the thesis's 1 (with `c_isect` 5 in both).
    ///
    /// A frustum walk pays a node step once for a whole tile, but at each leaf it tests every packet of the
    /// (sub)frustum against the leaf's box before any triangle, and a leaf of the thesis's tree serves only a
    /// few rays: its visits, not its triangle tests, dominate. A packet's SIMD triangle test, too, costs little
    /// against a step of its walk. The SAH has no term for a leaf visit, so the split cost carries it; a
    /// larger `c_trav` gives fewer, fuller leaves. 12 is the best of a sweep over 1-24 for the frustum methods
    /// on primary and shadow rays, and packets gain from it too; single rays do not, so they keep the thesis's
    /// model.
    pub const PACKET_C_TRAV: f32 = 12.0;

    /// The depth limit used for a scene of `n` triangles.
    pub fn depth_for(&self, n: usize) -> u32 {
        let auto = || (8.0 + 1.3 * (n.max(1) as f64).log2()).round() as u32;
        self.max_depth.unwrap_or_else(auto).min(Self::DEPTH_LIMIT)
    }

    /// Checks the values are usable; returns a message naming the bad field.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.c_trav.is_finite() && self.c_trav > 0.0) {
            return Err(format!("c_trav must be finite and > 0, got {}", self.c_trav));
        }
        if !(self.c_isect.is_finite() && self.c_isect > 0.0) {
            return Err(format!("c_isect must be finite and > 0, got {}", self.c_isect));
        }
        if !(0.0..1.0).contains(&self.empty_bonus) {
            return Err(format!("empty_bonus must be in [0, 1), got {}", self.empty_bonus));
        }
        Ok(())
    }
}
