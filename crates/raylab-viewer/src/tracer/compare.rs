//! The "compare methods" measurement: the current view traced with every interactive traversal method and
//! tile size, giving FPS, N and I per configuration as in thesis Tables 4.1-4.5, for any view.

use raylab_core::method::Method;
use serde::Serialize;

use crate::settings::ViewerSettings;
use crate::tracer::jobs::{Job, trace_frame};

/// Timed frames per configuration (after one untimed warm-up frame); the median is kept.
pub const TIMED_FRAMES: usize = 3;

/// One measured configuration.
#[derive(Clone, Debug, Serialize)]
pub struct CompareRow {
    /// Traversal method.
    pub method: Method,
    /// Tile edge.
    pub tile: u32,
    /// Median frame time in milliseconds.
    pub ms: f64,
    /// Frames per second at that time.
    pub fps: f64,
    /// Million rays per second (primary and shadow).
    pub mrays: f64,
    /// Nodes per packet (thesis N).
    pub n: f64,
    /// Intersection tests per packet (thesis I).
    pub i: f64,
    /// Packets culled at leaves, percent of packet-leaf visits.
    pub culled_pct: f64,
}

/// The configurations compared: the single-ray and packet methods at the current tile (where the tile is
/// only the threads' work unit), the frustum methods at every tile size.
pub fn compare_configs(current_tile: u32) -> Vec<(Method, u32)> {
    let mut v = Vec::new();
    for m in Method::ALL {
        if m.entry().not_live.is_some() {
            continue;
        }
        if m.entry().tile_matters() {
            v.extend(ViewerSettings::TILES.iter().map(|&t| (m, t)));
        } else {
            v.push((m, current_tile));
        }
    }
    v
}

/// Traces `job`'s view with `method` and `tile` on the current rayon pool.
pub fn measure(job: &Job, method: Method, tile: u32) -> CompareRow {
    let mut job = job.clone();
    job.settings.tile = tile;
    trace_frame(&job, method);
    let mut runs: Vec<_> = (0..TIMED_FRAMES).map(|_| trace_frame(&job, method)).collect();
    runs.sort_by(|a, b| a.wall_s.total_cmp(&b.wall_s));
    let r = &runs[TIMED_FRAMES / 2];
    let s = r.frame.stats;
    CompareRow {
        method,
        tile,
        ms: r.wall_s * 1e3,
        fps: 1.0 / r.wall_s.max(1e-9),
        mrays: s.rays as f64 / r.wall_s.max(1e-9) / 1e6,
        n: s.nodes_per_packet(),
        i: s.isects_per_packet(),
        culled_pct: s.culled_percent(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_interactive_method_is_compared() {
        let c = compare_configs(16);
        for m in Method::ALL {
            let n = c.iter().filter(|(x, _)| *x == m).count();
            let want = match m {
                _ if m.entry().not_live.is_some() => 0,
                m if m.entry().tile_matters() => ViewerSettings::TILES.len(),
                _ => 1,
            };
            assert_eq!(n, want, "{m}");
        }
        assert!(c.contains(&(Method::Mono, 16)) && c.contains(&(Method::Mft, 64)));
    }
}
