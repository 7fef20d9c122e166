//! `raylab-bench render`: one frame, shaded with the scene's materials under a chosen shadow technique,
//! written as PNG; with `--frames` the same frame rendered again and again to time it as a viewer would, and
//! with `--json` the times, stages and counters as one JSON object.

use std::path::PathBuf;

use clap::Args;
use raylab_cli::env::Environment;
use raylab_cli::still::{Still, render_still};
use raylab_core::ray_order::RayOrder;
use raylab_core::render::{FrameView, RenderSettings};
use raylab_core::scene::PointLight;
use serde_json::json;

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
    /// Print one JSON object on stdout and nothing else: the machine, the view and settings, every frame's
    /// time, the median frame's stages and the frame's counters (the PNG is still written).
    #[arg(long)]
    json: bool,
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

/// The frame settings of the flags, for the scene's `light` (the default edge-width radius is its radius).
fn frame_settings(a: &RenderArgs, light: &PointLight) -> RenderSettings {
    let (width, height) = a.image.size();
    RenderSettings {
        width,
        height,
        tile: a.m.tile as u32,
        order: a.order,
        shadows: a.shade.shadows(light),
        max_depth: a.shade.depth as u32,
        view: a.show,
        heat_max: a.heat_max,
    }
}

/// Runs the command.
pub fn run(a: &RenderArgs) -> Result<(), String> {
    let threads = a.threads.map_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()), |t| t as usize);
    let settings = |light: &_| frame_settings(a, light);
    let frames = a.frames as usize;
    let env = a.json.then(Environment::detect);
    let options = a.m.options();
    let still = render_still(&a.scene, &a.kd.structure_params()?, options, settings, threads, frames)?;
    still.image()?.save(&a.out).map_err(|e| format!("cannot write {}: {e}", a.out.display()))?;
    let shown = std::fs::canonicalize(&a.out).unwrap_or_else(|_| a.out.clone());
    let Still { scene, structures, camera, light, frame, load_s, render_s, frame_s } = &still;
    let kd_params = structures.params().kd_for(a.m.method);
    let kd_build_s = structures.kd_for(a.m.method).map_or(0.0, |t| t.build_time().as_secs_f64());
    let stats = &frame.stats;
    let (min, max) = frame_s.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &t| (lo.min(t), hi.max(t)));
    if let Some(env) = env {
        let v = json!({
            "environment": env,
            "scene": a.scene.scene,
            "triangles": scene.triangle_count(),
            "camera": camera,
            "light": light,
            "settings": frame_settings(a, light),
            "options": options,
            "threads": threads,
            "load_seconds": load_s,
            "kd_build_seconds": kd_build_s,
            "kd_params": kd_params,
            "structures": structures.builds(),
            "frames": frames,
            "frame_seconds": { "median": render_s, "min": min, "max": max, "each": frame_s },
            "fps": 1.0 / render_s,
            "stages_seconds": frame.stages,
            "counters": stats,
            "mrays_per_second": stats.rays as f64 / render_s / 1e6,
            "nodes_per_ray": stats.nodes_per_ray(),
            "nodes_per_packet": stats.nodes_per_packet(),
            "isects_per_packet": stats.isects_per_packet(),
            "culled_percent": stats.culled_percent(),
            "cache_hit_rate": stats.cache_hit_rate(),
            "out": shown,
        });
        println!("{v}");
        return Ok(());
    }
    println!(
        "{}: {} triangles, loaded in {:.3} s, structures (kd-tree C_trav {}) in {:.3} s; rendered {}x{} with {} in {:.3} s ({} threads, {:.2} Mrays/s, {:.1} nodes/ray)",
        a.scene.scene,
        scene.triangle_count(),
        load_s,
        kd_params.c_trav,
        structures.build_seconds(),
        frame.width,
        frame.height,
        a.m.method,
        render_s,
        threads,
        stats.rays as f64 / render_s / 1e6,
        stats.nodes_per_ray(),
    );
    let stages: Vec<String> = raylab_core::render::StageTimes::NAMES
        .iter()
        .zip(frame.stages.as_array())
        .filter(|&(_, t)| t > 0.0)
        .map(|(name, t)| format!("{name} {:.1} ms", t * 1e3))
        .collect();
    if frames > 1 {
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
    println!(
        "counters: {} rays, N {:.2} nodes and I {:.2} triangle tests per packet, {:.1}% of packet/leaf visits culled",
        stats.rays,
        stats.nodes_per_packet(),
        stats.isects_per_packet(),
        stats.culled_percent()
    );
    println!("wrote {}", shown.display());
    Ok(())
}
