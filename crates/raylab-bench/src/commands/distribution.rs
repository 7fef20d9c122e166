//! `raylab-bench distribution`: the MBVH RS paper's workload (a distribution ray tracer, 16 paths per pixel,
//! every surface glossy) traced with several methods; Mrays/s per bounce (paper Figures 2-3), the MBVH
//! counters per ray (Figures 4-6) and, with `--groups`, MBVH RS at several ray-group sizes (Figures 7-8).

use std::fmt::Write as _;
use std::path::PathBuf;

use clap::Args;
use raylab_core::distribution::{Accumulator, BounceStats, DistributionSettings, render_pass};
use raylab_core::mbvh::Mbvh;
use raylab_core::method::Method;
use raylab_core::trace::{TraceOptions, Tracer};

use crate::args::{KdArgs, SceneArgs, in_range, parse_non_negative};
use crate::env::Environment;
use crate::prepare::{build_tree, load_scene, with_spinner};

/// Traces the distribution workload with each method and prints per-bounce speeds and counters.
#[derive(Args, Debug)]
pub struct DistributionArgs {
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    kd: KdArgs,
    /// Methods to compare (comma-separated).
    #[arg(long, value_delimiter = ',', default_value = "mono,packet,mbvh,mbvh-rs")]
    methods: Vec<Method>,
    /// Bounces after the primary hit (1 to 7).
    #[arg(long, default_value_t = 3, value_parser = in_range(1, 7))]
    bounces: u64,
    /// Paths per pixel.
    #[arg(long, default_value_t = 16, value_parser = in_range(1, 1024))]
    spp: u64,
    /// Image width.
    #[arg(long, default_value_t = 512, value_parser = in_range(1, 8192))]
    width: u64,
    /// Image height.
    #[arg(long, default_value_t = 512, value_parser = in_range(1, 8192))]
    height: u64,
    /// Tile edge: with 16 paths per pixel an 8x8 tile is a group of 1024 rays per bounce.
    #[arg(long, default_value_t = 4, value_parser = in_range(1, 256))]
    tile: u64,
    /// MBVH RS group sweep: tile edges to try (each tile holds tile x tile x spp rays per bounce).
    #[arg(long, value_delimiter = ',')]
    groups: Vec<u64>,
    /// Phong exponent of the glossy lobe.
    #[arg(long, default_value_t = 64.0, value_parser = parse_non_negative)]
    glossy_exponent: f32,
    /// Lens radius of the thin-lens camera (0: pinhole).
    #[arg(long, default_value_t = 0.0, value_parser = parse_non_negative)]
    aperture: f32,
    /// Glossy reflections only on reflective materials; the rest scatter diffusely.
    #[arg(long)]
    materials: bool,
    /// Worker threads.
    #[arg(long, default_value_t = 1, value_parser = in_range(1, 1024))]
    threads: u64,
    /// Write the first method's image here.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Also write the markdown tables to this file.
    #[arg(long)]
    markdown: Option<PathBuf>,
}

/// Runs the command.
pub fn run(a: &DistributionArgs) -> Result<(), String> {
    let env = Environment::detect();
    let (scene, _) = load_scene(&a.scene.source())?;
    let (mut camera, light) = a.scene.camera_and_light(&scene)?;
    camera.aperture = a.aperture;
    let light = light.soft();
    let tree = build_tree(&scene, &a.kd.params()?, a.threads as usize)?;
    let pool = rayon::ThreadPoolBuilder::new().num_threads(a.threads as usize).build().map_err(|e| e.to_string())?;
    let mbvh = with_spinner("building MBVH", || pool.install(|| Mbvh::build(&scene)));
    let settings = |tile: u64| DistributionSettings {
        width: a.width as u32,
        height: a.height as u32,
        tile: tile as u32,
        spp: a.spp as u32,
        bounces: a.bounces as u32,
        glossy_exponent: a.glossy_exponent,
        all_glossy: !a.materials,
    };
    let run_one = |method: Method, tile: u64| -> (Vec<BounceStats>, Accumulator, f64) {
        let s = settings(tile);
        let tracer = Tracer::new(&tree, None, TraceOptions { method, ..TraceOptions::default() }).with_mbvh(&mbvh);
        let mut acc = Accumulator::new(s.width, s.height);
        let t0 = std::time::Instant::now();
        let stats = pool.install(|| render_pass(&scene, &tracer, &camera, light, &s, 0, &mut acc));
        (stats, acc, t0.elapsed().as_secs_f64())
    };
    let mut md = String::new();
    let cmd: Vec<String> = std::env::args().collect();
    let _ = writeln!(md, "Machine and build: {}.", env.line());
    let _ = writeln!(md, "Command: `{}`", cmd.join(" "));
    let _ = writeln!(
        md,
        "\n{}x{}, {} paths per pixel, {} bounces, {}, Phong exponent {}, {} thread(s); Mrays/s of closest-hit rays \
         (shadow rays in their own column), per thread.\n",
        a.width,
        a.height,
        a.spp,
        a.bounces,
        if a.materials { "glossy where the material reflects" } else { "every surface glossy" },
        a.glossy_exponent,
        a.threads
    );
    let _ = write!(md, "| method | group |");
    for b in 0..=a.bounces {
        let _ = write!(md, " bounce {b} |");
    }
    let _ = writeln!(md, " shadow | box tests/ray | node fetches/ray | triangle tests/ray | leaf SIMD use 4/8/16 |");
    let _ = writeln!(md, "|---|---:|{}", "---:|".repeat(a.bounces as usize + 6));
    let group = |tile: u64| tile * tile * a.spp;
    let mut first_image = None;
    let mut rows: Vec<(Method, u64)> = a.methods.iter().map(|&m| (m, a.tile)).collect();
    rows.extend(a.groups.iter().map(|&t| (Method::MbvhRs, t)));
    for (method, tile) in rows {
        eprintln!("tracing with {method}, tile {tile}");
        let (stats, acc, _) = run_one(method, tile);
        let _ = write!(
            md,
            "| {method} | {} |",
            if method == Method::MbvhRs { group(tile).to_string() } else { "-".into() }
        );
        let mut total = raylab_core::stats::TraversalStats::default();
        let (mut shadow_rays, mut shadow_s) = (0u64, 0f64);
        for b in &stats {
            let _ = write!(md, " {:.2} |", b.rays as f64 / b.seconds.max(1e-12) / 1e6);
            total += b.stats;
            shadow_rays += b.shadow_rays;
            shadow_s += b.shadow_seconds;
        }
        let per_ray = |x: u64| x as f64 / total.rays.max(1) as f64;
        let u = total.leaf_utilisation();
        let _ = writeln!(
            md,
            " {:.2} | {:.2} | {:.2} | {:.2} | {} |",
            shadow_rays as f64 / shadow_s.max(1e-12) / 1e6,
            per_ray(total.box_tests),
            per_ray(total.nodes),
            per_ray(total.isect_tests),
            if total.leaf_rays > 0 { format!("{:.0}% / {:.0}% / {:.0}%", u[0], u[1], u[2]) } else { "-".into() }
        );
        if first_image.is_none() {
            first_image = Some(acc);
        }
    }
    print!("{md}");
    if let Some(p) = &a.markdown {
        std::fs::write(p, &md).map_err(|e| format!("--markdown: cannot write {}: {e}", p.display()))?;
    }
    if let (Some(out), Some(acc)) = (&a.out, first_image) {
        image::RgbaImage::from_raw(acc.width, acc.height, acc.rgba().as_flattened().to_vec())
            .ok_or("frame buffer size mismatch")?
            .save(out)
            .map_err(|e| format!("--out: cannot write {}: {e}", out.display()))?;
    }
    Ok(())
}
