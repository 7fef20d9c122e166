//! `raylab-bench animate`: tracing a scene whose objects move every frame (seed 003's dynamic scenes). Each
//! frame moves the animation's objects, brings each method's structure up to date and traces the harness's
//! rays: the kd-tree is rebuilt, the MBVH refitted, and DACRT only copies the triangles. Reports the median
//! update and trace time per frame for each, and checks that all three agree with brute force.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use clap::Args;
use raylab_core::method::{Method, Structure};
use raylab_core::structures::Structures;
use raylab_core::trace::{TraceOptions, Tracer};
use raylab_core::workload::{RayKind, WorkloadBuilder};
use raylab_scene::animation::Animation;
use serde::Serialize;
use serde_json::json;

use crate::args::{KdArgs, SceneArgs, in_range, parse_non_negative};
use crate::env::Environment;
use crate::output::{markdown_header, print_markdown, write_json};
use crate::prepare::load_scene;
use crate::timing::{DACRT_SET_TILE, HARNESS_TILE, summarize, trace_once, validate};

/// Moves objects every frame and times structure updates and tracing per method.
#[derive(Args, Debug)]
pub struct AnimateArgs {
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    kd: KdArgs,
    /// Frames to time.
    #[arg(long, default_value_t = 10, value_parser = in_range(1, 10_000))]
    frames: u64,
    /// Animation time between frames, in seconds.
    #[arg(long, default_value_t = 1.0 / 30.0, value_parser = parse_non_negative)]
    step: f32,
    /// Image width.
    #[arg(long, default_value_t = 512, value_parser = in_range(1, 8192))]
    width: u64,
    /// Image height.
    #[arg(long, default_value_t = 512, value_parser = in_range(1, 8192))]
    height: u64,
    /// Ray kind: primary, shadow or diffuse.
    #[arg(long, default_value = "primary")]
    kind: RayKind,
    /// Tracing (and kd-tree and MBVH building) threads.
    #[arg(long, default_value_t = 1, value_parser = in_range(1, 1024))]
    threads: u64,
    /// Rays per frame checked against brute force.
    #[arg(long, default_value_t = 64, value_parser = in_range(0, 100_000))]
    validate: u64,
    /// Also write the markdown table to this file.
    #[arg(long)]
    markdown: Option<PathBuf>,
    /// Also write the run as one JSON object to this file: every frame's update and trace times per method
    /// beside the medians of the table.
    #[arg(long)]
    json: Option<PathBuf>,
}

/// One method's times per frame, in milliseconds.
#[derive(Clone, Debug, Default, Serialize)]
struct Row {
    update_ms: Vec<f64>,
    trace_ms: Vec<f64>,
    total_ms: Vec<f64>,
}

fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    s.get(s.len() / 2).copied().unwrap_or(0.0)
}

/// Runs the command.
pub fn run(a: &AnimateArgs) -> Result<(), String> {
    let env = Environment::detect();
    let (base, _) = load_scene(&a.scene.source())?;
    let (camera, light) = a.scene.camera_and_light(&base)?;
    let (mut scene, anim) = Animation::add_movers(&base);
    let params = a.kd.structure_params()?;
    let pool = rayon::ThreadPoolBuilder::new().num_threads(a.threads as usize).build().map_err(|e| e.to_string())?;
    let methods = [
        (Method::Mono, "kd-tree rebuilt"),
        (Method::Mbvh, "MBVH refitted"),
        (Method::Dacrt, "triangles copied, top divided"),
    ];
    let mut rows = vec![Row::default(); methods.len()];
    // The methods' structures and the brute force the results are checked against, updated every frame.
    let needs = [Structure::ThesisKd, Structure::Mbvh, Structure::Dacrt, Structure::Reference];
    let mut structures =
        pool.install(|| Structures::build_these(&scene, &needs, &params)).map_err(|e| e.to_string())?;
    let mut rays = 0;
    for f in 0..a.frames {
        anim.apply(&mut scene, f as f32 * a.step)?;
        let times = pool.install(|| structures.update(&scene)).map_err(|e| e.to_string())?;
        let ms = |which: Structure| times.iter().find(|(s, _)| *s == which).map_or(0.0, |(_, t)| t.as_secs_f64() * 1e3);
        let updates = [ms(Structure::ThesisKd), ms(Structure::Mbvh), ms(Structure::Dacrt)];
        let (Some(tree), Some(reference)) = (structures.kd(Structure::ThesisKd), structures.reference()) else {
            return Err("the kd-tree and the brute-force reference were not built".into());
        };
        let workload =
            WorkloadBuilder::new(&scene, &camera, light.position, a.width as u32, a.height as u32, tree).build(a.kind);
        rays = workload.ray_count();
        let mut checksums = Vec::new();
        for ((method, _), (row, update)) in methods.iter().zip(rows.iter_mut().zip(updates)) {
            let options = TraceOptions { method: *method, ..TraceOptions::default() };
            let tracer = Tracer::for_rays(&structures, options).map_err(|e| e.to_string())?;
            let tile = if method.entry().structure == Structure::Dacrt { DACRT_SET_TILE } else { HARNESS_TILE };
            let t = Instant::now();
            let (results, _) = pool.install(|| trace_once(&tracer, &workload, tile));
            let trace = t.elapsed().as_secs_f64() * 1e3;
            validate(reference, &workload, &results, a.validate as usize)
                .map_err(|m| format!("frame {f}: validation failed ({method}): {m}"))?;
            checksums.push(summarize(&results));
            row.update_ms.push(update);
            row.trace_ms.push(trace);
            row.total_ms.push(update + trace);
        }
        if checksums.windows(2).any(|w| w[0].0 != w[1].0) {
            return Err(format!("frame {f}: the methods disagree on the hit count: {checksums:?}"));
        }
    }
    let cmd: Vec<String> = std::env::args().collect();
    let mut md = markdown_header(&env, &cmd);
    let _ = writeln!(
        md,
        "\n{} ({} triangles, {} of them moving), {} {} rays a frame, {} frames, {} thread(s); medians per frame.\n",
        a.scene.scene,
        scene.triangle_count(),
        anim.moving_triangles(),
        rays,
        a.kind,
        a.frames,
        a.threads
    );
    let _ =
        writeln!(md, "| method | structure update | update ms | trace ms | update + trace ms | Mrays/s incl. update |");
    let _ = writeln!(md, "|---|---|---:|---:|---:|---:|");
    for ((method, what), row) in methods.iter().zip(&rows) {
        let total = median(&row.total_ms);
        let _ = writeln!(
            md,
            "| {method} | {what} | {:.2} | {:.2} | {:.2} | {:.2} |",
            median(&row.update_ms),
            median(&row.trace_ms),
            total,
            rays as f64 / (total * 1e3).max(1e-9)
        );
    }
    print_markdown(&md, a.markdown.as_deref())?;
    if let Some(p) = &a.json {
        let v = json!({
            "scene": a.scene.scene,
            "triangles": scene.triangle_count(),
            "moving_triangles": anim.moving_triangles(),
            "kind": a.kind,
            "rays_per_frame": rays,
            "frames": a.frames,
            "step_seconds": a.step,
            "threads": a.threads,
            "kd_params": params,
            "methods": methods.iter().zip(&rows).map(|((method, what), row)| {
                let total = median(&row.total_ms);
                json!({
                    "method": method,
                    "structure_update": what,
                    "median_update_ms": median(&row.update_ms),
                    "median_trace_ms": median(&row.trace_ms),
                    "median_total_ms": total,
                    "mrays_per_second_with_update": rays as f64 / (total * 1e3).max(1e-9),
                    "frames": row,
                })
            }).collect::<Vec<_>>(),
        });
        write_json(p, &env, &cmd, v)?;
    }
    Ok(())
}
