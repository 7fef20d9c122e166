//! `raylab-bench compare`: the Embree harness and raylab on the same OBJ, view, light and rays in one
//! invocation, printed as one markdown table for `docs/BENCHMARKS.md`. The two take turns: the harness builds
//! next to raylab's builds, and runs each ray kind just before raylab's runs of that kind, so that a host whose
//! speed drifts over the minutes of a run (a shared machine) skews the ratios as little as it can; `--rounds`
//! repeats that sequence and reports the median round, so that a slow spell of the host lands on one round of
//! a configuration rather than on all of its runs.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::Command;

use clap::Args;
use raylab_core::dacrt::Dacrt;
use raylab_core::mbvh::Mbvh;
use raylab_core::method::{Method, Purpose, Structure};
use raylab_core::scene::Scene;
use raylab_core::structures::Structures;
use raylab_core::trace::{TraceOptions, Tracer};
use raylab_core::workload::{RayKind, Workload, WorkloadBuilder};
use serde::Serialize;
use serde_json::json;

use crate::args::{ImageArgs, KdArgs, SceneArgs, in_range, parse_group};
use crate::env::Environment;
use crate::output::{markdown_header, print_markdown, write_json};
use crate::prepare::{build_structures, build_tree, load_scene, with_spinner};
use crate::timing::{DACRT_SET_TILE as DACRT_TILE, HARNESS_TILE, TraceReport, measure, tile_for_group, validate};

/// Compares raylab's single-ray kd-tree with Embree's single-ray API on the harness's rays.
#[derive(Args, Debug)]
pub struct CompareArgs {
    /// Path to the built `embree_bench` binary (see shared/tools/embree-bench).
    #[arg(long)]
    embree: PathBuf,
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    kd: KdArgs,
    #[command(flatten)]
    image: ImageArgs,
    /// Thread counts, comma separated.
    #[arg(long, default_value = "1,2", value_delimiter = ',', value_parser = in_range(1, 1024))]
    threads: Vec<u64>,
    /// Timed runs per configuration.
    #[arg(long, default_value_t = 7, value_parser = in_range(1, 10_000))]
    reps: u64,
    /// Untimed runs before timing.
    #[arg(long, default_value_t = 1, value_parser = in_range(0, 10_000))]
    warmup: u64,
    /// Rounds: the whole sequence of ray kinds (harness, then raylab's configurations) runs this many times,
    /// `--reps` timed runs per configuration each round, and each table cell reports the median of the rounds'
    /// medians (with the slowest and fastest run of all rounds). Spread over the invocation like this, every
    /// configuration meets a shared host's slow spells about as often as the others.
    #[arg(long, default_value_t = 1, value_parser = in_range(1, 100))]
    rounds: u64,
    /// Acceleration-structure builds per thread count (the median is reported).
    #[arg(long, default_value_t = 3, value_parser = in_range(1, 100))]
    builds: u64,
    /// Coherent methods to measure beside Embree's packet and stream APIs (primary and shadow rays).
    #[arg(long, value_delimiter = ',', default_value = "packet,frustum,mft,cone,mft-cone")]
    methods: Vec<Method>,
    /// Methods to measure on the diffuse (incoherent) rays beside Embree's `rtcIntersect1` and
    /// `rtcIntersect1M` (mbvh-rs traces groups of `--rs-groups` rays, dacrt each 256x256 tile as one set).
    #[arg(long, value_delimiter = ',', default_value = "mbvh,mbvh-rs,dacrt")]
    incoherent: Vec<Method>,
    /// MBVH RS ray-group sizes to measure, powers of two from 16 to 4096 (the paper's default is 256).
    #[arg(long, value_delimiter = ',', default_value = "256,4096", value_parser = parse_group)]
    rs_groups: Vec<u64>,
    /// Tile sizes for the frustum methods.
    #[arg(long, value_delimiter = ',', default_value = "4,8,16,32", value_parser = in_range(2, 256))]
    tiles: Vec<u64>,
    /// Also write the markdown to this file.
    #[arg(long)]
    markdown: Option<PathBuf>,
    /// Also write the comparison as one JSON object to this file: the machine, the view, the harness's rows
    /// and builds, and each raylab configuration's full report (counters included) beside the Embree row it is
    /// compared with and the ratio.
    #[arg(long)]
    json: Option<PathBuf>,
}

/// Embree's numbers for one kind and thread count.
#[derive(Clone, Serialize)]
struct EmbreeRow {
    /// The harness's name of the ray kind and API (`primary_1`, `shadow_8_4x2`, `diffuse_1M`, ...).
    kind: String,
    threads: u64,
    /// Mrays/s: the median run (of the median round, with `--rounds`), the slowest and the fastest.
    median: f64,
    min: f64,
    max: f64,
}

/// What the harness printed over its invocations.
#[derive(Default)]
struct EmbreeRun {
    builds: Vec<(u64, f64)>,
    rows: Vec<EmbreeRow>,
    checks: Vec<String>,
}

impl EmbreeRun {
    /// Adds one invocation's builds and rows, and its checks not seen before (each invocation repeats the
    /// primary check). A row for a kind and thread count seen in an earlier round joins that row's rounds.
    fn merge(&mut self, run: EmbreeRun, rounds: &mut Vec<Vec<EmbreeRow>>) {
        self.builds.extend(run.builds);
        for row in run.rows {
            match self.rows.iter().position(|e| e.kind == row.kind && e.threads == row.threads) {
                Some(i) => rounds[i].push(row),
                None => {
                    rounds.push(vec![row.clone()]);
                    self.rows.push(row);
                }
            }
        }
        for check in run.checks {
            if !self.checks.contains(&check) {
                self.checks.push(check);
            }
        }
    }

    /// The row of harness kind `kind` at `threads` threads.
    fn row(&self, kind: &str, threads: usize) -> Option<&EmbreeRow> {
        self.rows.iter().find(|e| e.kind == kind && e.threads == threads as u64)
    }

    /// The fastest packet or stream API (not the single-ray one) for the primary or the shadow rays of `r`.
    fn best_coherent(&self, r: &TraceReport) -> Option<&EmbreeRow> {
        let prefix = if r.kind.is_occlusion() { "shadow_" } else { "primary_" };
        self.rows
            .iter()
            .filter(|e| e.kind.starts_with(prefix) && !e.kind.ends_with("_1") && e.threads == r.threads as u64)
            .max_by(|x, y| x.median.total_cmp(&y.median))
    }

    /// Replaces each row's figures by those of its rounds ([`median_of_rounds`]).
    fn combine(&mut self, rounds: &[Vec<EmbreeRow>]) {
        for (row, all) in self.rows.iter_mut().zip(rounds) {
            let (median, min, max) = median_of_rounds(all.iter().map(|e| (e.median, e.min, e.max)));
            (row.median, row.min, row.max) = (median, min, max);
        }
    }
}

/// Over rounds of `(median, min, max)`: the median of the medians (the lower middle one for an even count), the
/// smallest minimum and the largest maximum.
fn median_of_rounds(rounds: impl Iterator<Item = (f64, f64, f64)>) -> (f64, f64, f64) {
    let (mut medians, mut min, mut max) = (Vec::new(), f64::INFINITY, f64::NEG_INFINITY);
    for (median, lo, hi) in rounds {
        medians.push(median);
        (min, max) = (min.min(lo), max.max(hi));
    }
    medians.sort_by(f64::total_cmp);
    (medians.get(medians.len().saturating_sub(1) / 2).copied().unwrap_or(f64::NAN), min, max)
}

/// The first round's report of a configuration, with its Mrays/s figures taken over all rounds
/// ([`median_of_rounds`]); the counters and checksums are the same in every round.
fn combine_reports(rounds: &[&TraceReport]) -> TraceReport {
    let mut r = rounds[0].clone();
    (r.mrays_median, r.mrays_min, r.mrays_max) =
        median_of_rounds(rounds.iter().map(|x| (x.mrays_median, x.mrays_min, x.mrays_max)));
    r
}

/// Embree's single-ray API for a ray kind, and the harness's name of its row.
fn single_ray_api(kind: RayKind) -> (&'static str, &'static str) {
    match kind {
        RayKind::Primary => ("rtcIntersect1", "primary_1"),
        RayKind::Shadow => ("rtcOccluded1", "shadow_1"),
        RayKind::Diffuse => ("rtcIntersect1", "diffuse_1"),
    }
}

/// raylab's median against an Embree row's, or `None` without the row.
fn ratio(r: &TraceReport, e: Option<&EmbreeRow>) -> Option<f64> {
    e.map(|e| r.mrays_median / e.median)
}

/// A report's checksum column: the occluded count, or the hits and their distances' sum.
fn check_of(r: &TraceReport) -> String {
    if r.kind.is_occlusion() { format!("{} occluded", r.hits) } else { format!("{} hits, {:.1}", r.hits, r.sum_t) }
}

/// Runs the harness for the ray kinds `kinds` (its `--kinds`: `none` only builds) with `builds` builds per
/// thread count.
fn run_embree(
    a: &CompareArgs,
    cam: &raylab_core::scene::Camera,
    light: glam::Vec3,
    kinds: &str,
    builds: u64,
) -> Result<EmbreeRun, String> {
    let v = |p: glam::Vec3| format!("{},{},{}", p.x, p.y, p.z);
    let threads: Vec<String> = a.threads.iter().map(u64::to_string).collect();
    let out = Command::new(&a.embree)
        .arg(&a.scene.scene)
        .args(["--eye", &v(cam.eye), "--target", &v(cam.target), "--up", &v(cam.up)])
        .args(["--fov", &cam.vfov_deg.to_string(), "--light", &v(light)])
        .args(["--width", &a.image.width.to_string(), "--height", &a.image.height.to_string()])
        .args(["--threads", &threads.join(","), "--reps", &a.reps.to_string()])
        .args(["--warmup", &a.warmup.to_string(), "--builds", &builds.to_string()])
        .args(["--kinds", kinds])
        .output()
        .map_err(|e| format!("--embree: cannot run {}: {e}", a.embree.display()))?;
    let text = String::from_utf8_lossy(&out.stdout);
    if !out.status.success() {
        return Err(format!("{} failed: {}{}", a.embree.display(), text, String::from_utf8_lossy(&out.stderr)));
    }
    let mut run = EmbreeRun::default();
    for line in text.lines() {
        if let Some(rest) = line.strip_prefix("build HIGH") {
            // "       1 thread(s): median 0.108 s (min ...)"
            let t: Option<u64> = rest.split_whitespace().next().and_then(|s| s.parse().ok());
            let m: Option<f64> = rest.split("median").nth(1).and_then(|s| s.split_whitespace().next()?.parse().ok());
            if let (Some(t), Some(m)) = (t, m) {
                run.builds.push((t, m));
            }
        } else if let Some(rest) = line.strip_prefix("CSV,") {
            let f: Vec<&str> = rest.split(',').collect();
            if f.len() >= 7 && f[0] != "res" {
                let num = |i: usize| f[i].parse::<f64>().map_err(|_| format!("bad CSV line from embree: {line}"));
                run.rows.push(EmbreeRow {
                    kind: f[1].to_string(),
                    threads: f[2].parse().map_err(|_| format!("bad CSV line from embree: {line}"))?,
                    median: num(4)?,
                    min: num(5)?,
                    max: num(6)?,
                });
            }
        } else if line.starts_with("## ") || line.starts_with("shadow rays") || line.starts_with("diffuse rays") {
            run.checks.push(line.trim_start_matches("## ").to_string());
        }
    }
    if run.rows.is_empty() && kinds != "none" {
        return Err(format!("no CSV rows in the output of {}", a.embree.display()));
    }
    Ok(run)
}

/// Runs the command.
pub fn run(a: &CompareArgs) -> Result<(), String> {
    let env = Environment::detect();
    let (scene, _) = load_scene(&a.scene.source())?;
    let (cam, light) = a.scene.camera_and_light(&scene)?;
    let mut embree = EmbreeRun::default();
    let mut embree_rounds = Vec::new();
    let builds_run = with_spinner("Embree harness: builds", || run_embree(a, &cam, light.position, "none", a.builds))?;
    embree.merge(builds_run, &mut embree_rounds);

    // The thesis's tree for single rays, and the one with the packet methods' cost model
    // (`StructureParams::packet_kd`) for packets, frustums, MFT and cones: their builds timed per thread count.
    let structure_params = a.kd.structure_params()?;
    let params = [structure_params.kd, structure_params.packet_kd];
    let mut builds = Vec::new();
    for &t in &a.threads {
        let mut times = [Vec::new(), Vec::new()];
        for _ in 0..a.builds {
            for (k, p) in params.iter().enumerate() {
                times[k].push(build_tree(&scene, p, t as usize)?.build_time().as_secs_f64());
            }
        }
        let [thesis, packets] = times.map(|mut v| {
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        });
        builds.push((t, thesis, packets));
    }
    // Every traced method's structures, and the brute force that validates them.
    let mut methods = vec![Method::Mono, Method::Reference];
    methods.extend(a.methods.iter().filter(|m| m.entry().packets()));
    methods.extend(&a.incoherent);
    let threads = a.threads.iter().copied().max().ok_or("--threads: no thread count given")? as usize;
    let structures = build_structures(&scene, &methods, Purpose::Rays, &structure_params, threads)?;
    let (Some(tree), Some(reference)) = (structures.kd(Structure::ThesisKd), structures.reference()) else {
        return Err("the kd-tree and the brute-force reference were not built".into());
    };
    let (w, h) = a.image.size();
    let wb = with_spinner("generating rays", || WorkloadBuilder::new(&scene, &cam, light.position, w, h, tree));
    // Per round and ray kind: the harness first, then raylab's single rays, then the coherent methods (primary
    // and shadow rays) or the incoherent ones (diffuse rays).
    let mut rounds = Vec::new();
    let (mut mbvh_builds, mut dacrt_setup) = (Vec::new(), None);
    for round in 1..=a.rounds {
        let mut this = Round::default();
        for kind in RayKind::ALL {
            let label = format!("Embree harness: {kind} rays (round {round} of {})", a.rounds);
            let run = with_spinner(&label, || run_embree(a, &cam, light.position, kind.name(), 1))?;
            embree.merge(run, &mut embree_rounds);
            let workload = wb.build(kind);
            for &t in &a.threads {
                let options = TraceOptions { method: Method::Mono, ..Default::default() };
                let tracer = Tracer::for_rays(&structures, options).map_err(|e| e.to_string())?;
                let runs = (t as usize, a.warmup as usize, a.reps as usize);
                let (report, results) = measure(&tracer, &workload, HARNESS_TILE, runs, None)?;
                validate(reference, &workload, &results, 256).map_err(|m| format!("validation failed: {m}"))?;
                this.ours.push(report);
            }
            if kind == RayKind::Diffuse {
                // Incoherent rays: the MBVH methods (MBVH RS paper) and DACRT (seed 003).
                if !a.incoherent.is_empty() {
                    let (mbvh_times, setup, rows) = incoherent_runs(a, &scene, &structures, &workload)?;
                    (mbvh_builds, dacrt_setup, this.incoherent) = (mbvh_times, setup, rows);
                }
                continue;
            }
            // Coherent methods: every tile size for the frustum methods.
            for &method in a.methods.iter().filter(|m| m.entry().packets()) {
                let tiles: Vec<u64> =
                    if method.entry().tile_matters() { a.tiles.clone() } else { vec![u64::from(HARNESS_TILE)] };
                for &tile in &tiles {
                    for &t in &a.threads {
                        let options = TraceOptions { method, ..Default::default() };
                        let tracer = Tracer::for_rays(&structures, options).map_err(|e| e.to_string())?;
                        let runs = (t as usize, a.warmup as usize, a.reps as usize);
                        let (report, results) = measure(&tracer, &workload, tile as u32, runs, None)?;
                        validate(reference, &workload, &results, 256)
                            .map_err(|m| format!("validation failed ({method} tile {tile}): {m}"))?;
                        this.coherent.push((method, tile, report));
                    }
                }
            }
        }
        rounds.push(this);
    }
    embree.combine(&embree_rounds);
    let Round { ours, coherent, incoherent } = Round::combine(&rounds);

    let cmd: Vec<String> = std::env::args().collect();
    let mut md = markdown_header(&env, &cmd);
    let _ = writeln!(md, "\nEmbree harness checks: {}.\n", embree.checks.join("; "));
    let _ = writeln!(
        md,
        "| rays | threads | raylab mono Mrays/s (min-max) | Embree API | Embree Mrays/s (min-max) | raylab / Embree | raylab hits, sum_t | nodes/ray | tests/ray |"
    );
    let _ = writeln!(md, "|---|---:|---:|---|---:|---:|---|---:|---:|");
    for r in &ours {
        let (api, ekind) = single_ray_api(r.kind);
        let e = embree.row(ekind, r.threads);
        let (es, ratio) = match e {
            Some(e) => {
                (format!("{:.2} ({:.2}-{:.2})", e.median, e.min, e.max), format!("{:.2}x", r.mrays_median / e.median))
            }
            None => ("n/a".into(), "n/a".into()),
        };
        let check = check_of(r);
        let _ = writeln!(
            md,
            "| {} | {} | {:.2} ({:.2}-{:.2}) | {} | {} | {} | {} | {:.1} | {:.1} |",
            r.kind,
            r.threads,
            r.mrays_median,
            r.mrays_min,
            r.mrays_max,
            api,
            es,
            ratio,
            check,
            r.nodes_per_ray,
            r.isects_per_ray
        );
    }
    let _ = writeln!(
        md,
        "\n| build | threads | raylab kd-tree (SAH, perfect splits, C_trav {}) s | the packet methods' kd-tree (C_trav {}) s | Embree BVH (HIGH) s |",
        params[0].c_trav, params[1].c_trav
    );
    let _ = writeln!(md, "|---|---:|---:|---:|---:|");
    for (t, thesis, packets) in &builds {
        let e = embree.builds.iter().find(|(et, _)| et == t).map_or("n/a".into(), |(_, s)| format!("{s:.3}"));
        let _ = writeln!(md, "| median of {} | {} | {:.3} | {:.3} | {} |", a.builds, t, thesis, packets, e);
    }
    if !coherent.is_empty() {
        let backend = TraceOptions::default().backend;
        let (pw, ph) = raylab_core::packet::packet_shape(backend.lanes());
        let packet = format!("{pw}x{ph}");
        let _ = writeln!(
            md,
            "\nCoherent methods against Embree's best packet or stream API for the same rays and thread count \
             ({} backend; N = nodes per {packet} packet, I = triangle tests per {packet} packet, culled = \
             packet/leaf visits culled; every method here walks the packet methods' kd-tree, with C_trav {}):\n",
            backend.name(),
            params[1].c_trav
        );
        let _ = writeln!(
            md,
            "| rays | threads | method | tile | Mrays/s (min-max) | N | I | culled | Embree best | Embree Mrays/s | raylab / Embree | check |"
        );
        let _ = writeln!(md, "|---|---:|---|---:|---:|---:|---:|---:|---|---:|---:|---|");
        for (method, tile, r) in &coherent {
            let best = embree.best_coherent(r);
            let (bname, bval, ratio) = match best {
                Some(e) => (e.kind.clone(), format!("{:.2}", e.median), format!("{:.2}x", r.mrays_median / e.median)),
                None => ("n/a".into(), "n/a".into(), "n/a".into()),
            };
            let check = check_of(r);
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {:.2} ({:.2}-{:.2}) | {:.2} | {:.2} | {:.1}% | {} | {} | {} | {} |",
                r.kind,
                r.threads,
                method,
                tile,
                r.mrays_median,
                r.mrays_min,
                r.mrays_max,
                r.nodes_per_packet,
                r.isects_per_packet,
                r.culled_percent,
                bname,
                bval,
                ratio,
                check
            );
        }
    }
    if !incoherent.is_empty() {
        let _ = writeln!(
            md,
            "\nIncoherent rays: the MBVH methods and DACRT on the diffuse rays against Embree's single-ray and \
             stream APIs (per ray: 4-box SIMD tests, node fetches, triangle tests; MBVH RS rows name their ray-group \
             size, groups cut along the Z-order curve of each tile; DACRT traces {DACRT_TILE}x{DACRT_TILE} tiles as sets, and its box tests are ray-box filter \
             tests, its fetches recursion nodes). MBVH builds (median of {}): {}. DACRT setup (copying the \
             triangles and dividing the top of them, its only preparation, redone in every timed run): {}.\n",
            a.builds,
            mbvh_builds.iter().map(|(t, s)| format!("{s:.3} s on {t} thread(s)")).collect::<Vec<_>>().join(", "),
            dacrt_setup.map_or("n/a".to_string(), |s| format!("{:.1} ms", s * 1e3))
        );
        let _ = writeln!(
            md,
            "| method | threads | Mrays/s (min-max) | Embree rtcIntersect1 | raylab / Embree | Embree rtcIntersect1M | raylab / Embree | box tests | fetches | tests | check |"
        );
        let _ = writeln!(md, "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|");
        for (method, r) in &incoherent {
            let embree_of = |kind: &str| {
                embree.row(kind, r.threads).map_or(("n/a".to_string(), "n/a".to_string()), |e| {
                    (format!("{:.2}", e.median), format!("{:.2}x", r.mrays_median / e.median))
                })
            };
            let ((e1, r1), (em, rm)) = (embree_of("diffuse_1"), embree_of("diffuse_1M"));
            let _ = writeln!(
                md,
                "| {method} | {} | {:.2} ({:.2}-{:.2}) | {e1} | {r1} | {em} | {rm} | {:.2} | {:.2} | {:.2} | {} hits, {:.1} |",
                r.threads,
                r.mrays_median,
                r.mrays_min,
                r.mrays_max,
                r.box_tests_per_ray,
                r.nodes_per_ray,
                r.isects_per_ray,
                r.hits,
                r.sum_t
            );
        }
    }
    print_markdown(&md, a.markdown.as_deref())?;
    if let Some(p) = &a.json {
        let v = json!({
            "scene": a.scene.scene,
            "camera": cam,
            "light": light.position.to_array(),
            "width": w,
            "height": h,
            "reps": a.reps,
            "rounds": a.rounds,
            "embree": { "checks": embree.checks, "rows": embree.rows, "builds": embree.builds.iter()
                .map(|&(threads, seconds)| json!({ "threads": threads, "seconds": seconds })).collect::<Vec<_>>() },
            "builds": builds.iter().map(|&(threads, thesis, packets)| json!({
                "threads": threads, "kd_seconds": thesis, "packet_kd_seconds": packets, "kd_params": params[0],
                "packet_kd_params": params[1],
            })).collect::<Vec<_>>(),
            "mono": ours.iter().map(|r| {
                let (api, ekind) = single_ray_api(r.kind);
                let e = embree.row(ekind, r.threads);
                json!({ "report": r, "embree_api": api, "embree": e, "ratio": ratio(r, e) })
            }).collect::<Vec<_>>(),
            "coherent": coherent.iter().map(|(method, tile, r)| {
                let e = embree.best_coherent(r);
                json!({ "method": method, "tile": tile, "report": r, "embree_best": e, "ratio": ratio(r, e) })
            }).collect::<Vec<_>>(),
            "incoherent": incoherent.iter().map(|(label, r)| {
                let (single, stream) = (embree.row("diffuse_1", r.threads), embree.row("diffuse_1M", r.threads));
                json!({ "method": label, "report": r, "embree_intersect1": single, "ratio_intersect1": ratio(r, single),
                    "embree_intersect1m": stream, "ratio_intersect1m": ratio(r, stream) })
            }).collect::<Vec<_>>(),
            "mbvh_builds": mbvh_builds.iter().map(|&(threads, seconds)| json!({ "threads": threads, "seconds": seconds }))
                .collect::<Vec<_>>(),
            "dacrt_setup_seconds": dacrt_setup,
        });
        write_json(p, &env, &cmd, v)?;
    }
    Ok(())
}

/// raylab's reports of one round, in the order the configurations ran.
#[derive(Default)]
struct Round {
    /// Single rays (`mono`), per ray kind and thread count.
    ours: Vec<TraceReport>,
    /// The coherent methods, per method, tile and thread count.
    coherent: Vec<(Method, u64, TraceReport)>,
    /// The incoherent methods, labelled as in [`Incoherent`].
    incoherent: Vec<(String, TraceReport)>,
}

impl Round {
    /// One round whose reports take their Mrays/s over all `rounds` ([`combine_reports`]), which ran the same
    /// configurations in the same order.
    fn combine(rounds: &[Round]) -> Round {
        let pick = |i: usize, get: &dyn Fn(&Round, usize) -> &TraceReport| {
            combine_reports(&rounds.iter().map(|r| get(r, i)).collect::<Vec<_>>())
        };
        let first = &rounds[0];
        Round {
            ours: (0..first.ours.len()).map(|i| pick(i, &|r, i| &r.ours[i])).collect(),
            coherent: (0..first.coherent.len())
                .map(|i| (first.coherent[i].0, first.coherent[i].1, pick(i, &|r, i| &r.coherent[i].2)))
                .collect(),
            incoherent: (0..first.incoherent.len())
                .map(|i| (first.incoherent[i].0.clone(), pick(i, &|r, i| &r.incoherent[i].1)))
                .collect(),
        }
    }
}

/// What the incoherent runs give: the MBVH's median build time per thread count, DACRT's setup time, and each
/// method's report, labelled with its RS group size where it has one.
type Incoherent = (Vec<(u64, f64)>, Option<f64>, Vec<(String, TraceReport)>);

/// Times the MBVH's build (per thread count, `--builds` times) as the methods need, then measures and
/// validates the incoherent methods on the diffuse rays `workload` with `structures`: the MBVH methods (MBVH RS
/// paper, each RS group size) and DACRT (seed 003).
fn incoherent_runs(
    a: &CompareArgs,
    scene: &Scene,
    structures: &Structures,
    workload: &Workload,
) -> Result<Incoherent, String> {
    let reference = structures.reference().ok_or("the brute-force reference was not built")?;
    let mut mbvh_builds = Vec::new();
    if a.incoherent.iter().any(|m| m.entry().structure == Structure::Mbvh) {
        for &t in &a.threads {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(t as usize).build().map_err(|e| e.to_string())?;
            let mut times = Vec::new();
            for _ in 0..a.builds {
                times.push(pool.install(|| Mbvh::build(scene)).build_time().as_secs_f64());
            }
            times.sort_by(f64::total_cmp);
            mbvh_builds.push((t, times[times.len() / 2]));
        }
    }
    let dacrt_setup = structures.dacrt().map(|d| d.setup_time().as_secs_f64());
    let runs = a.incoherent.iter().flat_map(|&m| {
        let groups: Vec<Option<u64>> =
            if m == Method::MbvhRs { a.rs_groups.iter().map(|&g| Some(g)).collect() } else { vec![None] };
        groups.into_iter().map(move |g| (m, g))
    });
    let mut reports = Vec::new();
    for (method, group) in runs {
        for &t in &a.threads {
            let options = TraceOptions { method, stream_group: group.map(|g| g as usize), ..Default::default() };
            let tracer = Tracer::for_rays(structures, options).map_err(|e| e.to_string())?;
            let tile = match group {
                _ if (method.entry().structure == Structure::Dacrt) => DACRT_TILE,
                Some(g) => tile_for_group(HARNESS_TILE, g as u32),
                None => HARNESS_TILE,
            };
            let setup = || drop(Dacrt::new(scene));
            let setup = (method.entry().structure == Structure::Dacrt).then_some(&setup as &(dyn Fn() + Sync));
            let runs = (t as usize, a.warmup as usize, a.reps as usize);
            let (report, results) = measure(&tracer, workload, tile, runs, setup)?;
            validate(reference, workload, &results, 256).map_err(|m| format!("validation failed ({method}): {m}"))?;
            let label = match group {
                Some(g) => format!("{method} ({g})"),
                None => method.to_string(),
            };
            reports.push((label, report));
        }
    }
    Ok((mbvh_builds, dacrt_setup, reports))
}
