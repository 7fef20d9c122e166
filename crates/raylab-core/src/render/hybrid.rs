//! The CPU half of G-buffer ray tracing (seed 003, Stokes 2014, chapter 3): the GPU rasterises the primary
//! visibility into a G-buffer, and the CPU only traces the reflection rays of reflective pixels, shading their
//! hits exactly as the Whitted renderer shades a first reflection (local light under the frame's shadow
//! technique, no deeper rays). [`reference_reflections`] is that renderer's own answer for the same view, which
//! the hybrid mode is checked against.

use glam::Vec3;
use rayon::prelude::*;

use crate::ray::{Hit, Ray};
use crate::scene::{Camera, PointLight, Scene};
use crate::stats::TraversalStats;
use crate::trace::Tracer;

use super::shade::{Surface, reflect};
use super::visibility::ShadowScratch;
use super::whitted::Layer;
use super::{RenderSettings, StageTimes, TileContext, TileOut, surface_epsilon};

/// One G-buffer pixel as the CPU needs it: only reflective pixels cast a ray, from their position along the
/// mirror of the view direction about their normal.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GPixel {
    /// World position of the surface seen.
    pub position: Vec3,
    /// Unit shading normal, turned toward the viewer.
    pub normal: Vec3,
    /// Whether the surface reflects (its material's reflection weight is above 0); false for the background.
    pub reflective: bool,
}

/// The reflection ray of a G-buffer pixel seen from `eye` (`None` for the background or a surface that does
/// not reflect): it leaves `epsilon` above the surface along the normal, in the mirror direction.
pub fn reflection_ray(eye: Vec3, px: &GPixel, epsilon: f32) -> Option<Ray> {
    if !px.reflective || !px.position.is_finite() {
        return None;
    }
    let d = (px.position - eye).normalize_or_zero();
    let mirror = reflect(d, px.normal).normalize_or_zero();
    (d != Vec3::ZERO && mirror != Vec3::ZERO).then(|| Ray::new(px.position + px.normal * epsilon, mirror))
}

/// The seed of pixel `index`'s reflection ray, as the Whitted renderer derives it (its light samples).
pub fn reflection_seed(index: u32) -> u32 {
    index.wrapping_mul(0x2C1B_3C6D).wrapping_add(1)
}

/// Rays per set below which the non-DACRT methods stop splitting a frame's reflection rays among threads.
const MIN_CHUNK: usize = 256;

/// Linear colours of a `width x height` layer of reflection rays (one slot per pixel, `None` where none is
/// traced), traced with `tracer` and shaded one bounce deep under `settings.shadows`; black where there is no
/// ray or no hit. The per-pixel form of [`shade_reflection_set`]. Returns the colours, the work and the time
/// per stage.
pub fn shade_reflections(
    scene: &Scene,
    tracer: &Tracer,
    camera: &Camera,
    light: PointLight,
    settings: &RenderSettings,
    rays: &[Option<Ray>],
) -> (Vec<Vec3>, TraversalStats, StageTimes) {
    let (w, h) = (settings.width.max(1), settings.height.max(1));
    assert_eq!(rays.len(), (w * h) as usize, "one ray slot per pixel");
    let set: Vec<(u32, Ray)> = rays.iter().enumerate().filter_map(|(i, r)| r.map(|r| (i as u32, r))).collect();
    let (found, stats, stages) = shade_reflection_set(scene, tracer, camera, light, settings, &set);
    let mut colors = vec![Vec3::ZERO; rays.len()];
    for (&(i, _), c) in set.iter().zip(found) {
        colors[i as usize] = c;
    }
    (colors, stats, stages)
}

/// Linear colours of the reflection rays `set` (each with the index of its pixel in the `width x height`
/// layer of `settings`, which seeds its light samples), traced with `tracer` and shaded one bounce deep under
/// `settings.shadows`, in the order of `set`; black where a ray hits nothing. The rays are cut into sets
/// shared among the threads of the current rayon pool (for the methods that ask for it, at least
/// [`min_tile_rays`](crate::method::MethodEntry::min_tile_rays) rays a set: DACRT divides its triangles
/// again for every set).
/// The hybrid mode passes only its reflective pixels, so its cost follows their number rather than the
/// G-buffer's size.
pub fn shade_reflection_set(
    scene: &Scene,
    tracer: &Tracer,
    camera: &Camera,
    light: PointLight,
    settings: &RenderSettings,
    set: &[(u32, Ray)],
) -> (Vec<Vec3>, TraversalStats, StageTimes) {
    let (w, h) = (settings.width.max(1), settings.height.max(1));
    let threads = rayon::current_num_threads().max(1);
    let min_set = tracer.options.method.entry().min_tile_rays().map_or(MIN_CHUNK, |n| n as usize);
    let chunk = set.len().div_ceil(threads).max(min_set).max(1);
    let one_bounce = RenderSettings { max_depth: 1, ..*settings };
    let ctx = TileContext {
        scene,
        tracer,
        primary: camera.raster(w, h).grid(),
        light,
        settings: &one_bounce,
        width: w,
        epsilon: surface_epsilon(scene),
        order: crate::ray_order::RayOrder::Scanline,
        tile: settings.tile,
        offsets: Vec::new(),
        plain: super::plain::PlainMaterials::of(scene),
    };
    let sets: Vec<(Vec<Vec3>, TileOut)> = set
        .par_chunks(chunk)
        .map(|part| {
            let rays: Vec<Option<Ray>> = part.iter().map(|&(_, r)| Some(r)).collect();
            let seeds: Vec<u32> = part.iter().map(|&(i, _)| reflection_seed(i)).collect();
            let mut out = TileOut::default();
            let t0 = std::time::Instant::now();
            let mut hits = vec![None; rays.len()];
            tracer.intersect_tile(&rays, rays.len(), 1, &mut hits, &mut out.stats);
            out.stages.secondary += t0.elapsed().as_secs_f64();
            out.stages.secondary_tests += out.stats.isect_tests;
            let layer = Layer { rays: &rays, hits: &hits, dims: (rays.len(), 1), seeds: &seeds };
            let colors = ctx.shade_layer(layer, 1, &mut out, &mut ShadowScratch::default());
            (colors, out)
        })
        .collect();
    let mut colors = Vec::with_capacity(set.len());
    let (mut stats, mut stages) = (TraversalStats::default(), StageTimes::default());
    for (c, out) in sets {
        colors.extend(c);
        stats += out.stats;
        stages += out.stages;
    }
    (colors, stats, stages)
}

/// Each pixel's primary hit (`None` for a miss), traced with `tracer` on the current rayon pool.
fn primary_surfaces(tracer: &Tracer, camera: &Camera, w: u32, h: u32) -> Vec<Option<(Ray, Hit)>> {
    let raster = camera.raster(w, h);
    (0..h)
        .into_par_iter()
        .flat_map_iter(|y| {
            let rays: Vec<Option<Ray>> = (0..w).map(|x| Some(raster.primary(x, y))).collect();
            let mut hits: Vec<Option<Hit>> = vec![None; rays.len()];
            tracer.intersect_tile(&rays, w as usize, 1, &mut hits, &mut TraversalStats::default());
            rays.into_iter().zip(hits).map(|(r, h)| r.zip(h)).collect::<Vec<_>>()
        })
        .collect()
}

/// The G-buffer the CPU renderer would see: each pixel's primary hit as a [`GPixel`] (reflective where the
/// material reflects, with the Whitted renderer's shading normal), traced on the current rayon pool.
pub fn cpu_gbuffer(scene: &Scene, tracer: &Tracer, camera: &Camera, width: u32, height: u32) -> Vec<GPixel> {
    primary_surfaces(tracer, camera, width, height)
        .into_iter()
        .map(|p| {
            let Some((r, h)) = p else { return GPixel::default() };
            let s = Surface::at(scene, &r, &h);
            GPixel {
                position: s.point,
                normal: s.normal,
                reflective: s.material.kind.reflects() && s.material.reflect_blend > 0.0,
            }
        })
        .collect()
}

/// The Whitted renderer's first-reflection colour of each pixel of the view (`None` where the primary ray
/// misses or hits a surface that does not reflect), with that renderer's own reflection rays (leaving along
/// the geometric normal): what the hybrid mode must reproduce.
pub fn reference_reflections(
    scene: &Scene,
    tracer: &Tracer,
    camera: &Camera,
    light: PointLight,
    settings: &RenderSettings,
) -> Vec<Option<Vec3>> {
    let (w, h) = (settings.width.max(1), settings.height.max(1));
    let eps = surface_epsilon(scene);
    let rays: Vec<Option<Ray>> = primary_surfaces(tracer, camera, w, h)
        .into_iter()
        .map(|p| {
            let (r, h) = p?;
            let s = Surface::at(scene, &r, &h);
            let reflects = s.material.kind.reflects() && s.material.reflect_blend > 0.0;
            let mirror = reflect(r.dir, s.normal).normalize_or_zero();
            reflects.then(|| Ray::new(s.point + s.geometric * eps, mirror))
        })
        .collect();
    let (colors, _, _) = shade_reflections(scene, tracer, camera, light, settings, &rays);
    rays.iter().zip(colors).map(|(r, c)| r.map(|_| c)).collect()
}

/// Peak signal-to-noise ratio in dB of pairs of linear colours, compared as the 8-bit display values they
/// become ([`super::shade::to_display`]); infinite when they are all equal, `None` for no pairs.
pub fn psnr(pairs: impl IntoIterator<Item = (Vec3, Vec3)>) -> Option<f64> {
    let (mut sum, mut n) = (0.0f64, 0usize);
    for (a, b) in pairs {
        for k in 0..3 {
            let d = super::shade::to_display(a[k]) as f64 - super::shade::to_display(b[k]) as f64;
            sum += d * d;
        }
        n += 3;
    }
    (n > 0).then(|| if sum == 0.0 { f64::INFINITY } else { 10.0 * (255.0f64 * 255.0 / (sum / n as f64)).log10() })
}
