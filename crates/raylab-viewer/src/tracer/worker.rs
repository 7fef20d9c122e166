//! The render worker: one thread that owns a rayon pool of the chosen size and traces the latest requested
//! frame below the UI's thread priority ([`TracerPriority`]), so the window's event loop never waits for the
//! tracer. Requests replace each other (only the newest matters); in continuous mode the last view is traced
//! again and again to give steady FPS readings.

use std::sync::mpsc::{self, Receiver, Sender};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::Instant;

use raylab_core::distribution::{Accumulator, render_pass};
use raylab_core::render::{Frame, StageTimes};
use raylab_core::stats::TraversalStats;
use raylab_core::trace::TraceOptions;

use raylab_core::ray::Ray;
use raylab_core::render::hybrid::{reflection_ray, shade_reflection_set};
use raylab_core::render::shade::to_display;
use raylab_core::render::surface_epsilon;

use crate::animated::AnimatedScene;
use crate::settings::RenderMode;
use crate::tracer::compare::{CompareRow, compare_configs};
use crate::tracer::jobs::{HybridFrame, Job, ReflectionJob, Rendered, Traced, trace_in};
use crate::tracer::priority::TracerPriority;

/// The distribution mode's image in progress and the view it belongs to.
struct Progressive {
    job: Job,
    acc: Accumulator,
    passes: u32,
}

impl Progressive {
    /// True when `job` shows the same view with the same settings (so its passes may be added).
    fn same_view(&self, job: &Job) -> bool {
        let (a, b) = (&self.job, job);
        Arc::ptr_eq(&a.scene, &b.scene)
            && a.camera == b.camera
            && a.light == b.light
            && a.settings == b.settings
            && a.size == b.size
    }
}

/// What the worker reports.
pub enum WorkerEvent {
    /// A finished frame.
    Frame(Box<Rendered>),
    /// One measured configuration of a method comparison, and how many there are in all.
    CompareRow(CompareRow, usize),
    /// The comparison finished (or was cancelled).
    CompareDone,
    /// Something went wrong (for example the thread pool could not start); the message says what.
    Error(String),
}

enum Task {
    Frame(Job),
    Compare(Job),
    Reflections(Box<ReflectionJob>),
}

#[derive(Default)]
struct State {
    next: Option<Task>,
    repeat: Option<Job>,
    cancel: bool,
    quit: bool,
}

struct Shared {
    state: Mutex<State>,
    wake_worker: Condvar,
}

impl Shared {
    /// The state, even if a panicking thread poisoned the lock (the state stays consistent: plain fields).
    fn lock(&self) -> MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(|p| p.into_inner())
    }
}

/// Handle to the render worker thread.
pub struct Worker {
    shared: Arc<Shared>,
    events: Receiver<WorkerEvent>,
    thread: Option<JoinHandle<()>>,
}

impl Worker {
    /// Starts the worker; `wake` is called after every event it sends (to wake the event loop).
    pub fn start(wake: impl Fn() + Send + 'static) -> Self {
        let shared = Arc::new(Shared { state: Mutex::new(State::default()), wake_worker: Condvar::new() });
        let (tx, events) = mpsc::channel();
        let s = Arc::clone(&shared);
        let priority = TracerPriority::below_caller();
        let thread = std::thread::Builder::new()
            .name("raylab-render".into())
            .spawn(move || run(&s, &tx, &wake, priority))
            .expect("the operating system refused to start the render thread");
        Self { shared, events, thread: Some(thread) }
    }

    /// Asks for `job` to be traced next, replacing any request not yet started.
    pub fn request(&self, job: Job) {
        self.shared.lock().next = Some(Task::Frame(job));
        self.shared.wake_worker.notify_one();
    }

    /// Asks for the reflections of a G-buffer (hybrid mode), replacing any request not yet started.
    pub fn reflections(&self, job: ReflectionJob) {
        let mut st = self.shared.lock();
        st.repeat = None;
        st.next = Some(Task::Reflections(Box::new(job)));
        drop(st);
        self.shared.wake_worker.notify_one();
    }

    /// Asks for a comparison of every method and tile size on `job`'s view.
    pub fn compare(&self, job: Job) {
        let mut st = self.shared.lock();
        st.cancel = false;
        st.next = Some(Task::Compare(job));
        drop(st);
        self.shared.wake_worker.notify_one();
    }

    /// Stops a running comparison after its current configuration.
    pub fn cancel_compare(&self) {
        self.shared.lock().cancel = true;
    }

    /// Events sent since the last call.
    pub fn drain(&self) -> Vec<WorkerEvent> {
        self.events.try_iter().collect()
    }
}

impl Drop for Worker {
    fn drop(&mut self) {
        let mut st = self.shared.lock();
        st.quit = true;
        st.cancel = true;
        drop(st);
        self.shared.wake_worker.notify_one();
        if let Some(t) = self.thread.take() {
            // A worker that panicked has nothing left to clean up.
            let _ = t.join();
        }
    }
}

/// The worker's loop; it and its pool's threads run at `priority`.
fn run(shared: &Shared, tx: &Sender<WorkerEvent>, wake: &dyn Fn(), priority: TracerPriority) {
    priority.apply();
    let mut pool: Option<(usize, rayon::ThreadPool)> = None;
    let mut progressive: Option<Progressive> = None;
    let mut animated: Option<AnimatedScene> = None;
    let mut rbuffer = Interlaced::default();
    loop {
        let task = {
            let mut st = shared.lock();
            loop {
                if st.quit {
                    return;
                }
                if let Some(t) = st.next.take() {
                    break t;
                }
                if let Some(j) = st.repeat.clone() {
                    break Task::Frame(j);
                }
                st = shared.wake_worker.wait(st).unwrap_or_else(|p| p.into_inner());
            }
        };
        let job = match &task {
            Task::Frame(j) | Task::Compare(j) => j,
            Task::Reflections(r) => &r.job,
        };
        let threads = job.settings.threads.max(1);
        if pool.as_ref().is_none_or(|(n, _)| *n != threads) {
            let pool_result =
                rayon::ThreadPoolBuilder::new().num_threads(threads).start_handler(move |_| priority.apply()).build();
            match pool_result {
                Ok(p) => pool = Some((threads, p)),
                Err(e) => {
                    shared.lock().repeat = None;
                    send(tx, wake, WorkerEvent::Error(format!("cannot start {threads} tracer threads: {e}")));
                    continue;
                }
            }
        }
        let Some((_, pool)) = pool.as_ref() else { continue };
        // With the animation on, move the objects and update the structures this frame traces.
        let update = match &task {
            Task::Frame(job) if job.settings.animate => {
                if !animated.as_ref().is_some_and(|a| a.animates(&job.scene)) {
                    animated = match pool.install(|| AnimatedScene::new(&job.scene)) {
                        Ok(a) => Some(a),
                        Err(e) => {
                            shared.lock().repeat = None;
                            send(tx, wake, WorkerEvent::Error(e));
                            continue;
                        }
                    };
                }
                let Some(a) = animated.as_mut() else { continue };
                match pool.install(|| a.step(&job.settings)) {
                    Ok(u) => Some(u),
                    Err(e) => {
                        shared.lock().repeat = None;
                        send(tx, wake, WorkerEvent::Error(e));
                        continue;
                    }
                }
            }
            // The reflections of an animated G-buffer pose the scene themselves, at the G-buffer's time.
            Task::Reflections(r) if r.animation_time.is_some() => None,
            _ => {
                animated = None;
                None
            }
        };
        let moving = animated.as_ref().filter(|_| update.is_some());
        match task {
            Task::Frame(job) if job.settings.mode == RenderMode::Distribution => {
                // Moving geometry starts the image afresh every frame.
                if moving.is_some() || !progressive.as_ref().is_some_and(|p| p.same_view(&job)) {
                    let acc = Accumulator::new(job.size.0.max(1), job.size.1.max(1));
                    progressive = Some(Progressive { job: job.clone(), acc, passes: 0 });
                }
                let Some(p) = progressive.as_mut() else { continue };
                let s = moving.map_or_else(|| job.scene.traced(), AnimatedScene::traced);
                let mut rendered = pool.install(|| distribution_pass(p, &s));
                rendered.animation = update;
                // Keep refining while the view stays, up to the pass limit.
                let more = p.passes < job.settings.distribution.max_passes.max(1);
                let again = more || job.settings.continuous || job.settings.animate;
                shared.lock().repeat = again.then(|| job.clone());
                send(tx, wake, WorkerEvent::Frame(Box::new(rendered)));
            }
            Task::Frame(job) => {
                let s = moving.map_or_else(|| job.scene.traced(), AnimatedScene::traced);
                let mut rendered = pool.install(|| trace_in(&s, &job, job.settings.trace.method));
                rendered.animation = update;
                shared.lock().repeat = (job.settings.continuous || job.settings.animate).then(|| job.clone());
                send(tx, wake, WorkerEvent::Frame(Box::new(rendered)));
            }
            Task::Reflections(r) => {
                let mut update = None;
                if let Some(t) = r.animation_time {
                    if !animated.as_ref().is_some_and(|a| a.animates(&r.job.scene)) {
                        match pool.install(|| AnimatedScene::new(&r.job.scene)) {
                            Ok(a) => animated = Some(a),
                            Err(e) => {
                                send(tx, wake, WorkerEvent::Error(e));
                                continue;
                            }
                        }
                    }
                    let Some(a) = animated.as_mut() else { continue };
                    match pool.install(|| a.step_at(t, &r.job.settings)) {
                        Ok(u) => update = Some(u),
                        Err(e) => {
                            send(tx, wake, WorkerEvent::Error(e));
                            continue;
                        }
                    }
                }
                let s = match (&animated, update) {
                    (Some(a), Some(_)) => a.traced(),
                    _ => r.job.scene.traced(),
                };
                let mut rendered = pool.install(|| reflections(&r, &s, &mut rbuffer));
                rendered.animation = update;
                send(tx, wake, WorkerEvent::Frame(Box::new(rendered)));
            }
            Task::Compare(job) => {
                let configs = compare_configs(job.settings.tile);
                for (method, tile) in &configs {
                    if shared.lock().cancel {
                        break;
                    }
                    let row = pool.install(|| crate::tracer::compare::measure(&job, *method, *tile));
                    send(tx, wake, WorkerEvent::CompareRow(row, configs.len()));
                }
                send(tx, wake, WorkerEvent::CompareDone);
            }
        }
    }
}

fn send(tx: &Sender<WorkerEvent>, wake: &dyn Fn(), ev: WorkerEvent) {
    // The receiver goes away only when the viewer closes, when nobody needs the event.
    let _ = tx.send(ev);
    wake();
}

/// The R-buffer (and its display bytes) kept from frame to frame for interlacing, and which rows come next.
#[derive(Default)]
struct Interlaced {
    size: (u32, u32),
    colors: Vec<[f32; 4]>,
    rgba: Vec<[u8; 4]>,
    phase: u32,
}

/// Traces and shades the reflection rays of `r`'s G-buffer on the current rayon pool: every row, or every
/// k-th row in turn when interlacing (the other rows keep the previous frame's reflections). The readback
/// kept only the reflective pixels; those in the traced rows get rays, and only they are traced and written,
/// so the cost follows the mirrors on screen rather than the G-buffer's size.
fn reflections(r: &ReflectionJob, s: &Traced, kept: &mut Interlaced) -> Rendered {
    let t0 = Instant::now();
    let job = &r.job;
    let g = &r.gbuffer;
    let (w, h) = (g.width, g.height);
    let k = job.settings.hybrid.interlace.max(1);
    let n = w as usize * h as usize;
    if kept.size != (w, h) || kept.colors.len() != n {
        *kept =
            Interlaced { size: (w, h), colors: vec![[0.0, 0.0, 0.0, 1.0]; n], rgba: vec![[0, 0, 0, 255]; n], phase: 0 };
    }
    let phase = kept.phase % k;
    kept.phase = kept.phase.wrapping_add(1);
    let eps = surface_epsilon(s.scene);
    let row_len = (w as usize).max(1);
    let raster = job.camera.raster(w, h);
    // The readback kept only the reflective pixels; those of the traced rows get rays.
    let reflective = g.reflective.len();
    let set: Vec<(u32, Ray)> = g
        .reflective
        .iter()
        .filter(|t| (t.index as usize / row_len) as u32 % k == phase)
        .filter_map(|t| reflection_ray(job.camera.eye, &g.pixel(&raster, t), eps).map(|r| (t.index, r)))
        .collect();
    let settings = job.settings.render_settings(w, h);
    let options = TraceOptions { method: job.settings.hybrid.method, ..job.settings.trace };
    let tracer = s.tracer(options);
    let (colors, stats, stages) = shade_reflection_set(s.scene, &tracer, &job.camera, job.light, &settings, &set);
    // The traced rows start black; then their reflective pixels get their colours.
    let rows = kept.colors.chunks_mut(row_len).zip(kept.rgba.chunks_mut(row_len));
    for (_, (colors, rgba)) in rows.enumerate().filter(|(y, _)| *y as u32 % k == phase) {
        colors.fill([0.0, 0.0, 0.0, 1.0]);
        rgba.fill([0, 0, 0, 255]);
    }
    for (&(i, _), c) in set.iter().zip(&colors) {
        kept.colors[i as usize] = [c.x, c.y, c.z, 1.0];
        kept.rgba[i as usize] = [to_display(c.x), to_display(c.y), to_display(c.z), 255];
    }
    let trace_ms = t0.elapsed().as_secs_f64() * 1e3;
    let frame = Frame { width: w, height: h, rgba: kept.rgba.clone(), stats, stages, range: None };
    let hybrid = HybridFrame {
        size: (w, h),
        rbuffer: kept.colors.clone(),
        eye: job.camera.eye,
        reflective,
        rays: set.len(),
        raster_ms: r.raster_ms,
        readback_ms: r.readback_ms,
        trace_ms,
    };
    Rendered {
        frame,
        wall_s: (r.raster_ms + r.readback_ms + trace_ms) / 1e3,
        settings: job.settings,
        paths: None,
        animation: None,
        hybrid: Some(Box::new(hybrid)),
    }
}

/// Adds one distribution pass, traced in `s`, to `p` on the current rayon pool and returns the refined image.
fn distribution_pass(p: &mut Progressive, s: &Traced) -> Rendered {
    let job = &p.job;
    let (w, h) = (p.acc.width, p.acc.height);
    let settings = job.settings.distribution.settings(w, h, job.settings.tile);
    let tracer = s.tracer(job.settings.trace);
    let mut camera = job.camera;
    camera.aperture = job.settings.distribution.aperture;
    let light = job.light.soft();
    let t0 = Instant::now();
    let bounces = render_pass(s.scene, &tracer, &camera, light, &settings, p.passes, &mut p.acc);
    p.passes += 1;
    let mut stats = TraversalStats::default();
    let mut stages = StageTimes::default();
    for (k, b) in bounces.iter().enumerate() {
        stats += b.stats;
        if k == 0 {
            stages.primary += b.seconds;
        } else {
            stages.secondary += b.seconds;
        }
        stages.shadow += b.shadow_seconds;
    }
    let frame = Frame { width: w, height: h, rgba: p.acc.rgba(), stats, stages, range: None };
    Rendered {
        frame,
        wall_s: t0.elapsed().as_secs_f64(),
        settings: job.settings,
        paths: Some(p.acc.paths),
        animation: None,
        hybrid: None,
    }
}
