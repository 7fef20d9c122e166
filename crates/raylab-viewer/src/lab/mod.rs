//! The lab: the state behind the window (scene, camera, settings, worker, readouts) and the egui panels that
//! change it. It knows nothing about winit or the GPU, so the windowed and the headless runs share it.

mod bookmarks;
mod compare_table;
mod panel;
mod readouts;

use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

use raylab_cli::args::SceneArgs;
use raylab_core::scene::PointLight;
use raylab_core::structures::StructureParams;

use crate::camera::fly::{FlyCamera, MoveKeys};
use crate::camera::fly_scale::{FLY_BUDGET, FlyScale, scale_for_budget};
use crate::camera::paths::{CameraPath, Player, Recorder};
use crate::loader::{LoadPoll, LoadedScene, PendingLoad};
use crate::settings::{RenderMode, ViewerSettings};
use crate::tracer::jobs::{Job, ReflectionJob, Rendered};
use crate::tracer::worker::{Worker, WorkerEvent};
pub use bookmarks::Bookmarks;
use compare_table::CompareTable;
pub use readouts::{HybridReport, Readouts, StatsReport};

/// How long a message stays on screen.
const MESSAGE_TIME: Duration = Duration::from_secs(8);
/// Redraw interval while only a progress indicator moves.
const PROGRESS_REDRAW: Duration = Duration::from_millis(100);
/// How often the UI polls for G-buffers coming back from the GPU (hybrid mode, asynchronous readback).
const HYBRID_POLL: Duration = Duration::from_millis(2);

/// A line shown at the bottom of the window.
struct Message {
    text: String,
    error: bool,
    at: Instant,
}

/// What a screenshot request captures.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Shot {
    /// The whole window, panels included, to this file.
    Window(PathBuf),
    /// The traced frame alone, to this file.
    Traced(PathBuf),
}

/// The viewer's state.
pub struct Lab {
    scene: Arc<LoadedScene>,
    kd: StructureParams,
    /// The settings the next frame is traced with.
    pub settings: ViewerSettings,
    fly: FlyCamera,
    /// Whether the user is flying the camera, for the render scale while flying.
    flying: FlyScale,
    light: PointLight,
    worker: Worker,
    wake: Arc<dyn Fn() + Send + Sync>,
    loading: Option<PendingLoad>,
    messages: Vec<Message>,
    latest: Option<Box<Rendered>>,
    fresh: bool,
    /// Hybrid mode: a G-buffer's reflections are being traced.
    hybrid_busy: bool,
    /// Hybrid mode: G-buffers are on their way back from the GPU (the UI polls for them).
    hybrid_pending: bool,
    /// Hybrid mode: GPU-side milliseconds of the last R-buffer upload and composite.
    pub hybrid_gpu_ms: Option<(f64, f64)>,
    /// Frame times and counters.
    pub readouts: Readouts,
    compare: CompareTable,
    bookmarks: Bookmarks,
    recorder: Option<Recorder>,
    player: Option<Player>,
    keys: MoveKeys,
    /// Whether the side panel is shown.
    pub panel_visible: bool,
    window: (u32, u32),
    dirty: bool,
    shots: Vec<Shot>,
    /// Where the side panel was drawn in the last UI frame, in pixels (for tests and the stats file).
    pub panel_rect: Option<[f32; 4]>,
    /// Rectangles of everything egui drew over the traced image in the last UI frame (the panel, the
    /// overlays and windows), in pixels, without their drop shadows.
    pub ui_rects: Vec<[f32; 4]>,
    /// The GPU in use, shown in the panel.
    pub gpu_name: String,
    open_path: String,
    new_bookmark: String,
    path_file: String,
    file_dialog: Option<egui_file::FileDialog>,
}

/// A file name in the working directory with the current time in it, for screenshots.
pub fn timestamped(stem: &str) -> PathBuf {
    let secs = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_millis());
    PathBuf::from(format!("{stem}-{secs}.png"))
}

/// Scene files the Open dialog lists.
fn is_scene_file(p: &std::path::Path) -> bool {
    p.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| ["obj", "gltf", "glb"].iter().any(|x| e.eq_ignore_ascii_case(x)))
}

impl Lab {
    /// A lab showing `scene`; `wake` is called from other threads when a frame or a load is ready.
    pub fn new(
        scene: LoadedScene,
        kd: StructureParams,
        settings: ViewerSettings,
        wake: Arc<dyn Fn() + Send + Sync>,
    ) -> Self {
        let w = Arc::clone(&wake);
        let worker = Worker::start(move || w());
        let fly = FlyCamera::new(scene.camera, &scene.scene.bounds());
        let light = scene.light;
        let bookmarks = Bookmarks::load();
        Self {
            scene: Arc::new(scene),
            kd,
            settings,
            fly,
            flying: FlyScale::default(),
            light,
            worker,
            wake,
            loading: None,
            messages: Vec::new(),
            latest: None,
            fresh: false,
            hybrid_busy: false,
            hybrid_pending: false,
            hybrid_gpu_ms: None,
            readouts: Readouts::default(),
            compare: CompareTable::default(),
            bookmarks,
            recorder: None,
            player: None,
            keys: MoveKeys::default(),
            panel_visible: true,
            window: (1, 1),
            dirty: true,
            shots: Vec::new(),
            panel_rect: None,
            ui_rects: Vec::new(),
            gpu_name: String::new(),
            open_path: String::new(),
            new_bookmark: String::new(),
            path_file: "camera-path.json".into(),
            file_dialog: None,
        }
    }

    /// The scene on screen, shared.
    pub fn scene_arc(&self) -> Arc<LoadedScene> {
        Arc::clone(&self.scene)
    }

    /// The light.
    pub fn light(&self) -> PointLight {
        self.light
    }

    /// The scene on screen.
    pub fn scene(&self) -> &LoadedScene {
        &self.scene
    }

    /// Tells the lab the window's size in pixels (zero while minimised: nothing is traced then).
    pub fn set_window_size(&mut self, width: u32, height: u32) {
        if (width, height) != self.window {
            self.window = (width, height);
            self.dirty = true;
        }
    }

    /// Shows a message at the bottom of the window (and on stderr when it is an error).
    pub fn message(&mut self, text: impl Into<String>, error: bool) {
        let text = text.into();
        if error {
            eprintln!("raylab: {text}");
        }
        self.messages.push(Message { text, error, at: Instant::now() });
    }

    /// Presses or releases a movement key.
    pub fn set_keys(&mut self, f: impl FnOnce(&mut MoveKeys)) {
        f(&mut self.keys);
    }

    /// Releases every movement key (when the window loses focus).
    pub fn release_keys(&mut self) {
        self.keys = MoveKeys::default();
    }

    /// Turns the camera by a mouse motion in pixels.
    pub fn look(&mut self, dx: f32, dy: f32) {
        if self.player.is_none() && self.fly.look(dx, dy) {
            self.flying.moved();
            self.dirty = true;
        }
    }

    /// Changes the flying speed by wheel lines.
    pub fn wheel(&mut self, lines: f32) {
        self.fly.wheel(lines);
    }

    /// Moves the camera so the whole scene is in view.
    pub fn frame_scene(&mut self) {
        if self.fly.frame(&self.scene.scene.bounds()) {
            self.dirty = true;
        }
    }

    /// Asks for a screenshot, saved after the next drawn UI frame.
    pub fn request_shot(&mut self, shot: Shot) {
        self.shots.push(shot);
    }

    /// Screenshot requests of the whole window (the caller draws and saves them); traced-frame requests are
    /// saved here, from the latest frame.
    pub fn take_window_shots(&mut self) -> Vec<PathBuf> {
        let shots = std::mem::take(&mut self.shots);
        let mut window = Vec::new();
        for s in shots {
            match s {
                Shot::Window(p) => window.push(p),
                Shot::Traced(p) => match self.save_traced(&p) {
                    Ok(()) => self.message(format!("saved the traced frame to {}", p.display()), false),
                    Err(e) => self.message(e, true),
                },
            }
        }
        window
    }

    /// Writes the latest traced frame as PNG; the error names the file.
    pub fn save_traced(&self, path: &std::path::Path) -> Result<(), String> {
        let r = self.latest.as_ref().ok_or("no frame has been traced yet")?;
        let f = &r.frame;
        let img = image::RgbaImage::from_raw(f.width, f.height, f.rgba.as_flattened().to_vec())
            .ok_or("frame buffer size mismatch")?;
        img.save(path).map_err(|e| format!("cannot write {}: {e}", path.display()))
    }

    /// Starts loading another scene; the current one stays until it is ready.
    pub fn open(&mut self, scene: &str) {
        let scene = scene.trim();
        if scene.is_empty() {
            return;
        }
        let w = Arc::clone(&self.wake);
        self.loading = Some(PendingLoad::start(SceneArgs::named(scene), self.kd, move || w()));
        (self.wake)();
    }

    /// Shows the Open dialog.
    pub fn open_dialog(&mut self) {
        let mut d = egui_file::FileDialog::open_file()
            .title("Open a scene")
            .show_files_filter(Box::new(is_scene_file))
            .show_new_folder(false)
            .show_rename(false);
        d.open();
        self.file_dialog = Some(d);
    }

    /// Starts a comparison of every method and tile size on the current view.
    pub fn start_compare(&mut self) {
        let (w, h) = self.window;
        if w == 0 || h == 0 || self.compare.running() {
            return;
        }
        self.compare.start();
        self.worker.compare(self.job());
    }

    /// Shows the error of `r`, if any.
    fn report(&mut self, r: Result<(), String>) {
        if let Err(e) = r {
            self.message(e, true);
        }
    }

    /// Ends the recording and saves the path to the panel's file name.
    fn stop_recording(&mut self) {
        if let Some(rec) = self.recorder.take() {
            let file = PathBuf::from(&self.path_file);
            match rec.finish().save(&file) {
                Ok(()) => self.message(format!("saved the camera path to {}", file.display()), false),
                Err(e) => self.message(e, true),
            }
        }
    }

    /// Plays `path` from its start (one key per traced frame).
    pub fn play(&mut self, path: CameraPath, looping: bool) {
        self.recorder = None;
        self.player = Some(Player::new(path, looping));
        self.advance_player();
    }

    fn advance_player(&mut self) {
        let Some(p) = &mut self.player else { return };
        match p.advance() {
            Some(c) => {
                self.fly.camera = c;
                self.dirty = true;
            }
            None => {
                self.player = None;
                self.message("camera path finished", false);
            }
        }
    }

    /// Advances time by `dt` seconds: flies the camera with the held keys, records the path, and asks for the
    /// chosen render scale again once the camera has settled after flying.
    pub fn tick(&mut self, dt: f32) {
        if self.player.is_none() && self.fly.step(&self.keys, dt) {
            self.flying.moved();
            self.dirty = true;
        }
        if self.flying.settled() {
            // The camera stopped: trace the view again at the chosen scale.
            self.dirty = true;
        }
        if let Some(r) = &mut self.recorder {
            r.tick(self.fly.camera);
        }
        self.messages.retain(|m| m.at.elapsed() < MESSAGE_TIME);
    }

    /// Collects finished frames, comparison rows and loads; returns the newest frame not yet handed out, for
    /// upload.
    pub fn poll(&mut self) -> Option<&Rendered> {
        for ev in self.worker.drain() {
            match ev {
                WorkerEvent::Frame(r) => {
                    if r.hybrid.is_some() {
                        self.hybrid_busy = false;
                    }
                    self.readouts.push(&r);
                    self.latest = Some(r);
                    self.fresh = true;
                    if self.player.is_some() {
                        self.advance_player();
                    }
                }
                WorkerEvent::CompareRow(row, total) => self.compare.add(row, total),
                WorkerEvent::CompareDone => {
                    self.compare.finish();
                    self.dirty = true;
                }
                WorkerEvent::Error(e) => self.message(e, true),
            }
        }
        if self.compare.take_cancel() {
            self.worker.cancel_compare();
        }
        self.poll_loading();
        self.submit();
        if std::mem::take(&mut self.fresh) { self.latest.as_deref() } else { None }
    }

    /// The latest traced frame.
    pub fn latest(&self) -> Option<&Rendered> {
        self.latest.as_deref()
    }

    /// How soon the UI must be drawn again without any input or traced frame: at once while a movement
    /// key is held (the camera flies), soon while a load or a comparison shows its progress, when the oldest
    /// message expires or when a frame traced at a lower scale while flying is to be traced again at the
    /// chosen one; `None` when nothing changes by itself. Traced frames wake the UI on their own.
    pub fn next_redraw(&self) -> Option<Duration> {
        if self.keys.any() {
            return Some(Duration::ZERO);
        }
        if self.loading.is_some() || self.compare.running() {
            return Some(PROGRESS_REDRAW);
        }
        if self.hybrid_pending && !self.hybrid_busy {
            return Some(HYBRID_POLL);
        }
        let message = self.messages.iter().map(|m| MESSAGE_TIME.saturating_sub(m.at.elapsed())).min();
        message.into_iter().chain(self.readouts.refresh_due()).chain(self.flying.settle_in()).min()
    }

    fn poll_loading(&mut self) {
        let Some(l) = &self.loading else { return };
        if let LoadPoll::Done(result) = l.poll() {
            let what = l.what.clone();
            self.loading = None;
            match *result {
                Ok(s) => {
                    let kd_s = s.structures.build_seconds();
                    self.message(
                        format!(
                            "loaded {}: {} triangles in {:.2} s (structures {:.2} s)",
                            s.name,
                            s.scene.triangle_count(),
                            s.load_s,
                            kd_s
                        ),
                        false,
                    );
                    for w in &s.warnings {
                        self.message(format!("warning: {w}"), true);
                    }
                    self.fly = FlyCamera::new(s.camera, &s.scene.bounds());
                    self.light = s.light;
                    self.scene = Arc::new(s);
                    self.player = None;
                    self.recorder = None;
                    self.dirty = true;
                }
                Err(e) => self.message(format!("could not open {what}: {e} (the current scene stays)"), true),
            }
        }
    }

    /// Hybrid mode: the view to rasterise next (at the G-buffer's size), when the view changed or frames are
    /// traced continuously, and no reflections are being traced.
    pub fn hybrid_request(&mut self) -> Option<Job> {
        let (w, h) = self.window;
        let wanted = self.dirty || self.settings.continuous;
        if self.settings.mode != RenderMode::Hybrid || !wanted || w == 0 || h == 0 || self.compare.running() {
            return None;
        }
        self.dirty = false;
        let mut job = self.next_job();
        job.size = job.settings.hybrid.gbuffer_size(job.size.0, job.size.1);
        Some(job)
    }

    /// Hybrid mode: true when the worker can take a G-buffer.
    pub fn hybrid_idle(&self) -> bool {
        !self.hybrid_busy
    }

    /// Hybrid mode: hands a G-buffer read back from the GPU to the worker.
    pub fn trace_reflections(&mut self, job: ReflectionJob) {
        self.hybrid_busy = true;
        self.worker.reflections(job);
    }

    /// Hybrid mode: whether G-buffers are on their way back (so the UI keeps polling).
    pub fn set_hybrid_pending(&mut self, pending: bool) {
        self.hybrid_pending = pending;
    }

    /// Sends the current view to the worker when it changed.
    fn submit(&mut self) {
        let (w, h) = self.window;
        let hybrid = self.settings.mode == RenderMode::Hybrid;
        if !self.dirty || w == 0 || h == 0 || self.compare.running() || hybrid {
            return;
        }
        self.dirty = false;
        let job = self.next_job();
        self.worker.request(job);
    }

    /// The job for the next frame: [`Lab::job`], at a lower scale while the user flies the camera (a played
    /// camera path never) and a frame at the chosen scale would take longer than the fly budget, as the
    /// latest frame's time per pixel predicts ([`crate::camera::fly_scale`]).
    fn next_job(&mut self) -> Job {
        let mut job = self.job();
        let chosen = job.settings.scale;
        if job.settings.fly_scale
            && self.flying.flying()
            && self.player.is_none()
            && let Some(r) = &self.latest
        {
            let (w, h) = self.window;
            let pixels = u64::from(r.frame.width) * u64::from(r.frame.height);
            job.settings.scale = scale_for_budget(chosen, u64::from(w) * u64::from(h), pixels, r.wall_s, FLY_BUDGET);
            job.size = job.settings.render_size(w, h);
        }
        self.flying.sent(job.settings.scale, chosen);
        job
    }

    fn job(&self) -> Job {
        let mut settings = self.settings;
        // A playing path asks for each frame itself.
        settings.continuous &= self.player.is_none();
        Job {
            scene: Arc::clone(&self.scene),
            camera: self.fly.camera,
            light: self.light,
            settings,
            size: settings.render_size(self.window.0, self.window.1),
        }
    }

    /// Draws the panels and overlays into `ui` (the whole window).
    pub fn ui(&mut self, ui: &mut egui::Ui) {
        self.readouts.refresh(self.latest.as_deref());
        self.panel_rect = None;
        let ppp = ui.ctx().pixels_per_point();
        let px = |r: egui::Rect| [r.min.x * ppp, r.min.y * ppp, r.max.x * ppp, r.max.y * ppp];
        if self.panel_visible {
            let r = egui::Panel::left("controls")
                .resizable(true)
                .default_size(300.0)
                .show(ui, |ui| egui::ScrollArea::vertical().show(ui, |ui| panel::show(self, ui)))
                .response
                .rect;
            self.panel_rect = Some(px(r));
        }
        let mut rects: Vec<egui::Rect> = self.overlays(ui);
        let ctx = ui.ctx().clone();
        rects.extend(self.compare.window(&ctx));
        if let Some(d) = &mut self.file_dialog {
            d.show(&ctx);
            let chosen = d.selected().then(|| d.path().map(|p| p.display().to_string())).flatten();
            if d.visible() {
                // The dialog is a window that may cover the image anywhere; count all of it.
                rects.push(ctx.content_rect());
            } else {
                self.file_dialog = None;
            }
            if let Some(p) = chosen {
                self.open_path.clone_from(&p);
                self.open(&p);
            }
        }
        self.ui_rects = self.panel_rect.into_iter().chain(rects.into_iter().map(px)).collect();
    }

    /// The FPS corner, the heat-map legend and the message lines; returns the rectangles they cover.
    fn overlays(&mut self, ui: &mut egui::Ui) -> Vec<egui::Rect> {
        let ctx = ui.ctx().clone();
        let mut rects = Vec::new();
        let r = egui::Area::new(egui::Id::unique("fps"))
            .anchor(egui::Align2::RIGHT_TOP, egui::vec2(-8.0, 8.0))
            .interactable(false)
            .show(&ctx, |ui| {
                egui::Frame::popup(ui.style()).show(ui, |ui| self.readouts.corner(ui));
            });
        rects.push(r.response.rect);
        if let Some(r) = &self.latest
            && let Some(range) = r.frame.range
        {
            let r = egui::Area::new(egui::Id::unique("legend"))
                .anchor(egui::Align2::RIGHT_BOTTOM, egui::vec2(-8.0, -8.0))
                .interactable(false)
                .show(&ctx, |ui| {
                    egui::Frame::popup(ui.style()).show(ui, |ui| readouts::legend(ui, r.settings.show, range));
                });
            rects.push(r.response.rect);
        }
        let loading = self.loading.as_ref().map(|l| {
            let (stage, t) = l.stage();
            format!("{}: {stage}... {:.1} s", l.what, t.as_secs_f32())
        });
        let status: Vec<(String, Option<bool>)> = loading
            .into_iter()
            .map(|t| (t, None))
            .chain(self.messages.iter().map(|m| (m.text.clone(), Some(m.error))))
            .collect();
        if !status.is_empty() {
            let r = egui::Area::new(egui::Id::unique("messages"))
                .anchor(egui::Align2::CENTER_BOTTOM, egui::vec2(0.0, -8.0))
                .interactable(false)
                .show(&ctx, |ui| {
                    egui::Frame::popup(ui.style()).show(ui, |ui| {
                        for (text, error) in status {
                            match error {
                                Some(true) => ui.colored_label(ui.visuals().error_fg_color, text),
                                Some(false) => ui.label(text),
                                None => {
                                    ui.horizontal(|ui| {
                                        ui.spinner();
                                        ui.label(text);
                                    })
                                    .response
                                }
                            };
                        }
                    });
                });
            rects.push(r.response.rect);
        }
        rects
    }
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use raylab_core::kdtree::KdParams;
    use raylab_core::method::Method;
    use raylab_core::ray_order::RayOrder;
    use raylab_core::render::FrameView;
    use raylab_core::trace::TraceOptions;

    use super::*;
    use crate::loader::load_now;
    use raylab_core::shadow::Shadows;

    use crate::settings::{DistributionControls, RenderMode};

    fn lab(method: Method) -> Lab {
        let kd = StructureParams::default();
        let scene = load_now(&SceneArgs::named("arena"), &kd, &|_| {}).unwrap();
        let settings = ViewerSettings {
            mode: RenderMode::Whitted,
            trace: TraceOptions { method, ..TraceOptions::default() },
            tile: 8,
            shadows: Shadows::Hard,
            depth: 3,
            distribution: DistributionControls::default(),
            hybrid: crate::settings::HybridControls::default(),
            order: RayOrder::Scanline,
            show: FrameView::Shaded,
            heat_max: None,
            scale: 100,
            fly_scale: true,
            threads: 2,
            continuous: false,
            animate: false,
        };
        Lab::new(scene, kd, settings, Arc::new(|| {}))
    }

    /// Polls until `done` holds (at most a minute).
    fn wait(lab: &mut Lab, done: impl Fn(&Lab) -> bool) {
        let t0 = Instant::now();
        while !done(lab) {
            assert!(t0.elapsed() < Duration::from_secs(60), "timed out");
            lab.poll();
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    fn run_ui(lab: &mut Lab) {
        let ctx = egui::Context::default();
        let raw = egui::RawInput {
            screen_rect: Some(egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(900.0, 700.0))),
            ..Default::default()
        };
        let mut out = ctx.run_ui(raw, |ui| lab.ui(ui));
        assert!(!out.shapes.is_empty());
        out.textures_delta.clear();
    }

    #[test]
    fn traces_draws_the_panel_and_keeps_the_scene_when_an_open_fails() {
        let mut l = lab(Method::Mft);
        l.set_window_size(48, 32);
        wait(&mut l, |l| l.latest().is_some());
        let f = &l.latest().unwrap().frame;
        assert_eq!((f.width, f.height), (48, 32));
        assert!(f.stats.rays > 0);
        run_ui(&mut l);
        assert!(l.panel_rect.is_some_and(|r| r[2] > r[0]));
        assert_eq!(l.ui_rects.first().copied(), l.panel_rect);

        l.open("no/such/scene.obj");
        wait(&mut l, |l| l.loading.is_none());
        assert_eq!(l.scene().name, "arena", "a failed open keeps the current scene");
        assert!(l.messages.iter().any(|m| m.error && m.text.contains("no/such/scene.obj")));
        run_ui(&mut l);

        l.open("kitchen");
        wait(&mut l, |l| l.loading.is_none());
        assert_eq!(l.scene().name, "kitchen");
        wait(&mut l, |l| l.latest().is_some_and(|r| r.frame.stats.rays > 0) && !l.dirty);
    }

    #[test]
    fn a_minimised_window_traces_nothing_and_resumes() {
        let mut l = lab(Method::Packet);
        l.set_window_size(0, 0);
        for _ in 0..20 {
            l.poll();
            std::thread::sleep(Duration::from_millis(5));
        }
        assert!(l.latest().is_none());
        l.set_window_size(20, 10);
        wait(&mut l, |l| l.latest().is_some());
        let f = &l.latest().unwrap().frame;
        assert_eq!((f.width, f.height), (20, 10));
    }

    #[test]
    fn compare_measures_every_configuration() {
        let mut l = lab(Method::Mono);
        l.set_window_size(16, 16);
        l.start_compare();
        wait(&mut l, |l| !l.compare.running());
        let want = crate::tracer::compare::compare_configs(8);
        assert_eq!(l.compare.rows.len(), want.len());
        for (row, (m, t)) in l.compare.rows.iter().zip(&want) {
            assert_eq!((row.method, row.tile), (*m, *t));
            assert!(row.fps > 0.0 && row.n > 0.0, "{row:?}");
        }
        let md = l.compare.markdown();
        assert_eq!(md.lines().count(), want.len() + 2);
        assert!(md.lines().any(|line| line.starts_with("| mft | 64x64 |")), "{md}");
        run_ui(&mut l);
    }

    /// Packets and frustums walk the tree built for them, the single-ray methods the thesis's, and the pixels
    /// are the same either way.
    #[test]
    fn each_method_walks_its_own_kd_tree() {
        let mut l = lab(Method::Mft);
        l.set_window_size(40, 24);
        let s = l.scene();
        let kd = |m| s.structures.kd_for(m).unwrap();
        let (thesis, packets) = (kd(Method::Mono), kd(Method::Mft));
        assert_eq!(thesis.params().c_trav, KdParams::default().c_trav);
        assert_eq!(packets.params().c_trav, KdParams::PACKET_C_TRAV);
        let nodes = |t: &raylab_core::kdtree::KdTree| t.nodes().len();
        assert!(nodes(packets) < nodes(thesis), "{} vs {} nodes", nodes(packets), nodes(thesis));
        assert!(std::ptr::eq(kd(Method::MbvhRs), thesis) && std::ptr::eq(kd(Method::Packet), packets));
        let job = l.job();
        let frames: Vec<_> = [Method::Mono, Method::Packet, Method::Mft, Method::Frustum]
            .into_iter()
            .map(|m| crate::tracer::jobs::trace_frame(&job, m).frame)
            .collect();
        for f in &frames[1..] {
            assert!(f.stats.rays > 0);
            assert_eq!(f.rgba, frames[0].rgba);
        }
    }

    /// Frames traced while the user flies drop to the scale the fly budget allows, and the view is traced
    /// again at the chosen scale once the camera settles; with the switch off the scale stays.
    #[test]
    fn flying_lowers_the_scale_until_the_camera_settles() {
        for on in [true, false] {
            let mut l = lab(Method::Mft);
            l.settings.fly_scale = on;
            l.set_window_size(64, 48);
            wait(&mut l, |l| l.latest().is_some());
            // As if the last full frame had taken a second: 25% is the most that fits 1/30 s.
            l.latest.as_mut().unwrap().wall_s = 1.0;
            l.look(4.0, 0.0);
            let flown = if on { (16, 12) } else { (64, 48) };
            wait(&mut l, |l| l.latest().is_some_and(|r| r.wall_s < 1.0) && !l.dirty);
            let r = l.latest().unwrap();
            assert_eq!((r.frame.width, r.frame.height), flown, "fly scale {on}");
            assert_eq!(r.settings.scale, if on { 25 } else { 100 });
            let again = l.flying.settled() || l.flying.settle_in().is_some();
            assert_eq!(again, on, "a reduced frame is to be traced again at the chosen scale");
            std::thread::sleep(crate::camera::fly_scale::SETTLE);
            l.tick(0.0);
            wait(&mut l, |l| l.latest().is_some_and(|r| r.settings.scale == 100) && !l.dirty);
            let f = &l.latest().unwrap().frame;
            assert_eq!((f.width, f.height), (64, 48), "the chosen scale is back");
            assert_eq!(l.flying.settle_in(), None);
        }
    }

    #[test]
    fn camera_paths_play_one_key_per_frame() {
        let mut l = lab(Method::Frustum);
        l.set_window_size(16, 16);
        let start = l.fly.camera;
        let mut moved = start;
        moved.eye += glam::Vec3::new(0.5, 0.0, 0.0);
        moved.target += glam::Vec3::new(0.5, 0.0, 0.0);
        l.play(CameraPath { scene: "arena".into(), keys: vec![start, moved] }, false);
        wait(&mut l, |l| l.player.is_none());
        assert_eq!(l.fly.camera, moved);
        assert!(l.readouts.frames() >= 2);
    }
}
