//! The tile renderer: the image is cut into square tiles that rayon threads take in turn (thesis chapter 6),
//! each traced in the chosen [`RayOrder`], lit under the chosen [`Shadows`] technique and shaded with the
//! fixed-function materials, reflections and refractions included ([`shade`]), or drawn as one of the
//! diagnostic [`FrameView`]s.

pub mod hybrid;
mod plain;
pub mod shade;
mod stages;
mod view;
mod visibility;
mod whitted;

pub use stages::StageTimes;
pub use view::{FrameView, depth_grey, heat_color};
pub use visibility::{ShadowScratch, ShadowTracer};

use std::cell::RefCell;
use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::ray::{Hit, Ray};
use crate::ray_order::RayOrder;
use crate::scene::{Camera, PointLight, PrimaryGrid, Scene};
use crate::shadow::Shadows;
use crate::stats::TraversalStats;
use crate::trace::Tracer;
use shade::to_display_rgba;

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
    /// The shadow technique.
    pub shadows: Shadows,
    /// Reflection and refraction bounces after the primary hit (0: primary rays only).
    pub max_depth: u32,
    /// What the frame shows.
    pub view: FrameView,
    /// Value at the hot end of the heat maps; `None` scales each frame to its own maximum.
    pub heat_max: Option<f32>,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 512,
            height: 512,
            tile: 16,
            order: RayOrder::Scanline,
            shadows: Shadows::Hard,
            max_depth: RenderSettings::DEFAULT_DEPTH,
            view: FrameView::Shaded,
            heat_max: None,
        }
    }
}

impl RenderSettings {
    /// Default reflection and refraction depth (as RTTest's demo scenes).
    pub const DEFAULT_DEPTH: u32 = 3;
    /// Deepest recursion accepted; every level can double the rays.
    pub const MAX_DEPTH: u32 = 16;
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
    /// Counters of primary, secondary and shadow rays together.
    pub stats: TraversalStats,
    /// Time per stage, summed over threads.
    pub stages: StageTimes,
    /// For the heat-map and depth views, the values at the two ends of the colour scale (for a legend).
    pub range: Option<(f32, f32)>,
}

/// A finished tile: where it lies in the image, its pixels row by row (`width` wide), and for the scalar views
/// each pixel's value (the hit distance for depth, the work for heat maps) in the same layout.
#[derive(Default)]
struct TileOut {
    x0: u32,
    y0: u32,
    width: u32,
    rgba: Vec<[u8; 4]>,
    values: Vec<f32>,
    stats: TraversalStats,
    stages: StageTimes,
}

impl TileOut {
    /// An empty `tw x th` tile at `(x0, y0)`: black pixels, and infinite values (misses) for a scalar `view`.
    fn new((x0, y0): (u32, u32), (tw, th): (u32, u32), view: FrameView) -> Self {
        let n = (tw * th) as usize;
        let values = if view.is_scalar() { vec![f32::INFINITY; n] } else { Vec::new() };
        Self { x0, y0, width: tw, rgba: vec![[0, 0, 0, 255]; n], values, ..Self::default() }
    }

    /// The place of image pixel `(x, y)`, which lies in the tile, in the tile's buffers.
    #[inline]
    fn index(&self, (x, y): (u32, u32)) -> usize {
        ((y - self.y0) * self.width + (x - self.x0)) as usize
    }
}

/// Renders `scene` from `camera` lit by `light`, tracing primary, secondary and shadow rays tile by tile with
/// `tracer` (so the traversal method changes the speed, never the pixels). The work runs on the current rayon pool
/// (install a pool to choose the thread count).
pub fn render(scene: &Scene, tracer: &Tracer, camera: &Camera, light: PointLight, settings: &RenderSettings) -> Frame {
    let (w, h) = (settings.width.max(1), settings.height.max(1));
    let tile = tracer.options.method.entry().tile_edge(settings.tile, 1);
    // Single rays are traced in the chosen order; packet methods need the tile's pixels row by row.
    let order = if tracer.options.method.entry().packets() { RayOrder::Scanline } else { settings.order };
    let ctx = TileContext {
        scene,
        tracer,
        primary: camera.raster(w, h).grid(),
        light,
        settings,
        width: w,
        epsilon: surface_epsilon(scene),
        order,
        tile,
        offsets: order.offsets(tile, tile),
        plain: plain::PlainMaterials::of(scene),
    };
    let tiles: Vec<(u32, u32)> =
        (0..h.div_ceil(tile)).flat_map(|ty| (0..w.div_ceil(tile)).map(move |tx| (tx * tile, ty * tile))).collect();
    // One tile per rayon job. Left to itself, rayon cuts a frame's tiles into about two pieces per thread and
    // splits a piece further only once another thread steals it; the parts of an image cost very different
    // amounts (sky against arcades, lit floor against shadow edges), so one thread was left finishing a
    // costly piece alone. The scratch buffers stay with the worker thread instead of the job.
    let done: Vec<TileOut> = tiles
        .par_iter()
        .with_max_len(1)
        .map(|&(x0, y0)| with_scratch(|sc| ctx.tile(x0, y0, tile.min(w - x0), tile.min(h - y0), sc)))
        .collect();

    let mut rgba = vec![[0, 0, 0, 255]; (w * h) as usize];
    let range = settings.view.is_scalar().then(|| value_range(&done, settings));
    let scalar_color = |v: f32| match (settings.view, range) {
        (FrameView::Depth, Some((near, far))) => depth_color(v, near, far),
        (_, Some((_, hot))) => heat_color(if hot > 0.0 { v / hot } else { 0.0 }),
        _ => [0, 0, 0, 255],
    };
    // The tiles are put in place band by band in parallel: a band of `tile` rows holds exactly one row of
    // tiles, which arrive in row-major order, and each tile row is one copy.
    let tiles_across = w.div_ceil(tile) as usize;
    let (width, tile) = (w as usize, tile as usize);
    rgba.par_chunks_mut(width * tile).zip(done.par_chunks(tiles_across)).for_each(|(band, row)| {
        for t in row {
            let (x0, tw) = (t.x0 as usize, t.width as usize);
            let dst = band.chunks_mut(width).map(|line| &mut line[x0..x0 + tw]);
            if range.is_some() {
                for (line, values) in dst.zip(t.values.chunks(tw)) {
                    for (c, &v) in line.iter_mut().zip(values) {
                        *c = scalar_color(v);
                    }
                }
            } else {
                for (line, src) in dst.zip(t.rgba.chunks(tw)) {
                    line.copy_from_slice(src);
                }
            }
        }
    });
    let mut stats = TraversalStats::default();
    let mut stages = StageTimes::default();
    for t in &done {
        stats += t.stats;
        stages += t.stages;
    }
    Frame { width: w, height: h, rgba, stats, stages, range }
}

/// How far secondary and shadow rays start off a surface: 1e-4 of the scene's diagonal.
pub fn surface_epsilon(scene: &Scene) -> f32 {
    let bounds = scene.bounds();
    if bounds.is_empty() { 0.0 } else { 1e-4 * bounds.diagonal() }
}

/// The ends of a scalar view's colour scale: nearest and farthest hit for depth, zero and the largest (or the
/// fixed) count for heat maps.
fn value_range(tiles: &[TileOut], settings: &RenderSettings) -> (f32, f32) {
    let values = || tiles.iter().flat_map(|t| t.values.iter().copied()).filter(|v| v.is_finite());
    if settings.view == FrameView::Depth {
        let near = values().fold(f32::INFINITY, f32::min);
        let far = values().fold(f32::NEG_INFINITY, f32::max);
        if near <= far { (near, far) } else { (0.0, 0.0) }
    } else {
        (0.0, settings.heat_max.filter(|m| m.is_finite() && *m > 0.0).unwrap_or_else(|| values().fold(0.0, f32::max)))
    }
}

/// Grey level of a hit distance: [`depth_grey`] of its place between the nearest and the farthest hit; black
/// for misses.
fn depth_color(t: f32, near: f32, far: f32) -> [u8; 4] {
    if !t.is_finite() {
        return [0, 0, 0, 255];
    }
    depth_grey(if far > near { (t - near) / (far - near) } else { 0.0 })
}

thread_local! {
    /// Each rayon worker's tile scratch buffers, kept from tile to tile and frame to frame.
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

/// Runs `f` with this thread's tile scratch, or with fresh buffers when they are in use: a thread that waits
/// inside a tile's own parallel work (DACRT's joins) may be handed another tile meanwhile.
fn with_scratch<R>(f: impl FnOnce(&mut Scratch) -> R) -> R {
    SCRATCH.with(|cell| match cell.try_borrow_mut() {
        Ok(mut sc) => f(&mut sc),
        Err(_) => f(&mut Scratch::default()),
    })
}

/// Everything a tile needs, shared by all tiles of a frame.
struct TileContext<'a> {
    scene: &'a Scene,
    tracer: &'a Tracer<'a>,
    /// The frame's primary rays.
    primary: PrimaryGrid,
    light: PointLight,
    settings: &'a RenderSettings,
    width: u32,
    epsilon: f32,
    order: RayOrder,
    /// Tile edge (the method's, see [`crate::method::MethodEntry::tile_edge`]).
    tile: u32,
    /// The pixel offsets of a whole tile in `order`, computed once per frame.
    offsets: Vec<(u32, u32)>,
    /// Which of the scene's materials the plain shading path takes ([`plain::PlainMaterials`]).
    plain: plain::PlainMaterials,
}

/// Buffers of one block of rays and the shadow techniques' state, reused from block to block and from tile to
/// tile by one worker.
#[derive(Default)]
struct Scratch {
    pixels: Vec<(u32, u32)>,
    rays: Vec<Option<Ray>>,
    hits: Vec<Option<Hit>>,
    seeds: Vec<u32>,
    shadow: ShadowScratch,
    plain: plain::PlainScratch,
}

impl TileContext<'_> {
    /// The shadow tracer of this frame.
    fn shadows(&self) -> ShadowTracer<'_> {
        ShadowTracer { tracer: self.tracer, light: self.light, shadows: self.settings.shadows, epsilon: self.epsilon }
    }

    /// Renders the `tw x th` tile at `(x0, y0)`. Heat maps trace it unit by unit so that each unit's counters
    /// can be shared among its own pixels; the units are exactly the pieces the method traces anyway.
    fn tile(&self, x0: u32, y0: u32, tw: u32, th: u32, scratch: &mut Scratch) -> TileOut {
        let view = self.settings.view;
        let mut out = TileOut::new((x0, y0), (tw, th), view);
        scratch.shadow.start_tile();
        if !view.is_heat_map() {
            // A partial tile at the image's edge keeps the whole tile's order.
            let offsets = self.offsets.iter().copied().filter(|&(dx, dy)| dx < tw && dy < th);
            self.block((x0, y0), (tw, th), offsets, self.order == RayOrder::Scanline, &mut out, scratch);
            return out;
        }
        let (uw, uh) = self.tracer.options.method.entry().unit_size(self.tracer.options.backend, self.tile);
        for uy in (0..th).step_by(uh as usize) {
            for ux in (0..tw).step_by(uw as usize) {
                let before = out.stats;
                let (bw, bh) = (uw.min(tw - ux), uh.min(th - uy));
                let rows = (0..bh).flat_map(|dy| (0..bw).map(move |dx| (dx, dy)));
                self.block((x0 + ux, y0 + uy), (bw, bh), rows, true, &mut out, scratch);
                let work = if view == FrameView::Nodes {
                    out.stats.nodes - before.nodes
                } else {
                    out.stats.isect_tests - before.isect_tests
                };
                let share = work as f32 / (bw * bh) as f32;
                for line in out.values.chunks_mut(tw as usize).skip(uy as usize).take(bh as usize) {
                    line[ux as usize..(ux + bw) as usize].fill(share);
                }
            }
        }
        out
    }

    /// Traces and shades the block of `(width, height)` pixels at `(x0, y0)`, its pixels visited at `offsets`
    /// (row by row when `rows`, else as one line in the given order), writing them into the tile `out`.
    fn block(
        &self,
        (x0, y0): (u32, u32),
        (bw, bh): (u32, u32),
        offsets: impl Iterator<Item = (u32, u32)>,
        rows: bool,
        out: &mut TileOut,
        sc: &mut Scratch,
    ) {
        let (scene, settings) = (self.scene, self.settings);
        let t0 = Instant::now();
        sc.pixels.clear();
        sc.pixels.extend(offsets.map(|(dx, dy)| (x0 + dx, y0 + dy)));
        sc.rays.clear();
        sc.rays.extend(sc.pixels.iter().map(|&(x, y)| Some(self.primary.primary(x, y))));
        let n = sc.rays.len();
        let (rw, rh) = if rows { (bw as usize, bh as usize) } else { (n, 1) };
        sc.hits.clear();
        sc.hits.resize(n, None);
        let tests_before = out.stats.isect_tests;
        self.tracer.intersect_tile(&sc.rays, rw, rh, &mut sc.hits, &mut out.stats);
        out.stages.primary += t0.elapsed().as_secs_f64();
        out.stages.primary_tests += out.stats.isect_tests - tests_before;

        let colors = match settings.view {
            FrameView::Normals | FrameView::Depth => Vec::new(),
            _ if self.shade_plain((rw, rh), out, sc) => return,
            _ => {
                sc.seeds.clear();
                sc.seeds.extend(sc.pixels.iter().map(|&(x, y)| y * self.width + x));
                let layer = whitted::Layer { rays: &sc.rays, hits: &sc.hits, dims: (rw, rh), seeds: &sc.seeds };
                self.shade_layer(layer, 0, out, &mut sc.shadow)
            }
        };
        let t = Instant::now();
        let hits = sc.pixels.iter().zip(&sc.rays).zip(&sc.hits).enumerate().filter_map(|(i, ((&p, r), h))| {
            let (Some(r), Some(h)) = (r, h) else { return None };
            Some((i, p, r, h))
        });
        match settings.view {
            FrameView::Normals => {
                for (_, p, r, h) in hits {
                    let k = out.index(p);
                    out.rgba[k] = to_display_rgba(shade::facing_normal(scene, r, h) * 0.5 + Vec3::splat(0.5));
                }
            }
            FrameView::Depth => {
                for (_, p, _, h) in hits {
                    let k = out.index(p);
                    out.values[k] = h.t;
                }
            }
            _ => {
                for (i, p, _, _) in hits {
                    let k = out.index(p);
                    out.rgba[k] = to_display_rgba(colors[i]);
                }
            }
        }
        out.stages.shading += t.elapsed().as_secs_f64();
    }
}
