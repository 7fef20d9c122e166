//! Where a frame's time goes, stage by stage, in the spirit of thesis Table 3.1.

use std::ops::AddAssign;

use serde::{Deserialize, Serialize};

/// Seconds spent per stage, summed over all worker threads (so on `n` threads they add up to about `n` times
/// the frame's wall time). Traversal and intersection run interleaved inside one kernel call, so they are one
/// stage per ray kind here.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StageTimes {
    /// Primary rays: building them, traversal and intersection.
    pub primary: f64,
    /// Shadow rays: building them, traversal and occlusion tests.
    pub shadow: f64,
    /// Shading the hits and writing pixels.
    pub shading: f64,
}

impl StageTimes {
    /// All stages together.
    pub fn total(&self) -> f64 {
        self.primary + self.shadow + self.shading
    }

    /// Each stage's share of the total, in percent (zeros when nothing was timed).
    pub fn percentages(&self) -> [f64; 3] {
        let t = self.total();
        if t <= 0.0 { [0.0; 3] } else { [self.primary, self.shadow, self.shading].map(|s| 100.0 * s / t) }
    }
}

impl AddAssign for StageTimes {
    fn add_assign(&mut self, o: Self) {
        self.primary += o.primary;
        self.shadow += o.shadow;
        self.shading += o.shading;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shares_sum_to_100() {
        let mut s = StageTimes { primary: 3.0, shadow: 1.0, shading: 0.0 };
        s += StageTimes { primary: 0.0, shadow: 0.0, shading: 1.0 };
        assert_eq!(s.total(), 5.0);
        assert_eq!(s.percentages(), [60.0, 20.0, 20.0]);
        assert_eq!(StageTimes::default().percentages(), [0.0; 3]);
    }
}
