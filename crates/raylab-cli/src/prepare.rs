//! Loading a scene (with a progress bar) and building its kd-tree (with a spinner), on a terminal.

use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};
use raylab_core::kdtree::{KdParams, KdTree};
use raylab_core::method::{Method, Purpose};
use raylab_core::scene::Scene;
use raylab_core::structures::{StructureParams, Structures};
use raylab_scene::SceneSource;

/// Runs `f` while a spinner with `msg` turns on stderr (hidden when stderr is not a terminal).
pub fn with_spinner<T>(msg: &str, f: impl FnOnce() -> T) -> T {
    let bar = ProgressBar::new_spinner();
    if let Ok(style) = ProgressStyle::with_template("{spinner} {msg} {elapsed}") {
        bar.set_style(style);
    }
    bar.set_message(msg.to_string());
    bar.enable_steady_tick(Duration::from_millis(100));
    let out = f();
    bar.finish_and_clear();
    out
}

/// Loads the scene named by `source`, printing the loader's warnings to stderr; the error names the scene or
/// file.
pub fn load_scene(source: &SceneSource) -> Result<(Scene, f64), String> {
    let (loaded, seconds) = load_scene_verbose(source)?;
    for w in &loaded.warnings {
        eprintln!("warning: {w}");
    }
    Ok((loaded.scene, seconds))
}

/// Loads the scene named by `source` with its warnings, with a progress bar on a terminal.
pub fn load_scene_verbose(source: &SceneSource) -> Result<(raylab_scene::Loaded, f64), String> {
    let t0 = Instant::now();
    let bar = ProgressBar::new(1000);
    if let Ok(style) = ProgressStyle::with_template("loading scene [{bar:30}] {percent}% {elapsed}") {
        bar.set_style(style.progress_chars("=> "));
    }
    let loaded = raylab_scene::load_with_progress(source, &|done| bar.set_position((done * 1000.0) as u64));
    bar.finish_and_clear();
    Ok((loaded.map_err(|e| e.to_string())?, t0.elapsed().as_secs_f64()))
}

/// Builds the structures `methods` need for `purpose` on a pool of `threads` threads.
pub fn build_structures(
    scene: &Scene,
    methods: &[Method],
    purpose: Purpose,
    params: &StructureParams,
    threads: usize,
) -> Result<Structures, String> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| format!("cannot start {threads} threads: {e}"))?;
    with_spinner("building structures", || pool.install(|| Structures::build(scene, methods, purpose, params)))
        .map_err(|e| e.to_string())
}

/// Builds the kd-tree on a pool of `threads` threads.
pub fn build_tree(scene: &Scene, params: &KdParams, threads: usize) -> Result<KdTree, String> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| format!("cannot start {threads} threads: {e}"))?;
    with_spinner("building kd-tree", || pool.install(|| KdTree::build(scene, params))).map_err(|e| e.to_string())
}
