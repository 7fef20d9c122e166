//! Where a frame's time goes, stage by stage, after thesis Table 3.1.

use std::ops::AddAssign;

use serde::{Deserialize, Serialize};

/// Seconds spent per stage, summed over all worker threads (so on `n` threads they add up to about `n` times
/// the frame's wall time). Traversal and intersection run interleaved inside one kernel call, so they are one
/// timed stage per ray kind; the triangle tests each trace stage made are counted, so that Table 3.1's split
/// can charge them at a separately measured cost per test (`raylab-bench tables`).
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
    /// Triangle tests (per packet for packet kernels) made during the primary trace stage.
    #[serde(default)]
    pub primary_tests: u64,
    /// Triangle tests made during the secondary trace stage.
    #[serde(default)]
    pub secondary_tests: u64,
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

    /// Names of the stages of [`StageTimes::split`], in its order.
    pub const SPLIT_NAMES: [&'static str; 7] = [
        "primary traversal",
        "primary intersection",
        "primary shading",
        "secondary traversal",
        "secondary intersection",
        "secondary shading",
        "shadows",
    ];

    /// The stages with each trace stage split into traversal and intersection, charging the stage's triangle
    /// tests `seconds_per_test` each (capped at the stage's time): primary traversal, primary intersection,
    /// primary shading, secondary traversal, secondary intersection, secondary shading, shadows (Table 3.1's
    /// rows).
    pub fn split(&self, seconds_per_test: f64) -> [f64; 7] {
        let part = |time: f64, tests: u64| {
            let isect = (tests as f64 * seconds_per_test).clamp(0.0, time.max(0.0));
            (time - isect, isect)
        };
        let (pt, pi) = part(self.primary, self.primary_tests);
        let (st, si) = part(self.secondary, self.secondary_tests);
        [pt, pi, self.shading, st, si, self.secondary_shading, self.shadow]
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
        self.primary_tests += o.primary_tests;
        self.secondary_tests += o.secondary_tests;
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

    #[test]
    fn split_charges_tests_and_never_exceeds_a_stage() {
        let s = StageTimes {
            primary: 2.0,
            secondary: 1.0,
            primary_tests: 100,
            secondary_tests: 1000,
            ..Default::default()
        };
        let split = s.split(0.005);
        assert_eq!(split[..2], [1.5, 0.5]);
        assert_eq!(split[3..5], [0.0, 1.0], "capped at the stage's time");
        assert_eq!(split.iter().sum::<f64>(), s.total());
    }
}
