//! Where a frame's time goes, stage by stage, after thesis Table 3.1.

use std::ops::AddAssign;

use serde::{Deserialize, Serialize};

/// Seconds spent per stage, summed over all worker threads (so on `n` threads they add up to about `n` times
/// the frame's wall time). Traversal and intersection run interleaved inside one kernel call, so they are one
/// stage per ray kind here; Table 3.1's split between them comes from a profile (see docs/BENCHMARKS.md).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StageTimes {
    /// Primary rays: building them, traversal and intersection.
    pub primary: f64,
    /// Shading primary hits: materials, textures, building secondary rays, combining their colours, writing
    /// pixels.
    pub shading: f64,
    /// Reflection and refraction rays: traversal and intersection.
    #[serde(default)]
    pub secondary: f64,
    /// Shading the hits of reflection and refraction rays.
    #[serde(default)]
    pub secondary_shading: f64,
    /// Shadow rays of all hits: building them, traversal and occlusion tests.
    pub shadow: f64,
}

impl StageTimes {
    /// Stage names, in the order of [`StageTimes::as_array`].
    pub const NAMES: [&'static str; 5] =
        ["primary trace", "primary shading", "secondary trace", "secondary shading", "shadows"];

    /// The stages as an array, in the order of [`StageTimes::NAMES`].
    pub fn as_array(&self) -> [f64; 5] {
        [self.primary, self.shading, self.secondary, self.secondary_shading, self.shadow]
    }

    /// All stages together.
    pub fn total(&self) -> f64 {
        self.as_array().iter().sum()
    }

    /// Each stage's share of the total, in percent, in the order of [`StageTimes::NAMES`] (zeros when
    /// nothing was timed).
    pub fn percentages(&self) -> [f64; 5] {
        let t = self.total();
        if t <= 0.0 { [0.0; 5] } else { self.as_array().map(|s| 100.0 * s / t) }
    }
}

impl AddAssign for StageTimes {
    fn add_assign(&mut self, o: Self) {
        self.primary += o.primary;
        self.shading += o.shading;
        self.secondary += o.secondary;
        self.secondary_shading += o.secondary_shading;
        self.shadow += o.shadow;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shares_sum_to_100() {
        let mut s = StageTimes { primary: 3.0, shadow: 1.0, ..StageTimes::default() };
        s += StageTimes { shading: 0.5, secondary: 0.25, secondary_shading: 0.25, ..StageTimes::default() };
        assert_eq!(s.total(), 5.0);
        assert_eq!(s.percentages(), [60.0, 10.0, 5.0, 5.0, 20.0]);
        assert_eq!(StageTimes::default().percentages(), [0.0; 5]);
    }
}
