//! One still frame exactly as `raylab-bench render` makes it: the scene, view and light from the flags, a
//! kd-tree, and the tile renderer on a pool of the given size. The viewer's tests compare its window
//! against this image.

use std::time::Instant;

use raylab_core::dacrt::Dacrt;
use raylab_core::kdtree::{KdParams, KdTree};
use raylab_core::mbvh::Mbvh;
use raylab_core::method::Method;
use raylab_core::reference::BruteForce;
use raylab_core::render::{Frame, RenderSettings, render};
use raylab_core::scene::{PointLight, Scene};
use raylab_core::trace::{TraceOptions, Tracer};

use crate::args::SceneArgs;
use crate::prepare::{build_tree, load_scene};

/// A rendered still and what it took.
pub struct Still {
    /// The scene.
    pub scene: Scene,
    /// Its kd-tree.
    pub tree: KdTree,
    /// The frame.
    pub frame: Frame,
    /// Seconds spent loading the scene.
    pub load_s: f64,
    /// Seconds spent rendering.
    pub render_s: f64,
}

/// Renders `scene`'s view with `options` on `threads` threads; `settings` makes the frame settings for the
/// scene's light (the default edge-width radius is the light's radius).
pub fn render_still(
    scene: &SceneArgs,
    kd: &KdParams,
    options: TraceOptions,
    settings: impl FnOnce(&PointLight) -> RenderSettings,
    threads: usize,
) -> Result<Still, String> {
    let (loaded, load_s) = load_scene(&scene.source())?;
    let (camera, light) = scene.camera_and_light(&loaded)?;
    let settings = &settings(&light);
    settings.shadows.validate().map_err(|e| format!("--shadows: {e}"))?;
    let tree = build_tree(&loaded, kd, threads)?;
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().map_err(|e| e.to_string())?;
    let t0 = Instant::now();
    let reference = (options.method == Method::Reference).then(|| BruteForce::new(&loaded));
    let mbvh = options.method.uses_mbvh().then(|| {
        let mut m = pool.install(|| Mbvh::build(&loaded));
        m.backend = options.backend;
        m
    });
    let dacrt = options.method.uses_dacrt().then(|| {
        let mut d = Dacrt::new(&loaded);
        d.backend = options.backend;
        d
    });
    let frame = {
        let mut tracer = Tracer::new(&tree, reference.as_ref(), options);
        if let Some(m) = &mbvh {
            tracer = tracer.with_mbvh(m);
        }
        if let Some(d) = &dacrt {
            tracer = tracer.with_dacrt(d);
        }
        pool.install(|| render(&loaded, &tracer, &camera, light, settings))
    };
    let render_s = t0.elapsed().as_secs_f64();
    Ok(Still { scene: loaded, tree, frame, load_s, render_s })
}

impl Still {
    /// The frame as an image.
    pub fn image(&self) -> Result<image::RgbaImage, String> {
        let f = &self.frame;
        image::RgbaImage::from_raw(f.width, f.height, f.rgba.as_flattened().to_vec())
            .ok_or_else(|| "frame buffer size mismatch".to_string())
    }
}
