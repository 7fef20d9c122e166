//! The render scale while the camera flies: when a traced frame at the chosen scale would take longer than
//! [`FLY_BUDGET`], the frames traced while the user moves the camera drop to the scale that fits the budget
//! (never under 25%), so flying stays fluid on a slow machine; the chosen scale comes back once the camera has
//! been still for [`SETTLE`]. Interactive ray tracers commonly trade resolution for latency this way while
//! the view moves. Camera paths played back and automated runs never move by user input, so their frames
//! keep the chosen scale and stay comparable.

use std::time::{Duration, Instant};

/// The traced-frame time aimed at while flying: 30 frames per second.
pub const FLY_BUDGET: Duration = Duration::from_micros(33_333);

/// How long the camera must be still before frames are traced at the chosen scale again.
pub const SETTLE: Duration = Duration::from_millis(250);

/// The smallest render scale in percent (the panel's lower bound).
const MIN_SCALE: u32 = 25;

/// The scale steps, in percent: coarse enough that the frame size does not change with every frame time.
const STEP: u32 = 5;

/// The render scale, in percent, at which a frame should take about `budget`, given that the last frame
/// traced `pixels` pixels in `wall_s` seconds and the window has `window_pixels` pixels: the frame time taken
/// as proportional to the pixel count, to the nearest percent and then down to a multiple of 5, between 25
/// and `chosen` (the panel's scale). The chosen scale when the last frame tells nothing (no pixels, no time).
pub fn scale_for_budget(chosen: u32, window_pixels: u64, pixels: u64, wall_s: f64, budget: Duration) -> u32 {
    let per_pixel = wall_s / pixels as f64;
    if !(per_pixel.is_finite() && per_pixel > 0.0) || window_pixels == 0 {
        return chosen;
    }
    let fits = budget.as_secs_f64() / per_pixel / window_pixels as f64;
    // To the nearest percent first, so that a frame time at a step's edge does not fall a step by rounding.
    let percent = (100.0 * fits.sqrt()).round().min(chosen as f64) as u32;
    (percent / STEP * STEP).clamp(MIN_SCALE.min(chosen), chosen)
}

/// Whether the user is flying the camera, and whether the frame last asked for was traced at a reduced scale.
#[derive(Debug, Default)]
pub struct FlyScale {
    /// When the user last moved the camera.
    last_motion: Option<Instant>,
    /// The last job asked for a scale under the chosen one.
    reduced: bool,
}

impl FlyScale {
    /// The user moved the camera (keys or mouse).
    pub fn moved(&mut self) {
        self.last_motion = Some(Instant::now());
    }

    /// True while the camera moved less than [`SETTLE`] ago.
    pub fn flying(&self) -> bool {
        self.last_motion.is_some_and(|t| t.elapsed() < SETTLE)
    }

    /// Records the scale of the job just sent against the chosen one.
    pub fn sent(&mut self, scale: u32, chosen: u32) {
        self.reduced = scale < chosen;
    }

    /// True when the last frame asked for was reduced and the camera has settled: the view is to be traced
    /// again at the chosen scale.
    pub fn settled(&self) -> bool {
        self.reduced && !self.flying()
    }

    /// How soon [`FlyScale::settled`] turns true without further input, while a reduced frame is shown and
    /// the camera has not settled yet; `None` once it has (the view is then marked for tracing, and a UI
    /// that cannot send the job yet, minimised or comparing methods, need not wake for it).
    pub fn settle_in(&self) -> Option<Duration> {
        let left = SETTLE.checked_sub(self.last_motion.filter(|_| self.reduced)?.elapsed())?;
        (!left.is_zero()).then_some(left)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const WINDOW: u64 = 1280 * 720;

    #[test]
    fn the_scale_fits_the_budget_between_its_bounds() {
        let budget = Duration::from_millis(30);
        // A full frame in 120 ms: a quarter of the pixels fits 30 ms, half the scale.
        assert_eq!(scale_for_budget(100, WINDOW, WINDOW, 0.120, budget), 50);
        // The last frame was already reduced: its cost per pixel is what counts.
        assert_eq!(scale_for_budget(100, WINDOW, WINDOW / 4, 0.030, budget), 50);
        // Rounded down to a step of 5: sqrt(30 / 50) = 0.775.
        assert_eq!(scale_for_budget(100, WINDOW, WINDOW, 0.050, budget), 75);
        // Fast frames keep the chosen scale, slow ones stop at 25%.
        assert_eq!(scale_for_budget(80, WINDOW, WINDOW, 0.010, budget), 80);
        assert_eq!(scale_for_budget(100, WINDOW, WINDOW, 10.0, budget), 25);
        // A chosen scale under 25% is never raised.
        assert_eq!(scale_for_budget(20, WINDOW, WINDOW, 10.0, budget), 20);
    }

    #[test]
    fn frames_that_tell_nothing_keep_the_chosen_scale() {
        let budget = FLY_BUDGET;
        assert_eq!(scale_for_budget(90, WINDOW, 0, 0.1, budget), 90);
        assert_eq!(scale_for_budget(90, WINDOW, WINDOW, 0.0, budget), 90);
        assert_eq!(scale_for_budget(90, WINDOW, WINDOW, f64::NAN, budget), 90);
        assert_eq!(scale_for_budget(90, 0, WINDOW, 0.1, budget), 90);
    }

    #[test]
    fn the_chosen_scale_returns_once_the_camera_settles() {
        let mut f = FlyScale::default();
        assert!(!f.flying() && !f.settled() && f.settle_in().is_none());
        f.moved();
        f.sent(50, 100);
        assert!(f.flying() && !f.settled());
        assert!(f.settle_in().is_some_and(|d| d <= SETTLE));
        std::thread::sleep(SETTLE + Duration::from_millis(20));
        assert!(!f.flying() && f.settled());
        assert_eq!(f.settle_in(), None, "settled: nothing more to wait for");
        f.sent(100, 100);
        assert!(!f.settled() && f.settle_in().is_none(), "the full-scale frame was asked for");
    }
}
