//! `raylab-bench distribution`: the MBVH RS paper's workload (a distribution ray tracer, 16 paths per pixel,
//! every surface glossy) traced with several methods; Mrays/s per bounce (paper Figures 2-3), the MBVH
//! counters per ray (Figures 4-6) and, with `--groups`, MBVH RS at several ray-group sizes (Figures 7-8).

use std::fmt::Write as _;
use std::path::PathBuf;

use clap::Args;
use raylab_core::distribution::{Accumulator, BounceStats, DistributionSettings, render_pass};
use raylab_core::method::{Method, Purpose, Structure};
use raylab_core::stats::TraversalStats;
use raylab_core::structures::StructureParams;
use raylab_core::trace::{TraceOptions, Tracer};
use serde_json::json;

use crate::args::{KdArgs, SceneArgs, in_range, parse_non_negative};
use crate::env::Environment;
use crate::output::{markdown_header, print_markdown, write_json};
use crate::prepare::{build_structures, load_scene};

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
    /// Also write the run as one JSON object to this file: per method (and MBVH RS group), each bounce's
    /// rays, thread-summed seconds and counters for closest-hit and shadow rays, and the speeds.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Write only the speed table (Figure 2), titled with the scene, for comparing scenes.
    #[arg(long)]
    speeds_only: bool,
}

/// Runs the command.
pub fn run(a: &DistributionArgs) -> Result<(), String> {
    let env = Environment::detect();
    let source = a.scene.source();
    let scene_name = a.scene.scene.clone();
    let (scene, _) = load_scene(&source)?;
    let (mut camera, light) = a.scene.camera_and_light(&scene)?;
    camera.aperture = a.aperture;
    let light = light.soft();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(a.threads as usize).build().map_err(|e| e.to_string())?;
    // The paper's workload compares every method on the thesis's kd-tree cost model (both slots take it).
    let thesis = a.kd.params()?;
    let params = StructureParams { packet_kd: thesis, ..a.kd.structure_params()? };
    let structures = build_structures(&scene, &a.methods, Purpose::Rays, &params, a.threads as usize)?;
    let settings = |tile: u64| DistributionSettings {
        width: a.width as u32,
        height: a.height as u32,
        tile: tile as u32,
        spp: a.spp as u32,
        bounces: a.bounces as u32,
        glossy_exponent: a.glossy_exponent,
        all_glossy: !a.materials,
    };
    let run_one = |method: Method, tile: u64| -> Result<(Vec<BounceStats>, Accumulator, f64), String> {
        let s = settings(tile);
        let options = TraceOptions { method, ..TraceOptions::default() };
        let tracer = Tracer::for_rays(&structures, options).map_err(|e| e.to_string())?;
        let mut acc = Accumulator::new(s.width, s.height);
        let t0 = std::time::Instant::now();
        let stats = pool.install(|| render_pass(&scene, &tracer, &camera, light, &s, 0, &mut acc));
        Ok((stats, acc, t0.elapsed().as_secs_f64()))
    };
    let cmd: Vec<String> = std::env::args().collect();
    let mut md = markdown_header(&env, &cmd);
    let _ = writeln!(
        md,
        "\n{}: {}x{}, {} paths per pixel, {} bounces, {}, Phong exponent {}, {} thread(s); speeds are per \
         thread (rays over thread-summed seconds).\n",
        scene_name,
        a.width,
        a.height,
        a.spp,
        a.bounces,
        if a.materials { "glossy where the material reflects" } else { "every surface glossy" },
        a.glossy_exponent,
        a.threads
    );
    let group = |tile: u64| tile * tile * a.spp;
    let mut first_image = None;
    let mut rows: Vec<(Method, u64, bool)> = a.methods.iter().map(|&m| (m, a.tile, false)).collect();
    rows.extend(a.groups.iter().map(|&t| (Method::MbvhRs, t, true)));
    let mut runs: Vec<Run> = Vec::with_capacity(rows.len());
    for (method, tile, sweep) in rows {
        eprintln!("tracing with {method}, tile {tile}");
        let (bounces, acc, _) = run_one(method, tile)?;
        let group = (method == Method::MbvhRs).then(|| group(tile));
        runs.push(Run { method, group, sweep, bounces });
        if first_image.is_none() {
            first_image = Some(acc);
        }
    }
    write_tables(&mut md, &runs, a.bounces as usize, a.speeds_only.then_some(scene_name.as_str()));
    print_markdown(&md, a.markdown.as_deref())?;
    if let Some(p) = &a.json {
        let v = json!({
            "scene": scene_name,
            "camera": camera,
            "light": light,
            "width": a.width,
            "height": a.height,
            "paths_per_pixel": a.spp,
            "bounces": a.bounces,
            "glossy_exponent": a.glossy_exponent,
            "all_glossy": !a.materials,
            "threads": a.threads,
            "runs": runs.iter().map(|r| json!({
                "method": r.method,
                "group": r.group,
                "group_sweep": r.sweep,
                "bounces": r.bounces.iter().map(|b| json!({
                    "mrays_per_second": mrays(b.rays, b.seconds),
                    "shadow_mrays_per_second": mrays(b.shadow_rays, b.shadow_seconds),
                    "work": b,
                })).collect::<Vec<_>>(),
            })).collect::<Vec<_>>(),
        });
        write_json(p, &env, &cmd, v)?;
    }
    if let (Some(out), Some(acc)) = (&a.out, first_image) {
        image::RgbaImage::from_raw(acc.width, acc.height, acc.rgba().as_flattened().to_vec())
            .ok_or("frame buffer size mismatch")?
            .save(out)
            .map_err(|e| format!("--out: cannot write {}: {e}", out.display()))?;
    }
    Ok(())
}

/// Millions of rays per thread-second (0 where nothing was timed).
fn mrays(rays: u64, seconds: f64) -> f64 {
    rays as f64 / seconds.max(1e-12) / 1e6
}

/// One method's pass: its MBVH RS group size (`None` for other methods) and the work per bounce.
struct Run {
    method: Method,
    group: Option<u64>,
    /// A row of the `--groups` sweep (shown only in the speed table and Figures 7-8).
    sweep: bool,
    bounces: Vec<BounceStats>,
}

impl Run {
    fn label(&self) -> String {
        match self.group {
            Some(g) => format!("{} | {g}", self.method),
            None => format!("{} | -", self.method),
        }
    }
}

/// A counter table: its title, the counter, and whether only MBVH methods have it.
type Counter = (&'static str, fn(&TraversalStats) -> u64, bool);

/// The paper's Figures 2-8 as tables: speeds per bounce, then the counters per bounce for closest-hit
/// (reflection) and shadow rays apart, then the leaf SIMD use against the group size.
fn write_tables(md: &mut String, runs: &[Run], bounces: usize, speeds_only: Option<&str>) {
    let bounce_header = |md: &mut String, first: &str| {
        let _ = write!(md, "| {first} |");
        for b in 0..=bounces {
            let _ = write!(md, " bounce {b} |");
        }
    };

    let title = match speeds_only {
        Some(scene) => format!("**Figure 2**, {scene}"),
        None => "**Figures 2-3**".to_string(),
    };
    let _ = writeln!(md, "{title}: Mrays/s per bounce (bounce 0: camera rays) and of the shadow rays.\n");
    bounce_header(md, "method | group");
    let _ = writeln!(md, " shadow | all rays |");
    let _ = writeln!(md, "|---|---:|{}", "---:|".repeat(bounces + 3));
    for r in runs {
        let _ = write!(md, "| {} |", r.label());
        for b in &r.bounces {
            let _ = write!(md, " {:.2} |", mrays(b.rays, b.seconds));
        }
        let sum = |f: fn(&BounceStats) -> f64| r.bounces.iter().map(f).sum::<f64>();
        let (shadow_rays, shadow_s) = (sum(|b| b.shadow_rays as f64), sum(|b| b.shadow_seconds));
        let (rays, secs) = (sum(|b| b.rays as f64), sum(|b| b.seconds));
        let _ = writeln!(
            md,
            " {:.2} | {:.2} |",
            mrays(shadow_rays as u64, shadow_s),
            mrays((rays + shadow_rays) as u64, secs + shadow_s)
        );
    }

    if speeds_only.is_some() {
        return;
    }
    let counters: [Counter; 3] = [
        (
            "**Figure 4**: SIMD box tests per ray (MBVH methods; kd-tree methods test split planes, not boxes).",
            |s| s.box_tests,
            true,
        ),
        (
            "**Figure 5**: node fetches per ray (MBVH RS fetches a node once per group; kd-tree methods count nodes visited, once per packet for packets).",
            |s| s.nodes,
            false,
        ),
        (
            "**Figure 6**: primitive tests per ray (triangles for single rays; SIMD tests for packets, packet against triangle, and for MBVH RS leaves, ray against a four-triangle block).",
            |s| s.isect_tests,
            false,
        ),
    ];
    for (title, counter, mbvh_only) in counters {
        let _ = writeln!(md, "\n{title}\n");
        bounce_header(md, "method | group | rays");
        let _ = writeln!(md);
        let _ = writeln!(md, "|---|---:|---|{}", "---:|".repeat(bounces + 1));
        for r in runs.iter().filter(|r| !r.sweep && (!mbvh_only || r.method.entry().structure == Structure::Mbvh)) {
            for (kind, pick) in [("reflection", 0), ("shadow", 1)] {
                let _ = write!(md, "| {} | {kind} |", r.label());
                for b in &r.bounces {
                    let s = if pick == 0 { &b.stats } else { &b.shadow_stats };
                    let _ = write!(md, " {:.2} |", counter(s) as f64 / s.rays.max(1) as f64);
                }
                let _ = writeln!(md);
            }
        }
    }

    let sweep: Vec<&Run> = runs.iter().filter(|r| r.method == Method::MbvhRs).collect();
    if !sweep.is_empty() {
        let _ = writeln!(
            md,
            "\n**Figures 7-8**: SIMD use of MBVH RS leaf packets (active rays over packet lanes, closest-hit and shadow rays of all bounces) against the ray-group size, at 4 lanes (the paper's packets, `--stream-leaves packets`) and at 8 and 16 lanes; the default leaf test takes rays against four-triangle blocks instead, whose lanes the leaf's triangles fill.\n"
        );
        let _ = writeln!(md, "| group | 4 lanes | 8 lanes | 16 lanes | node fetches/ray |");
        let _ = writeln!(md, "|---:|---:|---:|---:|---:|");
        let mut sweep = sweep;
        sweep.sort_by_key(|r| r.group);
        sweep.dedup_by_key(|r| r.group);
        for r in sweep {
            let mut total = TraversalStats::default();
            for b in &r.bounces {
                total += b.stats;
                total += b.shadow_stats;
            }
            let u = total.leaf_utilisation();
            let _ = writeln!(
                md,
                "| {} | {:.0}% | {:.0}% | {:.0}% | {:.2} |",
                r.group.unwrap_or(0),
                u[0],
                u[1],
                u[2],
                total.nodes as f64 / total.rays.max(1) as f64
            );
        }
    }
}
