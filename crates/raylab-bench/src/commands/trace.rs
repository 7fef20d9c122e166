//! `raylab-bench trace`: throughput of one method on the harness's rays.

use clap::Args;
use raylab_core::dacrt::Dacrt;
use raylab_core::mbvh::Mbvh;
use raylab_core::method::Structure;
use raylab_core::structures::Structures;
use raylab_core::trace::Tracer;
use raylab_core::workload::{RayKind, WorkloadBuilder};
use serde_json::json;

use crate::args::{ImageArgs, KdArgs, MethodArgs, SceneArgs, in_range, parse_group};
use crate::env::Environment;
use crate::prepare::{load_scene, with_spinner};
use crate::timing::{measure, tile_for_group, validate};

/// Traces the Embree harness's rays and reports Mrays/s, checksums and counters.
#[derive(Args, Debug)]
pub struct TraceArgs {
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    kd: KdArgs,
    #[command(flatten)]
    image: ImageArgs,
    /// Ray kind: primary, shadow or diffuse.
    #[arg(long, default_value = "primary")]
    kind: RayKind,
    #[command(flatten)]
    m: MethodArgs,
    /// Tracing threads.
    #[arg(long, default_value_t = 1, value_parser = in_range(1, 1024))]
    threads: u64,
    /// Timed runs.
    #[arg(long, default_value_t = 7, value_parser = in_range(1, 10_000))]
    reps: u64,
    /// Untimed runs before timing.
    #[arg(long, default_value_t = 1, value_parser = in_range(0, 10_000))]
    warmup: u64,
    /// Diffuse-ray seed (the harness's --seed).
    #[arg(long, default_value_t = 1)]
    seed: u32,
    /// Rays checked against the brute-force reference before any speed is reported (0 skips the check).
    #[arg(long, default_value_t = 256, value_parser = in_range(0, 1_000_000))]
    validate: u64,
    /// MBVH RS ray-group size, a power of two from 16 to 4096 (the paper's 2^4..2^12; default: one group per
    /// tile). Groups are cut from each tile along the Z-order curve; the tile grows to hold at least one group.
    #[arg(long, value_parser = parse_group)]
    group: Option<u64>,
    /// Print one JSON object on stdout and nothing else.
    #[arg(long)]
    json: bool,
}

/// Runs the command.
pub fn run(a: &TraceArgs) -> Result<(), String> {
    let env = Environment::detect();
    let (scene, _) = load_scene(&a.scene.source())?;
    let (camera, light) = a.scene.camera_and_light(&scene)?;
    // The method's structure, the thesis's kd-tree that traces the harness's primary pass (the hit points the
    // shadow and diffuse rays leave from), and the brute force the results are validated against.
    let params = a.kd.structure_params()?;
    let needs = [a.m.method.entry().structure, Structure::ThesisKd, Structure::Reference];
    let pool = rayon::ThreadPoolBuilder::new().num_threads(a.threads as usize).build().map_err(|e| e.to_string())?;
    let structures =
        with_spinner("building structures", || pool.install(|| Structures::build_these(&scene, &needs, &params)))
            .map_err(|e| e.to_string())?;
    let (Some(tree), Some(reference)) = (structures.kd(Structure::ThesisKd), structures.reference()) else {
        return Err("the kd-tree and the brute-force reference were not built".into());
    };
    let (w, h) = a.image.size();
    let builder = with_spinner("generating rays", || {
        WorkloadBuilder::new(&scene, &camera, light.position, w, h, tree).seed(a.seed)
    });
    let workload = builder.build(a.kind);
    let mut options = a.m.options();
    let mut tile = a.m.tile;
    if let Some(g) = a.group {
        if options.method != raylab_core::method::Method::MbvhRs {
            return Err(format!("--group sets the ray group of --method mbvh-rs, not of {}", options.method));
        }
        options.stream_group = Some(g as usize);
        tile = tile_for_group(tile as u32, g as u32) as u64;
    }
    let tracer = Tracer::for_rays(&structures, options).map_err(|e| e.to_string())?;
    let mbvh = structures.mbvh();
    let setup = || drop(Dacrt::new(&scene));
    let setup = structures.dacrt().map(|_| &setup as &(dyn Fn() + Sync));
    let runs = (a.threads as usize, a.warmup as usize, a.reps as usize);
    let (report, results) = measure(&tracer, &workload, tile as u32, runs, setup)?;
    // The kd-tree the report describes: the method's own, else the one that traced the primary pass.
    let kd = structures.kd_for(options.method).unwrap_or(tree);
    let checked = with_spinner("validating against brute force", || {
        validate(reference, &workload, &results, a.validate as usize)
    })
    .map_err(|m| format!("validation failed ({} vs brute force): {m}", a.m.method))?;
    if a.json {
        let v = json!({
            "environment": env,
            "scene": a.scene.scene,
            "triangles": scene.triangle_count(),
            "camera": camera,
            "light": light.position.to_array(),
            "width": w,
            "height": h,
            "method": a.m.method,
            "tile": tile,
            "group": a.group,
            "cull": options.cull,
            "backend": options.backend.name(),
            "kd_build_seconds": kd.build_time().as_secs_f64(),
            "kd_params": kd.params(),
            "kd_nodes": kd.nodes().len(),
            "mbvh": mbvh.map(Mbvh::stats),
            "structures": structures.builds(),
            "validated_rays": checked,
            "result": report,
        });
        println!("{v}");
        return Ok(());
    }
    println!("environment      {}", env.line());
    println!("scene            {} ({} triangles), {}x{}", a.scene.scene, scene.triangle_count(), w, h);
    println!(
        "kd-tree          C_trav {}, C_isect {}: {} nodes, built in {:.3} s on {} thread(s)",
        kd.params().c_trav,
        kd.params().c_isect,
        kd.nodes().len(),
        kd.build_time().as_secs_f64(),
        a.threads
    );
    if let Some(m) = mbvh {
        let st = m.stats();
        println!(
            "MBVH             built in {:.3} s on {} thread(s): {} nodes ({:.0}% of lanes used), {} leaves, depth {}, \
             {} triangle references (spatial splits' copies included)",
            st.build_seconds, a.threads, st.nodes, st.lane_fill_percent, st.leaves, st.depth, st.references
        );
    }
    println!("validated        {checked} rays against brute force");
    let what = if a.kind.is_occlusion() { "occluded" } else { "hits" };
    println!(
        "{} {} tile {}{} cull {} backend {} threads {}: rays {}, {} {}, sum_t {:.6}",
        a.kind,
        a.m.method,
        tile,
        a.group.map(|g| format!(" group {g}")).unwrap_or_default(),
        options.cull,
        options.backend.name(),
        report.threads,
        report.rays,
        what,
        report.hits,
        report.sum_t
    );
    println!(
        "Mrays/s          median {:.2} (min {:.2}, max {:.2}) over {} runs",
        report.mrays_median, report.mrays_min, report.mrays_max, a.reps
    );
    println!(
        "per ray          {:.2} nodes, {:.2} leaves, {:.2} triangle tests, {:.2} 4-box tests",
        report.nodes_per_ray, report.leaves_per_ray, report.isects_per_ray, report.box_tests_per_ray
    );
    println!(
        "per packet       N {:.2} nodes, I {:.2} tests, {:.1}% of packet/leaf visits culled",
        report.nodes_per_packet, report.isects_per_packet, report.culled_percent
    );
    Ok(())
}
