//! The viewer's animation switch: a spinning mirror and a bouncing ball (`raylab_scene::animation`) move every
//! frame in the loaded scene, and before each frame the structure the chosen method traces is brought up to
//! date: the kd-tree is rebuilt, the MBVH refitted, DACRT's triangle copy renewed (seed 003's dynamic scenes).
//! The time each update took is shown beside the frame.

use std::sync::Arc;
use std::time::Instant;

use raylab_core::method::{Method, Purpose, Structure};
use raylab_core::scene::Scene;
use raylab_core::shadow::Shadows;
use raylab_core::structures::Structures;
use raylab_scene::animation::Animation;
use serde::Serialize;

use crate::loader::{LoadedScene, viewer_methods};
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
    /// Its structures, each current when the last frame needed it.
    pub structures: Structures,
}

impl AnimatedScene {
    /// Adds the moving objects to `source`'s scene and builds its structures.
    pub fn new(source: &Arc<LoadedScene>) -> Result<Self, String> {
        let (scene, anim) = Animation::add_movers(&source.scene);
        let methods: Vec<Method> = viewer_methods().collect();
        let params = source.structures.params();
        let structures = Structures::build(&scene, &methods, Purpose::Frames, params)
            .map_err(|e| format!("animation: kd-tree: {e}"))?;
        Ok(Self { source: Arc::clone(source), anim, start: Instant::now(), scene, structures })
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
        let mut out = UpdateTimes { time_s, moving_triangles: self.anim.moving_triangles(), ..UpdateTimes::default() };
        let method = settings.frame_method();
        let mut update = |which: Structure| -> Result<Option<f64>, String> {
            let t = self.structures.update_one(&self.scene, which).map_err(|e| format!("animation: {e}"))?;
            Ok(t.map(|t| t.as_secs_f64() * 1e3))
        };
        if let Some(kd) = kd_tree_walked(settings) {
            // The packet methods' tree may be the thesis's (equal parameters): then the thesis's is rebuilt.
            out.kd_rebuild_ms = match update(kd)? {
                None => update(Structure::ThesisKd)?,
                t => t,
            };
        }
        match method.entry().structure {
            Structure::Mbvh => out.mbvh_refit_ms = update(Structure::Mbvh)?,
            Structure::Dacrt => out.dacrt_setup_ms = update(Structure::Dacrt)?,
            _ => {}
        }
        Ok(out)
    }
}

/// The kd-tree a frame with `settings` walks, if any: the kd-tree methods' own, and the method's
/// [`MethodEntry::frame_kd`](raylab_core::method::MethodEntry::frame_kd) for edge-width shadows (always traced through it) and multi-sampled shadows (bounded
/// by packets, pyramids or cones over it), in the Whitted and hybrid modes.
fn kd_tree_walked(settings: &ViewerSettings) -> Option<Structure> {
    let m = settings.frame_method();
    let kernel_on_kd = matches!(m.entry().structure, Structure::ThesisKd | Structure::PacketKd);
    let shadows_on_kd = settings.mode != RenderMode::Distribution
        && matches!(settings.shadows, Shadows::EdgeWidth { .. } | Shadows::MultiSample { .. });
    (kernel_on_kd || shadows_on_kd).then(|| m.entry().frame_kd).flatten()
}
