//! The tile renderer: the image is cut into square tiles that rayon threads take in turn (thesis chapter 6),
//! each traced in the chosen [`RayOrder`] and shaded with [`shade`].

mod order;
pub mod shade;

pub use order::RayOrder;

use glam::Vec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::ray::Ray;
use crate::scene::{Camera, PointLight, Scene};
use crate::stats::TraversalStats;
use crate::trace::Tracer;
use shade::to_display;

/// Options of one rendered frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RenderSettings {
    /// Image width in pixels (at least 1).
    pub width: u32,
    /// Image height in pixels (at least 1).
    pub height: u32,
    /// Tile edge in pixels.
    pub tile: u32,
    /// Pixel order inside a tile.
    pub order: RayOrder,
    /// Trace hard shadows.
    pub shadows: bool,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self { width: 512, height: 512, tile: 16, order: RayOrder::Scanline, shadows: true }
    }
}

/// A rendered image and the work it took.
#[derive(Clone, Debug)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Display-ready RGBA8 pixels (gamma 2.2), row-major from the top left.
    pub rgba: Vec<[u8; 4]>,
    /// Counters of primary and shadow rays together.
    pub stats: TraversalStats,
}

/// A finished tile: (pixel index, colour) pairs and its counters.
type TileResult = (Vec<(u32, [u8; 4])>, TraversalStats);

/// Renders `scene` from `camera` lit by `light`, tracing primary and shadow rays tile by tile with `tracer`
/// (so the traversal method changes the speed, never the pixels). The work runs on the current rayon pool
/// (install a pool to choose the thread count).
pub fn render(scene: &Scene, tracer: &Tracer, camera: &Camera, light: PointLight, settings: &RenderSettings) -> Frame {
    let (w, h) = (settings.width.max(1), settings.height.max(1));
    let tile = settings.tile.max(1);
    let raster = camera.raster(w, h);
    let bounds = scene.bounds();
    let epsilon = if bounds.is_empty() { 0.0 } else { 1e-4 * bounds.diagonal() };
    // Single rays are traced in the chosen order; packet methods need the tile's pixels row by row.
    let order = if tracer.options.method.uses_packets() { RayOrder::Scanline } else { settings.order };
    let offsets = order.offsets(tile, tile);
    let tiles: Vec<(u32, u32)> =
        (0..h.div_ceil(tile)).flat_map(|ty| (0..w.div_ceil(tile)).map(move |tx| (tx * tile, ty * tile))).collect();
    let done: Vec<TileResult> = tiles
        .par_iter()
        .map(|&(x0, y0)| {
            let mut stats = TraversalStats::default();
            let (tw, th) = (tile.min(w - x0), tile.min(h - y0));
            let pixels: Vec<(u32, u32)> =
                offsets.iter().map(|&(dx, dy)| (x0 + dx, y0 + dy)).filter(|&(x, y)| x < w && y < h).collect();
            let rays: Vec<Option<Ray>> = pixels.iter().map(|&(x, y)| Some(raster.primary(x, y))).collect();
            let (rw, rh) = if order == RayOrder::Scanline { (tw as usize, th as usize) } else { (rays.len(), 1) };
            let mut hits = vec![None; rays.len()];
            tracer.intersect_tile(&rays, rw, rh, &mut hits, &mut stats);
            let shadow: Vec<Option<Ray>> = rays
                .iter()
                .zip(&hits)
                .map(|(r, h)| match (r, h) {
                    (Some(r), Some(h)) if settings.shadows => shade::shadow_ray(scene, r, h, &light, epsilon),
                    _ => None,
                })
                .collect();
            let mut blocked = vec![false; rays.len()];
            if shadow.iter().any(Option::is_some) {
                tracer.occluded_tile(&shadow, rw, rh, Some(light.position), &mut blocked, &mut stats);
            }
            let px = pixels
                .iter()
                .enumerate()
                .map(|(i, &(x, y))| {
                    let c = match (&rays[i], &hits[i]) {
                        (Some(r), Some(hit)) => {
                            let visible = !settings.shadows || (shadow[i].is_some() && !blocked[i]);
                            shade::shade(scene, r, hit, &light, visible)
                        }
                        _ => Vec3::ZERO,
                    };
                    (y * w + x, [to_display(c.x), to_display(c.y), to_display(c.z), 255])
                })
                .collect();
            (px, stats)
        })
        .collect();
    let mut rgba = vec![[0, 0, 0, 255]; (w * h) as usize];
    let mut stats = TraversalStats::default();
    for (px, s) in done {
        for (i, c) in px {
            rgba[i as usize] = c;
        }
        stats += s;
    }
    Frame { width: w, height: h, rgba, stats }
}
