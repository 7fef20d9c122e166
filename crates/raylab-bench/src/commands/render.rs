//! `raylab-bench render`: one frame, shaded with the scene's materials under a chosen shadow technique,
//! written as PNG.

use std::path::PathBuf;

use clap::Args;
use raylab_bench::still::{Still, render_still};
use raylab_core::render::{FrameView, RayOrder, RenderSettings};

use crate::args::{ImageArgs, KdArgs, MethodArgs, SceneArgs, ShadeArgs, in_range, parse_positive};

/// Renders one frame to a PNG file.
#[derive(Args, Debug)]
pub struct RenderArgs {
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    kd: KdArgs,
    #[command(flatten)]
    image: ImageArgs,
    /// Output PNG file.
    #[arg(long, default_value = "raylab.png")]
    out: PathBuf,
    #[command(flatten)]
    m: MethodArgs,
    /// Pixel order inside a tile: scanline, morton or hilbert.
    #[arg(long, default_value = "scanline")]
    order: RayOrder,
    #[command(flatten)]
    shade: ShadeArgs,
    /// What the image shows: shaded, nodes or isects (heat maps of the work per pixel), normals or depth.
    #[arg(long, default_value = "shaded")]
    show: FrameView,
    /// Count at the hot end of the heat maps (default: the frame's maximum).
    #[arg(long, value_parser = parse_positive)]
    heat_max: Option<f32>,
    /// Worker threads (default: all CPUs).
    #[arg(long, value_parser = in_range(1, 1024))]
    threads: Option<u64>,
    /// Render the frame this many times and report the median frame time and its stages: the tracing and
    /// shading cost of a viewer frame, without the window.
    #[arg(long, default_value_t = 1, value_parser = in_range(1, 100_000))]
    frames: u64,
}

impl RenderArgs {
    /// The default action of a bare `raylab-bench`: the default scene to `raylab.png`.
    pub fn default_scene() -> Self {
        use clap::Parser;
        #[derive(Parser)]
        struct Wrap {
            #[command(flatten)]
            r: RenderArgs,
        }
        Wrap::parse_from(["raylab-bench"]).r
    }
}

/// Runs the command.
pub fn run(a: &RenderArgs) -> Result<(), String> {
    let threads = a.threads.map_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()), |t| t as usize);
    let (width, height) = a.image.size();
    let settings = |light: &_| RenderSettings {
        width,
        height,
        tile: a.m.tile as u32,
        order: a.order,
        shadows: a.shade.shadows(light),
        max_depth: a.shade.depth as u32,
        view: a.show,
        heat_max: a.heat_max,
    };
    let frames = a.frames as usize;
    let Still { scene, tree, frame, load_s, render_s, frame_s } =
        render_still(&a.scene, &a.kd.params_for(a.m.method)?, a.m.options(), settings, threads, frames)?;
    let img = image::RgbaImage::from_raw(frame.width, frame.height, frame.rgba.as_flattened().to_vec())
        .ok_or("frame buffer size mismatch")?;
    img.save(&a.out).map_err(|e| format!("cannot write {}: {e}", a.out.display()))?;
    println!(
        "{}: {} triangles, loaded in {:.3} s, kd-tree (C_trav {}) in {:.3} s; rendered {}x{} with {} in {:.3} s ({} threads, {:.2} Mrays/s, {:.1} nodes/ray)",
        a.scene.scene,
        scene.triangle_count(),
        load_s,
        tree.params().c_trav,
        tree.build_time().as_secs_f64(),
        frame.width,
        frame.height,
        a.m.method,
        render_s,
        threads,
        frame.stats.rays as f64 / render_s / 1e6,
        frame.stats.nodes_per_ray(),
    );
    let stages: Vec<String> = raylab_core::render::StageTimes::NAMES
        .iter()
        .zip(frame.stages.as_array())
        .filter(|&(_, t)| t > 0.0)
        .map(|(name, t)| format!("{name} {:.1} ms", t * 1e3))
        .collect();
    if frames > 1 {
        let (min, max) = frame_s.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &t| (lo.min(t), hi.max(t)));
        println!(
            "{frames} frames: median {:.2} ms ({:.1} FPS), min {:.2} ms, max {:.2} ms",
            render_s * 1e3,
            1.0 / render_s,
            min * 1e3,
            max * 1e3
        );
    }
    let which = if frames > 1 { "median frame, summed over threads" } else { "summed over threads" };
    println!("stages ({which}): {}", stages.join(", "));
    let shown = std::fs::canonicalize(&a.out).unwrap_or_else(|_| a.out.clone());
    println!("wrote {}", shown.display());
    Ok(())
}
