//! The distribution ray tracer that makes the MBVH RS paper's incoherent workload (Tsakok 2009, section 4):
//! 16 paths per pixel from stratified samples, a thin-lens camera (depth of field), soft shadows from the
//! spherical light, glossy (Phong-lobe) reflections, 1 to 7 bounces, and progressive accumulation.
//!
//! Paths are traced bounce by bounce: the rays of one bounce for a whole tile (every pixel's 16 samples) form
//! one layer, traced with the frame's method in a single call, so a tile is a ray group for MBVH RS and the
//! time and ray count of each bounce are measured apart (the paper's Figures 2-3). Everything random is a hash
//! of the pixel, sample, bounce and pass, so every method traces exactly the same rays.

mod sampling;

use std::time::Instant;

use glam::{Vec2, Vec3};
use rayon::prelude::*;
use serde::Serialize;

use crate::ray::{Hit, Ray};
use crate::render::shade::{Surface, reflect, to_display};
use crate::render::surface_epsilon;
use crate::scene::{Camera, MaterialKind, PointLight, Scene};
use crate::stats::TraversalStats;
use crate::trace::Tracer;
use sampling::{Rng, disc, phong_lobe};

/// Share of the light a surface passes on along a path (white surfaces would otherwise never darken).
const REFLECTANCE: f32 = 0.6;

/// Settings of the distribution ray tracer.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct DistributionSettings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Tile edge; a tile's paths form one ray group per bounce.
    pub tile: u32,
    /// Paths per pixel and pass (stratified on a square grid when a square number).
    pub spp: u32,
    /// Bounces after the primary hit (1 to 7 in the paper).
    pub bounces: u32,
    /// Phong exponent of the glossy lobe.
    pub glossy_exponent: f32,
    /// Make every surface glossy-reflective (the paper's benchmark configuration); otherwise only the
    /// reflective materials are, and the others scatter diffusely.
    pub all_glossy: bool,
}

impl Default for DistributionSettings {
    fn default() -> Self {
        Self { width: 512, height: 512, tile: 8, spp: 16, bounces: 3, glossy_exponent: 64.0, all_glossy: true }
    }
}

/// Rays and seconds of one bounce (0: camera rays), summed over threads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct BounceStats {
    /// Closest-hit rays traced.
    pub rays: u64,
    /// Shadow rays traced toward the light from this bounce's hits.
    pub shadow_rays: u64,
    /// Thread-summed seconds of the closest-hit tracing.
    pub seconds: f64,
    /// Thread-summed seconds of the shadow tracing.
    pub shadow_seconds: f64,
    /// Counters of the closest-hit rays.
    pub stats: TraversalStats,
    /// Counters of the shadow rays.
    pub shadow_stats: TraversalStats,
}

/// A progressively refined image: linear colour sums and the number of passes in them.
#[derive(Clone, Debug)]
pub struct Accumulator {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Per pixel, the sum of every path's radiance so far.
    pub sum: Vec<Vec3>,
    /// Paths per pixel accumulated.
    pub paths: u32,
}

impl Accumulator {
    /// An empty image.
    pub fn new(width: u32, height: u32) -> Self {
        Self { width, height, sum: vec![Vec3::ZERO; (width * height) as usize], paths: 0 }
    }

    /// The mean so far as display RGBA8 (gamma 2.2).
    pub fn rgba(&self) -> Vec<[u8; 4]> {
        let k = 1.0 / self.paths.max(1) as f32;
        self.sum.iter().map(|c| [to_display(c.x * k), to_display(c.y * k), to_display(c.z * k), 255]).collect()
    }
}

/// One pass: `settings.spp` paths per pixel added to `acc`; `pass` seeds the samples (pass `k` of a
/// progressive render). Returns the work per bounce.
pub fn render_pass(
    scene: &Scene,
    tracer: &Tracer,
    camera: &Camera,
    light: PointLight,
    settings: &DistributionSettings,
    pass: u32,
    acc: &mut Accumulator,
) -> Vec<BounceStats> {
    let (w, h) = (settings.width.max(1), settings.height.max(1));
    assert!(acc.width == w && acc.height == h, "accumulator size");
    let tile = tracer.options.method.entry().tile_edge(settings.tile, settings.spp);
    let ctx =
        Pass { scene, tracer, raster: camera.raster(w, h), light, settings, pass, epsilon: surface_epsilon(scene) };
    let tiles: Vec<(u32, u32)> =
        (0..h.div_ceil(tile)).flat_map(|ty| (0..w.div_ceil(tile)).map(move |tx| (tx * tile, ty * tile))).collect();
    // One tile per job, so that the threads share out the costly parts of the image (as `render` does).
    let done: Vec<TileResult> = tiles
        .par_iter()
        .with_max_len(1)
        .map(|&(x0, y0)| ctx.tile(x0, y0, tile.min(w - x0), tile.min(h - y0)))
        .collect();
    let mut per_bounce = vec![BounceStats::default(); settings.bounces as usize + 1];
    for (pixels, bounces) in done {
        for (i, c) in pixels {
            acc.sum[i as usize] += c;
        }
        for (a, b) in per_bounce.iter_mut().zip(bounces) {
            a.rays += b.rays;
            a.shadow_rays += b.shadow_rays;
            a.seconds += b.seconds;
            a.shadow_seconds += b.shadow_seconds;
            a.stats += b.stats;
            a.shadow_stats += b.shadow_stats;
        }
    }
    acc.paths += settings.spp.max(1);
    per_bounce
}

/// What a tile gives back: each pixel's summed radiance, and the work per bounce.
type TileResult = (Vec<(u32, Vec3)>, Vec<BounceStats>);

struct Pass<'a> {
    scene: &'a Scene,
    tracer: &'a Tracer<'a>,
    raster: crate::scene::CameraRaster,
    light: PointLight,
    settings: &'a DistributionSettings,
    pass: u32,
    epsilon: f32,
}

impl Pass<'_> {
    /// Traces every path of a tile, bounce by bounce; returns each pixel's summed radiance and the work.
    fn tile(&self, x0: u32, y0: u32, tw: u32, th: u32) -> TileResult {
        let spp = self.settings.spp.max(1);
        let g = (spp as f64).sqrt() as u32;
        let (gx, gy) = if g * g == spp { (g, g) } else { (spp, 1) };
        // Layer layout: each pixel's samples as a gx x gy block, so packets hold one pixel's samples.
        let (lw, lh) = ((tw * gx) as usize, (th * gy) as usize);
        let n = lw * lh;
        let mut pixel_of = vec![0u32; n];
        let mut rays: Vec<Option<Ray>> = vec![None; n];
        let mut rngs: Vec<Rng> = Vec::with_capacity(n);
        for ly in 0..lh {
            for lx in 0..lw {
                let (px, py) = (x0 + lx as u32 / gx, y0 + ly as u32 / gy);
                let (sx, sy) = (lx as u32 % gx, ly as u32 % gy);
                let index = py * self.settings.width + px;
                let mut rng = Rng::new(index, sy * gx + sx, self.pass);
                let jitter = Vec2::new((sx as f32 + rng.next()) / gx as f32, (sy as f32 + rng.next()) / gy as f32);
                let lens = disc(Vec2::new(rng.next(), rng.next()));
                let k = ly * lw + lx;
                pixel_of[k] = index;
                rays[k] = Some(self.raster.lens_ray(px as f64 + jitter.x as f64, py as f64 + jitter.y as f64, lens));
                rngs.push(rng);
            }
        }
        let mut radiance = vec![Vec3::ZERO; n];
        let mut throughput = vec![Vec3::ONE; n];
        let mut hits: Vec<Option<Hit>> = vec![None; n];
        let mut shadow: Vec<Option<Ray>> = vec![None; n];
        let mut blocked = vec![false; n];
        let mut bounces = Vec::with_capacity(self.settings.bounces as usize + 1);
        for bounce in 0..=self.settings.bounces {
            let mut b = BounceStats::default();
            let t0 = Instant::now();
            hits.iter_mut().for_each(|h| *h = None);
            self.tracer.intersect_tile(&rays, lw, lh, &mut hits, &mut b.stats);
            b.seconds = t0.elapsed().as_secs_f64();
            b.rays = rays.iter().filter(|r| r.is_some()).count() as u64;
            let surfaces: Vec<Option<Surface>> = rays
                .iter()
                .zip(&hits)
                .map(|(r, h)| match (r, h) {
                    (Some(r), Some(h)) => Some(Surface::at(self.scene, r, h)),
                    _ => None,
                })
                .collect();
            // Direct light: one shadow ray per hit to a random point on the light's disc.
            for k in 0..n {
                shadow[k] = surfaces[k].as_ref().and_then(|s| {
                    let target = self.light_point(s.point, &mut rngs[k]);
                    crate::render::shade::shadow_ray(s, self.light.position, target, self.epsilon)
                });
            }
            let t1 = Instant::now();
            blocked.iter_mut().for_each(|x| *x = false);
            if shadow.iter().any(Option::is_some) {
                self.tracer.occluded_tile(&shadow, lw, lh, None, &mut blocked, &mut b.shadow_stats);
            }
            b.shadow_seconds = t1.elapsed().as_secs_f64();
            b.shadow_rays = shadow.iter().filter(|r| r.is_some()).count() as u64;
            // Shade and continue the paths.
            for k in 0..n {
                let (Some(r), Some(s)) = (rays[k], &surfaces[k]) else {
                    rays[k] = None;
                    continue;
                };
                let visible = if shadow[k].is_some() && !blocked[k] { 1.0 } else { 0.0 };
                let mut local = s.local(r.dir, &self.light, visible);
                if bounce > 0 {
                    // The ambient term stands for all indirect light; later vertices add their own.
                    local -= s.albedo * crate::render::shade::AMBIENT;
                }
                radiance[k] += throughput[k] * local;
                rays[k] = (bounce < self.settings.bounces)
                    .then(|| self.scatter(s, &r, &mut rngs[k], &mut throughput[k]))
                    .flatten();
            }
            bounces.push(b);
        }
        let mut pixels: Vec<(u32, Vec3)> = Vec::with_capacity((tw * th) as usize);
        for (k, &p) in pixel_of.iter().enumerate() {
            match pixels.last_mut() {
                Some(last) if last.0 == p => last.1 += radiance[k],
                _ => pixels.push((p, radiance[k])),
            }
        }
        (pixels, bounces)
    }

    /// A point on the disc of the spherical light facing `from`.
    fn light_point(&self, from: Vec3, rng: &mut Rng) -> Vec3 {
        let c = self.light.position;
        let axis = (c - from).normalize_or_zero();
        if self.light.radius <= 0.0 || axis == Vec3::ZERO {
            return c;
        }
        let (u, v) = axis.any_orthonormal_pair();
        let d = disc(Vec2::new(rng.next(), rng.next())) * self.light.radius;
        c + u * d.x + v * d.y
    }

    /// The next ray of a path at surface `s`: a glossy Phong lobe about the mirror direction for glossy
    /// surfaces, a cosine-weighted diffuse bounce otherwise; `throughput` takes the surface's colour.
    fn scatter(&self, s: &Surface, r: &Ray, rng: &mut Rng, throughput: &mut Vec3) -> Option<Ray> {
        let glossy = self.settings.all_glossy || s.material.kind == MaterialKind::Reflective;
        let u = Vec2::new(rng.next(), rng.next());
        let dir = if glossy {
            phong_lobe(reflect(r.dir, s.normal).normalize_or_zero(), self.settings.glossy_exponent, u)
        } else {
            phong_lobe(s.normal, 1.0, u)
        };
        if dir.dot(s.geometric) <= 0.0 {
            return None; // sampled below the surface: the path ends
        }
        *throughput *= s.albedo * REFLECTANCE;
        if throughput.max_element() <= 1e-4 {
            return None;
        }
        Some(Ray::new(s.point + s.geometric * self.epsilon, dir))
    }
}
