//! Frame measurements the table commands share: a configuration's median frame rate, the thesis's N and I,
//! the culled share and the stage times (thesis Tables 4.1-4.6 and 5.1), as cells and JSON records.

use std::time::Instant;

use raylab_core::render::{RenderSettings, StageTimes, render};
use raylab_core::scene::{Camera, PointLight, Scene};
use raylab_core::trace::Tracer;
use serde::Serialize;
use serde_json::Value;

/// One measured configuration.
#[derive(Clone, Copy, Serialize)]
pub struct Cell {
    /// Frames per second from the median frame time.
    pub fps: f64,
    /// The thesis's N, nodes per packet.
    pub n: f64,
    /// The thesis's I, triangle tests per packet.
    pub i: f64,
    /// Culled packet visits in percent (`culled_percent` in JSON, as in the other commands' reports).
    #[serde(rename = "culled_percent")]
    pub culled: f64,
    /// Stage times of the last frame.
    pub stages: StageTimes,
    /// Shadow-cache hit rate of the last frame.
    pub cache_hit_rate: f64,
}

/// Renders one warm-up frame and `reps` timed ones.
pub fn measure(
    scene: &Scene,
    tracer: &Tracer,
    cam: &Camera,
    light: PointLight,
    s: &RenderSettings,
    pool: &rayon::ThreadPool,
    reps: u64,
) -> Cell {
    measure_interleaved(scene, cam, light, &[(tracer, *s)], pool, reps)[0]
}

/// Measures several configurations of one view together, each a tracer (a method) and frame settings: a
/// warm-up frame of each, then `reps` rounds that render each once, so that a slow spell of a shared machine
/// slows every configuration alike and the ratios between them (MFT against the frustum or the packets in
/// Tables 4.1-4.4, Table 5.1's edge/hard time, Table 4.6's cone speed-up) stay honest.
pub fn measure_interleaved(
    scene: &Scene,
    cam: &Camera,
    light: PointLight,
    configs: &[(&Tracer, RenderSettings)],
    pool: &rayon::ThreadPool,
    reps: u64,
) -> Vec<Cell> {
    let mut times = vec![Vec::new(); configs.len()];
    let mut last = vec![None; configs.len()];
    pool.install(|| {
        for (tracer, s) in configs {
            render(scene, tracer, cam, light, s);
        }
        for _ in 0..reps {
            for (((tracer, s), t), l) in configs.iter().zip(&mut times).zip(&mut last) {
                let t0 = Instant::now();
                let f = render(scene, tracer, cam, light, s);
                t.push(t0.elapsed().as_secs_f64());
                *l = Some((f.stats, f.stages));
            }
        }
    });
    times
        .iter_mut()
        .zip(last)
        .map(|(t, l)| {
            t.sort_by(f64::total_cmp);
            let (stats, stages) = l.unwrap_or_default();
            Cell {
                fps: t.get(t.len() / 2).map_or(0.0, |m| 1.0 / m),
                n: stats.nodes_per_packet(),
                i: stats.isects_per_packet(),
                culled: stats.culled_percent(),
                stages,
                cache_hit_rate: stats.cache_hit_rate(),
            }
        })
        .collect()
}

/// A JSON record of `cell`: the fields of `head` (what was measured) followed by the cell's.
pub fn record(head: Value, cell: &Cell) -> Value {
    let mut v = head;
    if let (Some(o), Ok(Value::Object(c))) = (v.as_object_mut(), serde_json::to_value(cell)) {
        o.extend(c);
    }
    v
}
