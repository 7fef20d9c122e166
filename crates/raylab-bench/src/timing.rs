//! Timed trace runs of a harness workload, with the harness's measurement protocol: all rays generated
//! before timing, 16x16-pixel tiles taken by the threads of a pool, warm-up runs, then timed runs of the
//! whole frame whose median, minimum and maximum are reported.

use std::time::Instant;

use raylab_core::ray::Ray;
use raylab_core::reference::BruteForce;
use raylab_core::stats::TraversalStats;
use raylab_core::trace::Tracer;
use raylab_core::workload::{RayKind, Workload};
use rayon::prelude::*;
use serde::Serialize;

/// The tile edge the harness uses.
pub const HARNESS_TILE: u32 = 16;

/// The tile edge, `tile` or the smallest power-of-two multiple of it, whose tiles hold at least `group` rays
/// (an MBVH RS ray group is cut from one tile).
pub fn tile_for_group(tile: u32, group: u32) -> u32 {
    let mut t = tile.max(1);
    while t * t < group {
        t *= 2;
    }
    t
}

/// Tile edge of DACRT's ray sets in the benchmarks: 65,536 rays a set, four sets for 512x512 (so two threads
/// share the work); smaller sets repeat the division of the scene's triangles more often.
pub const DACRT_SET_TILE: u32 = 256;

/// Per-pixel result of a trace: hit distance (closest-hit kinds) or occlusion.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PixelResult {
    /// No ray for this pixel.
    None,
    /// Closest hit: distance and triangle, or a miss.
    Hit(Option<(f32, u32)>),
    /// Any-hit: blocked or not.
    Occluded(bool),
}

/// What one timed configuration produced.
#[derive(Clone, Debug, Serialize)]
pub struct TraceReport {
    /// Ray kind.
    pub kind: RayKind,
    /// Threads in the pool.
    pub threads: usize,
    /// Rays traced per run.
    pub rays: usize,
    /// Closest-hit kinds: rays that hit. Shadow: rays that were blocked.
    pub hits: usize,
    /// Sum of hit distances in double precision (closest-hit kinds).
    pub sum_t: f64,
    /// Median Mrays/s over the timed runs.
    pub mrays_median: f64,
    /// Slowest run.
    pub mrays_min: f64,
    /// Fastest run.
    pub mrays_max: f64,
    /// Counters of one run.
    pub stats: TraversalStats,
    /// Nodes visited per ray.
    pub nodes_per_ray: f64,
    /// Leaves visited per ray.
    pub leaves_per_ray: f64,
    /// Triangle tests per ray.
    pub isects_per_ray: f64,
    /// SIMD four-box tests per ray (MBVH).
    pub box_tests_per_ray: f64,
    /// The thesis's N: nodes per 2x2 packet (per ray for single-ray methods).
    pub nodes_per_packet: f64,
    /// The thesis's I: intersection tests per 2x2 packet (per ray for single-ray methods).
    pub isects_per_packet: f64,
    /// Share of packets culled at leaves, in percent of packet visits to non-empty leaves.
    pub culled_percent: f64,
}

/// Traces every ray of `w` once, on the current rayon pool, in `tile x tile` tiles taken by the threads.
pub fn trace_once(tracer: &Tracer, w: &Workload, tile: u32) -> (Vec<PixelResult>, TraversalStats) {
    let (width, height) = (w.width as usize, w.height as usize);
    let tile = tile as usize;
    let tiles: Vec<(usize, usize)> = (0..height.div_ceil(tile))
        .flat_map(|ty| (0..width.div_ceil(tile)).map(move |tx| (tx * tile, ty * tile)))
        .collect();
    let occlusion = w.kind.is_occlusion();
    let parts: Vec<TileOutput> = tiles
        .par_iter()
        .map(|&(x0, y0)| {
            let mut stats = TraversalStats::default();
            let (tw, th) = (tile.min(width - x0), tile.min(height - y0));
            let rays: Vec<Option<Ray>> = (y0..y0 + th)
                .flat_map(|y| (x0..x0 + tw).map(move |x| (x, y)))
                .map(|(x, y)| w.rays[y * width + x])
                .collect();
            let results = if occlusion {
                let mut out = vec![false; rays.len()];
                tracer.occluded_tile(&rays, tw, th, w.toward, &mut out, &mut stats);
                rays.iter()
                    .zip(out)
                    .map(|(r, o)| if r.is_some() { PixelResult::Occluded(o) } else { PixelResult::None })
                    .collect()
            } else {
                let mut out = vec![None; rays.len()];
                tracer.intersect_tile(&rays, tw, th, &mut out, &mut stats);
                rays.iter()
                    .zip(out)
                    .map(
                        |(r, h)| {
                            if r.is_some() { PixelResult::Hit(h.map(|h| (h.t, h.tri))) } else { PixelResult::None }
                        },
                    )
                    .collect()
            };
            ((x0, y0, tw, th), results, stats)
        })
        .collect();
    let mut results = vec![PixelResult::None; w.rays.len()];
    let mut stats = TraversalStats::default();
    for ((x0, y0, tw, _), part, s) in parts {
        for (i, r) in part.into_iter().enumerate() {
            results[(y0 + i / tw) * width + x0 + i % tw] = r;
        }
        stats += s;
    }
    (results, stats)
}

/// A traced tile: its rectangle, per-pixel results and counters.
type TileOutput = ((usize, usize, usize, usize), Vec<PixelResult>, TraversalStats);

/// Runs `warmup` untimed and `reps` timed traces of `w` on a pool of `threads` threads.
pub fn measure(
    tracer: &Tracer,
    w: &Workload,
    tile: u32,
    threads: usize,
    warmup: usize,
    reps: usize,
) -> Result<(TraceReport, Vec<PixelResult>), String> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| format!("cannot start {threads} threads: {e}"))?;
    let rays = w.ray_count();
    let mut last = None;
    let mut speeds = Vec::with_capacity(reps);
    pool.install(|| {
        for _ in 0..warmup {
            last = Some(trace_once(tracer, w, tile));
        }
        for _ in 0..reps.max(1) {
            let t0 = Instant::now();
            let r = trace_once(tracer, w, tile);
            let secs = t0.elapsed().as_secs_f64();
            speeds.push(rays as f64 / secs.max(1e-12) / 1e6);
            last = Some(r);
        }
    });
    let (results, stats) = last.expect("at least one run");
    speeds.sort_by(f64::total_cmp);
    let (hits, sum_t) = summarize(&results);
    let report = TraceReport {
        kind: w.kind,
        threads,
        rays,
        hits,
        sum_t,
        mrays_median: speeds[speeds.len() / 2],
        mrays_min: speeds[0],
        mrays_max: speeds[speeds.len() - 1],
        stats,
        nodes_per_ray: stats.nodes_per_ray(),
        leaves_per_ray: stats.leaves_per_ray(),
        isects_per_ray: stats.isects_per_ray(),
        box_tests_per_ray: stats.box_tests as f64 / stats.rays.max(1) as f64,
        nodes_per_packet: stats.nodes_per_packet(),
        isects_per_packet: stats.isects_per_packet(),
        culled_percent: culled_percent(&stats),
    };
    Ok((report, results))
}

/// Culled packet visits as a share of packet visits to leaves (culled plus tested), in percent.
fn culled_percent(s: &TraversalStats) -> f64 {
    let tested = s.packets_culled + s.packets_tested;
    if tested == 0 { 0.0 } else { 100.0 * s.packets_culled as f64 / tested as f64 }
}

/// Hit (or occluded) count and the sum of hit distances.
pub fn summarize(results: &[PixelResult]) -> (usize, f64) {
    let mut hits = 0;
    let mut sum_t = 0.0;
    for r in results {
        match r {
            PixelResult::Hit(Some((t, _))) => {
                hits += 1;
                sum_t += *t as f64;
            }
            PixelResult::Occluded(true) => hits += 1,
            _ => {}
        }
    }
    (hits, sum_t)
}

/// Checks `samples` evenly spread rays of `w` against the brute-force reference; returns the number of
/// rays checked, or a description of the first mismatch. Two different triangles at the same distance both
/// count as correct.
pub fn validate(
    reference: &BruteForce,
    w: &Workload,
    results: &[PixelResult],
    samples: usize,
) -> Result<usize, String> {
    let idx: Vec<usize> = (0..w.rays.len()).filter(|&i| w.rays[i].is_some()).collect();
    if idx.is_empty() || samples == 0 {
        return Ok(0);
    }
    let step = (idx.len() / samples).max(1);
    let chosen: Vec<usize> = idx.iter().copied().step_by(step).take(samples).collect();
    let bad = chosen.par_iter().find_map_any(|&i| {
        let ray = w.rays[i].as_ref().expect("chosen rays exist");
        let mut s = TraversalStats::default();
        match results[i] {
            PixelResult::Occluded(o) => {
                let want = reference.occluded(ray, &mut s);
                (o != want).then(|| format!("pixel {i}: occluded {o}, reference says {want}"))
            }
            PixelResult::Hit(got) => {
                let want = reference.intersect(ray, &mut s).map(|h| (h.t, h.tri));
                let same = match (got, want) {
                    (None, None) => true,
                    (Some((t, tri)), Some((rt, rtri))) => {
                        tri == rtri || (t == rt && reference.hit_distance(ray, tri) == Some(t))
                    }
                    _ => false,
                };
                (!same).then(|| format!("pixel {i}: got {got:?}, reference {want:?}"))
            }
            PixelResult::None => Some(format!("pixel {i}: no result")),
        }
    });
    match bad {
        Some(m) => Err(m),
        None => Ok(chosen.len()),
    }
}
