//! The numbers on screen: FPS, frame time, Mrays/s, the thesis's N and I, culled packets, stage times, the
//! GPU-side costs, and time series of the last seconds; also the JSON report `--json-stats` writes.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use egui_plot::{Legend, Line, Plot, PlotPoints};
use raylab_core::render::{FrameView, StageTimes, depth_grey, heat_color};
use raylab_core::stats::TraversalStats;
use serde::Serialize;

use crate::cpu_clock::Cost;
use crate::tracer::jobs::Rendered;

/// Seconds of history the plots show.
const HISTORY_S: f64 = 20.0;

/// How often the numbers and plots on screen change while frames keep coming: often enough to follow, rarely
/// enough to read, and it bounds how often the UI has to be drawn again (see `Compositor::draw`, which reuses
/// the drawn UI while it stays the same) instead of once per traced frame.
const REFRESH: Duration = Duration::from_millis(500);

/// One traced frame, as the plots remember it.
#[derive(Clone, Copy, Debug)]
struct Sample {
    t: f64,
    ms: f64,
    n: f64,
    i: f64,
}

/// What the screen shows: the readouts as of the last refresh.
#[derive(Clone, Default)]
struct Shown {
    /// Counters, stage times and wall seconds of the latest traced frame.
    last: Option<(TraversalStats, StageTimes, f64)>,
    /// The corner's lines about the latest traced frame: wall seconds and what traced it.
    corner: Option<(f64, String)>,
    upload: Cost,
    ui: Cost,
    ui_fps: usize,
    /// The newest plotted sample's time: the plots end there.
    until_t: f64,
}

/// Running readouts.
pub struct Readouts {
    started: Instant,
    history: VecDeque<Sample>,
    /// Wall time of every frame traced so far, in milliseconds.
    frame_ms: Vec<f64>,
    /// Counters summed over every frame.
    totals: TraversalStats,
    stages: StageTimes,
    last: Option<(TraversalStats, StageTimes, f64)>,
    upload: Vec<Cost>,
    ui: Vec<Cost>,
    /// Per UI frame that uploaded a traced frame: the upload's and the UI's CPU ms together.
    upload_and_ui_ms: Vec<f64>,
    ui_frames: VecDeque<Instant>,
    /// Hybrid mode, per frame: raster, readback and trace ms, and when the frame arrived.
    hybrid_cpu: Vec<([f64; 3], Instant)>,
    /// Hybrid mode, per frame shown: upload and composite ms.
    hybrid_gpu: Vec<[f64; 2]>,
    shown: Shown,
    /// When `shown` was last refreshed.
    shown_at: Option<Instant>,
    /// A traced frame arrived since.
    pending: bool,
}

/// The hybrid mode's medians over the frames so far (`--json-stats`).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct HybridReport {
    /// Median ms of raster, readback, trace, upload and composite.
    pub stage_ms_median: [f64; 5],
    /// Median of raster + readback + trace: the CPU part of a frame.
    pub cpu_ms_median: f64,
    /// Median time between two R-buffers arriving (the hybrid frame period), in ms.
    pub period_ms_median: f64,
}

impl Default for Readouts {
    fn default() -> Self {
        Self {
            started: Instant::now(),
            history: VecDeque::new(),
            frame_ms: Vec::new(),
            totals: TraversalStats::default(),
            stages: StageTimes::default(),
            last: None,
            upload: Vec::new(),
            ui: Vec::new(),
            upload_and_ui_ms: Vec::new(),
            ui_frames: VecDeque::new(),
            hybrid_cpu: Vec::new(),
            hybrid_gpu: Vec::new(),
            shown: Shown::default(),
            shown_at: None,
            pending: false,
        }
    }
}

impl Readouts {
    /// Adds a traced frame.
    pub fn push(&mut self, r: &Rendered) {
        self.push_frame(r.frame.stats, r.frame.stages, r.wall_s);
        if let Some(h) = &r.hybrid {
            self.hybrid_cpu.push(([h.raster_ms, h.readback_ms, h.trace_ms], Instant::now()));
        }
    }

    /// Adds a traced frame's counters, stage times and wall seconds.
    fn push_frame(&mut self, s: TraversalStats, stages: StageTimes, wall_s: f64) {
        let ms = wall_s * 1e3;
        self.history.push_back(Sample {
            t: self.started.elapsed().as_secs_f64(),
            ms,
            n: s.nodes_per_packet(),
            i: s.isects_per_packet(),
        });
        let now = self.started.elapsed().as_secs_f64();
        while self.history.front().is_some_and(|x| now - x.t > HISTORY_S) {
            self.history.pop_front();
        }
        self.frame_ms.push(ms);
        self.totals += s;
        self.stages += stages;
        self.last = Some((s, stages, wall_s));
        self.pending = true;
    }

    /// Brings what the screen shows up to date with `latest` (the newest traced frame) and the UI costs, at
    /// most once per [`REFRESH`]; the first frame shows at once.
    pub fn refresh(&mut self, latest: Option<&Rendered>) {
        if !self.refresh_wait().is_zero() {
            return;
        }
        let corner = latest.map(|r| {
            let (w, h) = (r.frame.width, r.frame.height);
            let what = if r.hybrid.is_some() {
                format!("hybrid, {} reflections  {w}x{h} px", r.settings.hybrid.method)
            } else {
                format!("{} {}x{}  {w}x{h} px", r.settings.trace.method, r.settings.tile, r.settings.tile)
            };
            (r.wall_s, what)
        });
        self.shown = Shown {
            last: self.last,
            corner,
            upload: self.upload.last().copied().unwrap_or_default(),
            ui: self.ui.last().copied().unwrap_or_default(),
            ui_fps: self.ui_fps(),
            until_t: self.history.back().map_or(0.0, |s| s.t),
        };
        self.shown_at = Some(Instant::now());
        self.pending = false;
    }

    /// When to redraw the UI for a traced frame the screen does not show yet, if one arrived and no redraw
    /// comes sooner. Every arriving frame is drawn, and its figures shown once [`REFRESH`] has passed, so
    /// while frames keep coming this never adds a redraw; it gives one more `REFRESH` of grace and then shows
    /// the last frame's figures once frames stop.
    pub fn refresh_due(&self) -> Option<Duration> {
        self.pending.then(|| self.refresh_wait() + REFRESH)
    }

    /// How long until the next refresh may change the screen: none while it shows no traced frame yet.
    fn refresh_wait(&self) -> Duration {
        match self.shown_at {
            Some(t) if self.shown.last.is_some() => REFRESH.saturating_sub(t.elapsed()),
            _ => Duration::ZERO,
        }
    }

    /// Records the GPU-side cost of showing a hybrid frame: R-buffer upload and composite, in ms.
    pub fn push_hybrid_gpu(&mut self, upload_ms: f64, composite_ms: f64) {
        self.hybrid_gpu.push([upload_ms, composite_ms]);
    }

    /// The hybrid mode's medians, when hybrid frames were made.
    pub fn hybrid_report(&self) -> Option<HybridReport> {
        if self.hybrid_cpu.is_empty() {
            return None;
        }
        let cpu = |k: usize| median(self.hybrid_cpu.iter().map(|h| h.0[k]).collect());
        let gpu = |k: usize| median(self.hybrid_gpu.iter().map(|h| h[k]).collect());
        let periods: Vec<f64> =
            self.hybrid_cpu.windows(2).map(|w| w[1].1.duration_since(w[0].1).as_secs_f64() * 1e3).collect();
        Some(HybridReport {
            stage_ms_median: [cpu(0), cpu(1), cpu(2), gpu(0), gpu(1)],
            cpu_ms_median: median(self.hybrid_cpu.iter().map(|h| h.0.iter().sum()).collect()),
            period_ms_median: median(periods),
        })
    }

    /// Records the cost of a UI frame: uploading a traced frame (when one was), and building and submitting
    /// the UI.
    pub fn push_ui(&mut self, upload: Option<Cost>, ui: Cost) {
        if let Some(u) = upload {
            self.upload.push(u);
            self.upload_and_ui_ms.push(u.cpu_ms + ui.cpu_ms);
        }
        self.ui.push(ui);
        let now = Instant::now();
        self.ui_frames.push_back(now);
        while self.ui_frames.front().is_some_and(|t| now.duration_since(*t).as_secs_f64() > 1.0) {
            self.ui_frames.pop_front();
        }
    }

    /// Traced frames so far.
    pub fn frames(&self) -> usize {
        self.frame_ms.len()
    }

    /// UI frames drawn in the last second.
    pub fn ui_fps(&self) -> usize {
        self.ui_frames.len()
    }

    /// The top-right corner: FPS and frame time (in hybrid mode, of the CPU part: raster, readback, trace).
    pub fn corner(&self, ui: &mut egui::Ui) {
        match &self.shown.corner {
            Some((wall_s, what)) => {
                let ms = wall_s * 1e3;
                ui.monospace(format!("{:6.1} FPS  {:7.2} ms", 1e3 / ms.max(1e-6), ms));
                ui.monospace(what);
            }
            None => {
                ui.monospace("tracing the first frame...");
            }
        }
        ui.monospace(format!("UI redraws {:3}/s", self.shown.ui_fps));
    }

    /// The readouts section of the panel.
    pub fn panel(&self, ui: &mut egui::Ui) {
        let Some((s, st, wall)) = self.shown.last else {
            ui.label("no frame yet");
            return;
        };
        egui::Grid::new("readouts").num_columns(2).striped(true).show(ui, |ui| {
            let mut row = |k: &str, v: String| {
                ui.label(k);
                ui.monospace(v);
                ui.end_row();
            };
            row("FPS", format!("{:.1}", 1.0 / wall.max(1e-9)));
            row("frame", format!("{:.2} ms", wall * 1e3));
            row("Mrays/s", format!("{:.2}", s.rays as f64 / wall.max(1e-9) / 1e6));
            row("rays/frame", format!("{}", s.rays));
            row("N (nodes/packet)", format!("{:.2}", s.nodes_per_packet()));
            row("I (isects/packet)", format!("{:.2}", s.isects_per_packet()));
            row("packets culled", format!("{:.1} %", s.culled_percent()));
            if s.cache_lookups > 0 {
                row("shadow cache hits", format!("{:.1} %", 100.0 * s.cache_hit_rate()));
            }
            let pct = st.percentages();
            for ((name, ms), p) in StageTimes::NAMES.iter().zip(st.as_array()).zip(pct) {
                row(name, format!("{:.2} ms ({p:.0} %)", ms * 1e3));
            }
            let cost = |c: Cost| format!("{:.2} ms CPU, {:.2} wall", c.cpu_ms, c.wall_ms);
            row("upload", cost(self.shown.upload));
            row("UI", cost(self.shown.ui));
        });
        ui.small("stage times are summed over the tracer threads");
        let t0 = self.shown.until_t;
        let series = |f: fn(&Sample) -> f64| -> PlotPoints<'static> {
            self.history.iter().filter(|s| s.t <= t0).map(|s| [s.t - t0, f(s)]).collect::<Vec<_>>().into()
        };
        Plot::new("frame ms").height(90.0).legend(Legend::default()).allow_scroll(false).show(ui, |p| {
            p.line(Line::new("frame ms", series(|s| s.ms)));
        });
        Plot::new("n and i").height(90.0).legend(Legend::default()).allow_scroll(false).show(ui, |p| {
            p.line(Line::new("N", series(|s| s.n)));
            p.line(Line::new("I", series(|s| s.i)));
        });
    }

    /// The summary `--json-stats` writes.
    pub fn report(&self) -> StatsReport {
        let mut sorted = self.frame_ms.clone();
        sorted.sort_by(f64::total_cmp);
        let n = sorted.len().max(1) as f64;
        let mean_of = |v: &[Cost], f: fn(&Cost) -> f64| {
            if v.is_empty() { 0.0 } else { v.iter().map(f).sum::<f64>() / v.len() as f64 }
        };
        let total_s: f64 = sorted.iter().sum::<f64>() / 1e3;
        StatsReport {
            frames: self.frame_ms.len(),
            frame_ms_mean: sorted.iter().sum::<f64>() / n,
            frame_ms_median: sorted.get(sorted.len() / 2).copied().unwrap_or(0.0),
            frame_ms_min: sorted.first().copied().unwrap_or(0.0),
            frame_ms_max: sorted.last().copied().unwrap_or(0.0),
            fps_median: sorted.get(sorted.len() / 2).map_or(0.0, |m| 1e3 / m.max(1e-9)),
            mrays_per_s: if total_s > 0.0 { self.totals.rays as f64 / total_s / 1e6 } else { 0.0 },
            rays_per_frame: self.totals.rays as f64 / n,
            n: self.totals.nodes_per_packet(),
            i: self.totals.isects_per_packet(),
            culled_pct: self.totals.culled_percent(),
            stage_ms_per_frame: self.stages.as_array().map(|s| s * 1e3 / n),
            upload_ms_mean: mean_of(&self.upload, |c| c.cpu_ms),
            upload_wall_ms_mean: mean_of(&self.upload, |c| c.wall_ms),
            ui_ms_mean: mean_of(&self.ui, |c| c.cpu_ms),
            ui_wall_ms_mean: mean_of(&self.ui, |c| c.wall_ms),
            upload_ms_median: median(self.upload.iter().map(|c| c.cpu_ms).collect()),
            ui_ms_median: median(self.ui.iter().map(|c| c.cpu_ms).collect()),
            upload_and_ui_ms_median: median(self.upload_and_ui_ms.clone()),
            ui_frames: self.ui.len(),
        }
    }
}

/// Readouts summarised over a run.
#[derive(Clone, Debug, Serialize)]
pub struct StatsReport {
    /// Traced frames.
    pub frames: usize,
    /// Mean frame time in ms.
    pub frame_ms_mean: f64,
    /// Median frame time in ms.
    pub frame_ms_median: f64,
    /// Fastest frame in ms.
    pub frame_ms_min: f64,
    /// Slowest frame in ms.
    pub frame_ms_max: f64,
    /// FPS at the median frame time.
    pub fps_median: f64,
    /// Rays per second over all frames, in millions.
    pub mrays_per_s: f64,
    /// Mean rays per frame.
    pub rays_per_frame: f64,
    /// Thesis N over all frames.
    pub n: f64,
    /// Thesis I over all frames.
    pub i: f64,
    /// Culled packet share in percent.
    pub culled_pct: f64,
    /// Mean thread-summed ms per frame of each stage, in the order of [`StageTimes::NAMES`].
    pub stage_ms_per_frame: [f64; 5],
    /// Mean CPU ms (the UI thread's CPU time) to upload a traced frame.
    pub upload_ms_mean: f64,
    /// Mean wall ms of the uploads (their CPU time plus any wait for a core).
    pub upload_wall_ms_mean: f64,
    /// Mean CPU ms (the UI thread's CPU time) to build, encode and submit a UI frame (the upload excluded).
    pub ui_ms_mean: f64,
    /// Mean wall ms of the UI frames (their CPU time plus any wait for a core).
    pub ui_wall_ms_mean: f64,
    /// Median CPU ms of an upload (the means also count the first frames' one-off work, such as egui's font
    /// atlas).
    pub upload_ms_median: f64,
    /// Median CPU ms of a UI frame, the upload excluded.
    pub ui_ms_median: f64,
    /// Median over the UI frames that showed a new traced frame of their upload and UI CPU ms together.
    pub upload_and_ui_ms_median: f64,
    /// UI frames drawn.
    pub ui_frames: usize,
}

/// The median of `v` (the upper one of an even count; 0 when empty).
fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

/// The colour scale of a heat map or the depth view.
pub fn legend(ui: &mut egui::Ui, view: FrameView, (lo, hi): (f32, f32)) {
    let title = match view {
        FrameView::Nodes => "kd nodes per pixel",
        FrameView::Isects => "triangle tests per pixel",
        FrameView::Depth => "hit distance",
        _ => return,
    };
    ui.label(title);
    let (rect, _) = ui.allocate_exact_size(egui::vec2(180.0, 14.0), egui::Sense::hover());
    let steps = 36;
    for k in 0..steps {
        let x = k as f32 / (steps - 1) as f32;
        let c = if view == FrameView::Depth { depth_grey(x) } else { heat_color(x) };
        let w = rect.width() / steps as f32;
        let r = egui::Rect::from_min_size(rect.min + egui::vec2(k as f32 * w, 0.0), egui::vec2(w + 0.5, rect.height()));
        ui.painter().rect_filled(r, 0.0, egui::Color32::from_rgb(c[0], c[1], c[2]));
    }
    ui.horizontal(|ui| {
        ui.monospace(format!("{lo:.1}"));
        ui.add_space(110.0);
        ui.monospace(format!("{hi:.1}"));
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(rays: u64) -> TraversalStats {
        TraversalStats { rays, ..TraversalStats::default() }
    }

    #[test]
    fn the_screen_shows_new_figures_at_most_once_per_refresh() {
        let mut r = Readouts::default();
        assert_eq!(r.refresh_due(), None, "nothing traced, nothing to show");
        r.push_frame(frame(10), StageTimes::default(), 0.1);
        assert_eq!(r.refresh_due(), Some(REFRESH), "a frame waits at most one refresh for a redraw");
        let ms = |cpu_ms: f64| Cost { cpu_ms, wall_ms: cpu_ms + 1.0 };
        r.push_ui(Some(ms(0.5)), ms(2.0));
        r.refresh(None);
        assert_eq!(r.shown.last.map(|l| l.0.rays), Some(10));
        assert_eq!((r.shown.upload, r.shown.ui), (ms(0.5), ms(2.0)));
        assert_eq!(r.refresh_due(), None);

        r.push_frame(frame(20), StageTimes::default(), 0.1);
        r.push_ui(None, ms(3.0));
        let due = r.refresh_due().expect("a frame waits to be shown");
        assert!(due > REFRESH && due <= 2 * REFRESH, "{due:?}");
        r.refresh(None);
        assert_eq!(r.shown.last.map(|l| l.0.rays), Some(10), "too soon: the screen keeps the old figures");
        assert_eq!(r.shown.ui, ms(2.0));

        std::thread::sleep(REFRESH);
        assert_eq!(r.refresh_due(), Some(REFRESH));
        r.refresh(None);
        assert_eq!(r.shown.last.map(|l| l.0.rays), Some(20));
        assert_eq!(r.shown.ui, ms(3.0));
        assert_eq!(r.refresh_due(), None);
        assert_eq!(r.report().frames, 2, "the report counts every frame, shown or not");
        let report = r.report();
        assert_eq!((report.ui_ms_mean, report.ui_wall_ms_mean), (2.5, 3.5), "UI costs are averaged on both clocks");
        assert_eq!((report.upload_ms_mean, report.upload_wall_ms_mean), (0.5, 1.5));
        assert_eq!((report.ui_ms_median, report.upload_ms_median, report.upload_and_ui_ms_median), (3.0, 0.5, 2.5));
    }
}
