//! The viewer's animation switch: a spinning mirror and a bouncing ball (`raylab_scene::animation`) move every
//! frame in the loaded scene, and before each frame the structure the chosen method traces is brought up to
//! date: the kd-tree is rebuilt, the MBVH refitted, DACRT's triangle copy renewed (seed 003's dynamic scenes).
//! The time each update took is shown beside the frame.

use std::sync::Arc;
use std::time::Instant;

use raylab_core::dacrt::Dacrt;
use raylab_core::kdtree::KdTree;
use raylab_core::mbvh::Mbvh;
use raylab_core::method::Method;
use raylab_core::scene::Scene;
use raylab_core::shadow::Shadows;
use raylab_scene::animation::Animation;
use serde::Serialize;

use crate::loader::LoadedScene;
use crate::settings::{RenderMode, ViewerSettings};

/// What the last structure update cost; `None` for a structure the frame did not need (left stale, untouched).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct UpdateTimes {
    /// Animation time of the frame, in seconds.
    pub time_s: f64,
    /// Triangles that move.
    pub moving_triangles: usize,
    /// kd-tree rebuild.
    pub kd_rebuild_ms: Option<f64>,
    /// MBVH refit.
    pub mbvh_refit_ms: Option<f64>,
    /// DACRT's triangle copy.
    pub dacrt_setup_ms: Option<f64>,
}

/// A loaded scene with moving objects and its structures, owned by the render worker.
pub struct AnimatedScene {
    source: Arc<LoadedScene>,
    anim: Animation,
    start: Instant,
    /// The scene in its current pose.
    pub scene: Scene,
    /// Its kd-tree (current when the last frame needed it).
    pub tree: KdTree,
    /// Its MBVH (current when the last frame needed it).
    pub mbvh: Mbvh,
    /// DACRT's copy of its triangles (current when the last frame needed it).
    pub dacrt: Dacrt,
}

impl AnimatedScene {
    /// Adds the moving objects to `source`'s scene and builds its structures.
    pub fn new(source: &Arc<LoadedScene>) -> Result<Self, String> {
        let (scene, anim) = Animation::add_movers(&source.scene);
        let tree = KdTree::build(&scene, &source.params.thesis).map_err(|e| format!("animation: kd-tree: {e}"))?;
        let mbvh = Mbvh::build(&scene);
        let dacrt = Dacrt::new(&scene);
        Ok(Self { source: Arc::clone(source), anim, start: Instant::now(), scene, tree, mbvh, dacrt })
    }

    /// True when this animates `source`.
    pub fn animates(&self, source: &Arc<LoadedScene>) -> bool {
        Arc::ptr_eq(&self.source, source)
    }

    /// Moves the objects to the current time and updates what a frame with `settings` traces.
    pub fn step(&mut self, settings: &ViewerSettings) -> Result<UpdateTimes, String> {
        self.step_at(self.start.elapsed().as_secs_f64(), settings)
    }

    /// Moves the objects to time `time_s` (the hybrid mode's G-buffer gives it) and updates what a frame
    /// with `settings` traces.
    pub fn step_at(&mut self, time_s: f64, settings: &ViewerSettings) -> Result<UpdateTimes, String> {
        self.anim.apply(&mut self.scene, time_s as f32)?;
        let ms = |t: Instant| t.elapsed().as_secs_f64() * 1e3;
        let mut out = UpdateTimes { time_s, moving_triangles: self.anim.moving_triangles(), ..UpdateTimes::default() };
        let method = settings.frame_method();
        if needs_kd_tree(settings) {
            let t = Instant::now();
            // The tree of the frame's method ([`crate::loader::TreeParams`]).
            let params = self.source.params.for_method(method);
            self.tree = KdTree::build(&self.scene, params).map_err(|e| format!("animation: kd-tree: {e}"))?;
            out.kd_rebuild_ms = Some(ms(t));
        }
        if method.uses_mbvh() {
            let t = Instant::now();
            self.mbvh.refit(&self.scene).map_err(|e| format!("animation: {e}"))?;
            out.mbvh_refit_ms = Some(ms(t));
        }
        if method.uses_dacrt() {
            let t = Instant::now();
            self.dacrt = Dacrt::new(&self.scene);
            out.dacrt_setup_ms = Some(ms(t));
        }
        Ok(out)
    }
}

/// True when a frame with `settings` walks the kd-tree: the kd-tree methods, edge-width shadows (always traced
/// through it) and multi-sampled shadows (bounded by packets, pyramids or cones over it), in the Whitted and
/// hybrid modes.
fn needs_kd_tree(settings: &ViewerSettings) -> bool {
    let m = settings.frame_method();
    let structure_free = matches!(m, Method::Mbvh | Method::MbvhRs | Method::Dacrt);
    let shadows_on_kd = settings.mode != RenderMode::Distribution
        && matches!(settings.shadows, Shadows::EdgeWidth { .. } | Shadows::MultiSample { .. });
    !structure_free || shadows_on_kd
}
