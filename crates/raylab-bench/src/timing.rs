//! Timed trace runs of a harness workload, with the harness's measurement protocol: all rays generated
//! before timing, 16x16-pixel tiles taken by the threads of a pool, warm-up runs, then timed runs of the
//! whole frame whose median, minimum and maximum are reported.

use std::time::Instant;

use glam::Vec3;
use raylab_core::ray::{Hit, Ray};
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

/// One tile of a [`TiledWorkload`]: its rectangle, its rays row by row, its output buffer (closest hits or
/// occlusion, after the workload's kind; the other stays empty) and counters.
struct TileJob {
    x0: usize,
    y0: usize,
    width: usize,
    height: usize,
    rays: Vec<Option<Ray>>,
    hits: Vec<Option<Hit>>,
    occluded: Vec<bool>,
    stats: TraversalStats,
}

/// A workload cut into `tile x tile` tiles before any timing, as the harness prepares its rays: each tile owns
/// its rays and its output buffers, so a timed run does nothing but trace (the threads of the current rayon
/// pool take the tiles), and putting the results back in image order happens after the clock stops.
pub struct TiledWorkload {
    tiles: Vec<TileJob>,
    width: usize,
    pixels: usize,
    occlusion: bool,
    toward: Option<Vec3>,
}

impl TiledWorkload {
    /// Cuts `w` into tiles of edge `tile` (smaller at the image's right and bottom edges).
    pub fn new(w: &Workload, tile: u32) -> Self {
        let (width, height) = (w.width as usize, w.height as usize);
        let tile = tile.max(1) as usize;
        let occlusion = w.kind.is_occlusion();
        let tiles = (0..height.div_ceil(tile))
            .flat_map(|ty| (0..width.div_ceil(tile)).map(move |tx| (tx * tile, ty * tile)))
            .map(|(x0, y0)| {
                let (tw, th) = (tile.min(width - x0), tile.min(height - y0));
                let rays: Vec<Option<Ray>> =
                    (y0..y0 + th).flat_map(|y| w.rays[y * width + x0..y * width + x0 + tw].iter().copied()).collect();
                let n = rays.len();
                TileJob {
                    x0,
                    y0,
                    width: tw,
                    height: th,
                    rays,
                    hits: if occlusion { Vec::new() } else { vec![None; n] },
                    occluded: if occlusion { vec![false; n] } else { Vec::new() },
                    stats: TraversalStats::default(),
                }
            })
            .collect();
        Self { tiles, width, pixels: w.rays.len(), occlusion, toward: w.toward }
    }

    /// Traces every tile once with `tracer` on the current rayon pool: the timed part of a run. Each tile is
    /// its own rayon job: with rayon's default pieces (about two per thread, split further only when
    /// stolen) one thread can be left tracing a costly part of the image alone while the others idle.
    pub fn trace(&mut self, tracer: &Tracer) {
        let (occlusion, toward) = (self.occlusion, self.toward);
        self.tiles.par_iter_mut().with_max_len(1).for_each(|t| {
            t.stats = TraversalStats::default();
            if occlusion {
                tracer.occluded_tile(&t.rays, t.width, t.height, toward, &mut t.occluded, &mut t.stats);
            } else {
                tracer.intersect_tile(&t.rays, t.width, t.height, &mut t.hits, &mut t.stats);
            }
        });
    }

    /// The last trace's per-pixel results in image order, and its counters summed over the tiles.
    pub fn results(&self) -> (Vec<PixelResult>, TraversalStats) {
        let mut results = vec![PixelResult::None; self.pixels];
        let mut stats = TraversalStats::default();
        for t in &self.tiles {
            for (i, r) in t.rays.iter().enumerate() {
                if r.is_none() {
                    continue;
                }
                results[(t.y0 + i / t.width) * self.width + t.x0 + i % t.width] = if self.occlusion {
                    PixelResult::Occluded(t.occluded[i])
                } else {
                    PixelResult::Hit(t.hits[i].map(|h| (h.t, h.tri)))
                };
            }
            stats += t.stats;
        }
        (results, stats)
    }
}

/// Traces every ray of `w` once, on the current rayon pool, in `tile x tile` tiles taken by the threads.
pub fn trace_once(tracer: &Tracer, w: &Workload, tile: u32) -> (Vec<PixelResult>, TraversalStats) {
    let mut tiled = TiledWorkload::new(w, tile);
    tiled.trace(tracer);
    tiled.results()
}

/// Runs `warmup` untimed and `reps` timed traces of `w` on a pool of `threads` threads. Each timed run also
/// runs `setup` when given: the preparation a method redoes whenever the geometry moves (DACRT's
/// [`raylab_core::dacrt::Dacrt::new`]), so that its rates assume no structure prepared in advance.
pub fn measure(
    tracer: &Tracer,
    w: &Workload,
    tile: u32,
    (threads, warmup, reps): (usize, usize, usize),
    setup: Option<&(dyn Fn() + Sync)>,
) -> Result<(TraceReport, Vec<PixelResult>), String> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| format!("cannot start {threads} threads: {e}"))?;
    let rays = w.ray_count();
    let mut tiled = TiledWorkload::new(w, tile);
    let mut speeds = Vec::with_capacity(reps);
    pool.install(|| {
        for _ in 0..warmup {
            tiled.trace(tracer);
        }
        for _ in 0..reps.max(1) {
            let t0 = Instant::now();
            if let Some(setup) = setup {
                setup();
            }
            tiled.trace(tracer);
            let secs = t0.elapsed().as_secs_f64();
            speeds.push(rays as f64 / secs.max(1e-12) / 1e6);
        }
    });
    let (results, stats) = tiled.results();
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
        culled_percent: stats.culled_percent(),
    };
    Ok((report, results))
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
