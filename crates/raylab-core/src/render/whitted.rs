//! Shading a layer of hits and the reflection and refraction rays they spawn, recursively (Whitted ray
//! tracing with the fixed-function materials of Tsakok 2008, section 4.2.1 and Figure 3.2).
//!
//! The rays of a layer keep the block's layout, so a layer of secondary rays is traced as one tile by the
//! frame's method: neighbouring pixels' reflections form the omni-directional 2x2 packets that RTTest traces
//! secondary rays with (frustum methods fall back to packets, since secondary rays share no origin).
//! Reflection weights follow Schlick's Fresnel for the transparent-reflective kind, light inside a
//! transparent solid decays by Beer's law, and a refraction past the critical angle reflects instead.

use std::time::Instant;

use glam::Vec3;

use crate::ray::{Hit, Ray};
use crate::scene::MaterialKind;

use super::shade::{Surface, beer, reflect, refract, schlick};
use super::visibility::ShadowScratch;
use super::{TileContext, TileOut};

/// What a surface's secondary rays contribute: the weights of the local colour, the reflection and the
/// refraction, and the absorption of the medium each secondary ray travels through.
#[derive(Clone, Copy, Default)]
struct Mix {
    local: f32,
    reflect: f32,
    refract: f32,
    reflect_absorption: Vec3,
    refract_absorption: Vec3,
}

/// A block-shaped layer of rays traced together: the rays and their hits (`None` where there is no ray or
/// no hit), the block's `width x height`, and each ray's seed for light sampling (from its pixel).
pub(super) struct Layer<'a> {
    pub rays: &'a [Option<Ray>],
    pub hits: &'a [Option<Hit>],
    pub dims: (usize, usize),
    pub seeds: &'a [u32],
}

/// A layer of secondary rays in a block's layout, and what each carries.
struct Branch {
    rays: Vec<Option<Ray>>,
    seeds: Vec<u32>,
    absorption: Vec<Vec3>,
}

impl Branch {
    fn new(n: usize) -> Self {
        Self { rays: vec![None; n], seeds: vec![0; n], absorption: vec![Vec3::ZERO; n] }
    }
}

impl TileContext<'_> {
    /// Linear colours of a `width x height` layer of rays and their hits at recursion `depth` (0 for primary
    /// rays); misses are black. Secondary rays are spawned while `depth < max_depth`.
    pub(super) fn shade_layer(&self, layer: Layer, depth: u32, out: &mut TileOut, sc: &mut ShadowScratch) -> Vec<Vec3> {
        let Layer { rays, hits, dims, seeds } = layer;
        let scene = self.scene;
        let t0 = Instant::now();
        let surfaces: Vec<_> = rays
            .iter()
            .zip(hits)
            .map(|(r, h)| match (r, h) {
                (Some(r), Some(h)) => Some(Surface::at(scene, r, h)),
                _ => None,
            })
            .collect();
        let mut shading = t0.elapsed().as_secs_f64();
        let t_shadow = Instant::now();
        let vis = self.shadows().visibility(&surfaces, dims, seeds, &mut out.stats, sc);
        out.stages.shadow += t_shadow.elapsed().as_secs_f64();

        let t1 = Instant::now();
        let mut colors: Vec<Vec3> = surfaces
            .iter()
            .zip(rays)
            .zip(&vis)
            .map(|((s, r), &v)| match (s, r) {
                (Some(s), Some(r)) => s.local(r.dir, &self.light, v),
                _ => Vec3::ZERO,
            })
            .collect();
        let spawn = depth < self.settings.max_depth
            && surfaces.iter().flatten().any(|s| s.material.kind.reflects() || s.material.kind.refracts());
        let secondary = spawn.then(|| {
            let n = rays.len();
            let mut mixes = vec![Mix { local: 1.0, ..Mix::default() }; n];
            let (mut refl, mut refr) = (Branch::new(n), Branch::new(n));
            for i in 0..n {
                if let (Some(s), Some(r)) = (&surfaces[i], &rays[i]) {
                    mixes[i] = self.spawn(s, r, seeds[i], i, &mut refl, &mut refr);
                }
            }
            (mixes, refl, refr)
        });
        shading += t1.elapsed().as_secs_f64();

        if let Some((mixes, refl, refr)) = secondary {
            let reflected = self.trace_branch(&refl, dims, depth + 1, out, sc);
            let refracted = self.trace_branch(&refr, dims, depth + 1, out, sc);
            let t = Instant::now();
            for (i, (c, m)) in colors.iter_mut().zip(&mixes).enumerate() {
                let r = reflected.as_ref().map_or(Vec3::ZERO, |r| r[i]);
                let t = refracted.as_ref().map_or(Vec3::ZERO, |t| t[i]);
                *c = *c * m.local + r * m.reflect + t * m.refract;
            }
            shading += t.elapsed().as_secs_f64();
        }
        if depth == 0 {
            out.stages.shading += shading;
        } else {
            out.stages.secondary_shading += shading;
        }
        colors
    }

    /// Builds the secondary rays of surface `s` hit by `r` into slot `i` of the two branches and returns how
    /// its colour mixes them.
    fn spawn(&self, s: &Surface, r: &Ray, seed: u32, i: usize, refl: &mut Branch, refr: &mut Branch) -> Mix {
        let m = s.material;
        let (kr, kt) = (m.reflect_blend.clamp(0.0, 1.0), m.transmit_blend.clamp(0.0, 1.0));
        let above = s.point + s.geometric * self.epsilon;
        let below = s.point - s.geometric * self.epsilon;
        // The medium on the ray's side and behind the surface: inside a solid when leaving it.
        let (n_from, n_to) = if s.entering { (1.0, m.ior) } else { (m.ior, 1.0) };
        let inside = if s.entering { Vec3::ZERO } else { m.absorption };
        let behind = if s.entering { m.absorption } else { Vec3::ZERO };
        let mirror = reflect(r.dir, s.normal).normalize_or_zero();
        let put = |b: &mut Branch, ray: Ray, branch: u32| {
            b.rays[i] = Some(ray);
            b.seeds[i] = seed.wrapping_mul(0x2C1B_3C6D).wrapping_add(branch);
        };
        let mut mix = Mix { local: 1.0, ..Mix::default() };
        match m.kind {
            MaterialKind::Diffuse | MaterialKind::Specular => {}
            MaterialKind::Reflective if kr > 0.0 => {
                put(refl, Ray::new(above, mirror), 1);
                mix = Mix { local: 1.0 - kr, reflect: kr, reflect_absorption: inside, ..mix };
            }
            MaterialKind::Transparent if kt > 0.0 => {
                match refract(r.dir, s.normal, n_from / n_to) {
                    Some(d) => {
                        put(refr, Ray::new(below, d), 2);
                        mix = Mix { local: 1.0 - kt, refract: kt, refract_absorption: behind, ..mix };
                    }
                    // Total internal reflection: the transmitted share comes back as a reflection.
                    None => {
                        put(refl, Ray::new(above, mirror), 1);
                        mix = Mix { local: 1.0 - kt, reflect: kt, reflect_absorption: inside, ..mix };
                    }
                }
            }
            MaterialKind::TransparentReflective if kt > 0.0 || kr > 0.0 => {
                let fresnel = schlick(-r.dir.dot(s.normal), n_from, n_to);
                let f = kr + (1.0 - kr) * fresnel;
                let t = refract(r.dir, s.normal, n_from / n_to);
                let (f, t) = if t.is_none() { (1.0, None) } else { (f, t) };
                if f > 0.0 {
                    put(refl, Ray::new(above, mirror), 1);
                }
                if let Some(d) = t.filter(|_| f < 1.0) {
                    put(refr, Ray::new(below, d), 2);
                }
                mix = Mix {
                    local: 1.0 - kt,
                    reflect: kt * f,
                    refract: kt * (1.0 - f),
                    reflect_absorption: inside,
                    refract_absorption: behind,
                };
            }
            _ => {}
        }
        if refl.rays[i].is_some() {
            refl.absorption[i] = mix.reflect_absorption;
        }
        if refr.rays[i].is_some() {
            refr.absorption[i] = mix.refract_absorption;
        }
        mix
    }

    /// Traces one branch of secondary rays (timed as the secondary stage), shades the hits one level deeper,
    /// and applies Beer's law over each ray's length inside an absorbing solid; `None` when the branch is
    /// empty.
    fn trace_branch(
        &self,
        b: &Branch,
        dims: (usize, usize),
        depth: u32,
        out: &mut TileOut,
        sc: &mut ShadowScratch,
    ) -> Option<Vec<Vec3>> {
        if b.rays.iter().all(Option::is_none) {
            return None;
        }
        let t0 = Instant::now();
        let mut hits = vec![None; b.rays.len()];
        let tests_before = out.stats.isect_tests;
        self.tracer.intersect_tile(&b.rays, dims.0, dims.1, &mut hits, &mut out.stats);
        out.stages.secondary += t0.elapsed().as_secs_f64();
        out.stages.secondary_tests += out.stats.isect_tests - tests_before;
        let layer = Layer { rays: &b.rays, hits: &hits, dims, seeds: &b.seeds };
        let mut colors = self.shade_layer(layer, depth, out, sc);
        for ((c, h), a) in colors.iter_mut().zip(&hits).zip(&b.absorption) {
            if let Some(h) = h {
                *c *= beer(*a, h.t);
            }
        }
        Some(colors)
    }
}
