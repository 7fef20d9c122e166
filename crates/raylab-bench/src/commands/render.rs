//! `raylab-bench render`: one frame with the benchmark shading, written as PNG.

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;
use raylab_core::method::Method;
use raylab_core::reference::BruteForce;
use raylab_core::render::{RayOrder, RenderSettings, render};
use raylab_core::trace::Tracer;

use crate::args::{KdArgs, MethodArgs, SceneArgs, in_range};
use crate::prepare::{build_tree, load_scene};

/// Renders one frame to a PNG file.
#[derive(Args, Debug)]
pub struct RenderArgs {
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    kd: KdArgs,
    /// Image width in pixels.
    #[arg(long, default_value_t = 512, value_parser = in_range(1, 16384))]
    width: u64,
    /// Image height in pixels.
    #[arg(long, default_value_t = 512, value_parser = in_range(1, 16384))]
    height: u64,
    /// Output PNG file.
    #[arg(long, default_value = "raylab.png")]
    out: PathBuf,
    #[command(flatten)]
    m: MethodArgs,
    /// Pixel order inside a tile: scanline, morton or hilbert.
    #[arg(long, default_value = "scanline")]
    order: RayOrder,
    /// Skip the hard-shadow rays.
    #[arg(long)]
    no_shadows: bool,
    /// Worker threads (default: all CPUs).
    #[arg(long, value_parser = in_range(1, 1024))]
    threads: Option<u64>,
}

impl RenderArgs {
    /// The default action of a bare `cargo run --release`: the default scene to `raylab.png`.
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
    let (scene, load_s) = load_scene(&a.scene.source())?;
    let (camera, light) = a.scene.camera_and_light(&scene)?;
    let tree = build_tree(&scene, &a.kd.params()?, threads)?;
    let settings = RenderSettings {
        width: a.width as u32,
        height: a.height as u32,
        tile: a.m.tile as u32,
        order: a.order,
        shadows: !a.no_shadows,
    };
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().map_err(|e| e.to_string())?;
    let t0 = Instant::now();
    let reference = (a.m.method == Method::Reference).then(|| BruteForce::new(&scene));
    let tracer = Tracer::new(&tree, reference.as_ref(), a.m.options());
    let frame = pool.install(|| render(&scene, &tracer, &camera, light, &settings));
    let render_s = t0.elapsed().as_secs_f64();
    let rgba: Vec<u8> = frame.rgba.iter().flatten().copied().collect();
    let img = image::RgbaImage::from_raw(frame.width, frame.height, rgba).ok_or("frame buffer size mismatch")?;
    img.save(&a.out).map_err(|e| format!("cannot write {}: {e}", a.out.display()))?;
    println!(
        "{}: {} triangles, loaded in {:.3} s, kd-tree in {:.3} s; rendered {}x{} with {} in {:.3} s ({} threads, {:.2} Mrays/s, {:.1} nodes/ray)",
        a.scene.scene,
        scene.triangle_count(),
        load_s,
        tree.build_time().as_secs_f64(),
        frame.width,
        frame.height,
        a.m.method,
        render_s,
        threads,
        frame.stats.rays as f64 / render_s / 1e6,
        frame.stats.nodes_per_ray(),
    );
    let shown = std::fs::canonicalize(&a.out).unwrap_or_else(|_| a.out.clone());
    println!("wrote {}", shown.display());
    Ok(())
}
