//! Shading a layer of plain surfaces a vector of hits at a time: where every hit of a block is diffuse and
//! untextured (the thesis's benchmark shading, 4.2.1: one point light, Lambert, no secondary rays) and the
//! frame's shadows come from one segment per point to the light's centre (hard shadows, the shadow cache,
//! edge widths) or are off, the surfaces, their shadow segments and their colours are computed in
//! structure-of-arrays form with the backend's vectors instead of hit by hit.
//!
//! Every lane performs the operations of [`Surface::at`](super::shade::Surface::at),
//! [`shadow_ray`](super::shade::shadow_ray) and [`Surface::local`](super::shade::Surface::local) in their
//! order (glam's `Vec3` is scalar, and nothing is fused), so the colours are those of the per-hit path to
//! the bit; only the bookkeeping differs: the per-hit path builds a `Surface` per hit, collects it, and walks
//! the collections once per stage, which cost about as much as the arithmetic.

use std::time::Instant;

use glam::Vec3;
use raylab_simd::{Kernel, VMask, Vf32};

use crate::packet::{MAX_LANES, dot3, map3};
use crate::ray::{Hit, Ray};
use crate::scene::{Material, MaterialKind, PointLight, Scene};
use crate::shadow::Shadows;

use super::shade::{AMBIENT, DIRECT, to_display_rgba};
use super::{Scratch, TileContext, TileOut};

impl TileContext<'_> {
    /// Shades a block's primary rays and their hits (`sc.rays`, `sc.hits`: a `width x height` layer, pixel
    /// `i` at image position `sc.pixels[i]`) into the tile `out` and returns true, when every hit is on a
    /// plain surface ([`is_plain`]) and the frame's shadows trace one segment per point to the light's
    /// centre (hard, cached, edge widths; `ShadowTracer::segment_visibility`) or are off; returns false
    /// otherwise, and the caller shades the layer hit by hit (`shade_layer`). The same pixels either way, for
    /// fewer instructions: the lanes share each operation.
    pub(super) fn shade_plain(&self, dims: (usize, usize), out: &mut TileOut, sc: &mut Scratch) -> bool {
        let shadowed = match self.settings.shadows {
            Shadows::None => false,
            Shadows::MultiSample { .. } => return false,
            Shadows::Hard | Shadows::Cached | Shadows::EdgeWidth { .. } => true,
        };
        let check = match self.plain {
            PlainMaterials::All => false,
            PlainMaterials::Some => true,
            PlainMaterials::None => return false,
        };
        let Scratch { pixels, rays, hits, plain, shadow, .. } = sc;
        let (scene, backend) = (self.scene, self.tracer.options.backend);
        let (light, epsilon) = (self.light.position, self.epsilon);
        let t0 = Instant::now();
        let segments = shadowed.then_some(&mut shadow.rays);
        let kernel = Surfaces { scene, rays, hits, light, epsilon, segments, check, sc: &mut *plain };
        if !raylab_simd::dispatch(backend, kernel) {
            return false;
        }
        let mut shading = t0.elapsed().as_secs_f64();
        if shadowed {
            let t = Instant::now();
            let visible = self.shadows().segment_visibility(dims, &mut out.stats, shadow);
            plain.visible[..visible.len()].copy_from_slice(&visible);
            out.stages.shadow += t.elapsed().as_secs_f64();
        } else {
            plain.set_visible_where_hit(hits);
        }
        let t1 = Instant::now();
        raylab_simd::dispatch(backend, Colours { n: hits.len(), light: &self.light, sc: &mut *plain });
        let [r, g, b] = &plain.colour;
        for (i, &p) in pixels.iter().enumerate() {
            let k = out.index(p);
            out.rgba[k] = to_display_rgba(Vec3::new(r[i], g[i], b[i]));
        }
        shading += t1.elapsed().as_secs_f64();
        out.stages.shading += shading;
        true
    }
}

/// Which of a scene's materials are plain ([`is_plain`]), found once per frame: with all of them, the plain
/// path looks at no hit's material; with none, it is not tried.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum PlainMaterials {
    All,
    Some,
    None,
}

impl PlainMaterials {
    /// The plain materials of `scene`.
    pub(super) fn of(scene: &Scene) -> Self {
        let plain = scene.materials.iter().filter(|m| is_plain(m)).count();
        match plain {
            0 => Self::None,
            n if n == scene.materials.len() => Self::All,
            _ => Self::Some,
        }
    }
}

/// True for a plain material: diffuse and without textures, so a surface's colour is its base colour and it
/// spawns no secondary ray.
#[inline(always)]
fn is_plain(m: &Material) -> bool {
    m.kind == MaterialKind::Diffuse && m.diffuse_texture.is_none() && m.normal_texture.is_none()
}

/// A layer's plain surfaces in structure-of-arrays form, one entry per pixel of the layer (padded to whole
/// vectors), kept between the shadow rays and the colours; reused from block to block.
#[derive(Default)]
pub(super) struct PlainScratch {
    /// Hit points, one buffer per axis.
    point: [Vec<f32>; 3],
    /// Shading normals, turned toward the viewer.
    normal: [Vec<f32>; 3],
    /// Albedo (the material's base colour).
    albedo: [Vec<f32>; 3],
    /// Per pixel, how much of the light reaches it, in `[0, 1]`.
    visible: Vec<f32>,
    /// Linear colours, one buffer per channel: black where there is no hit.
    colour: [Vec<f32>; 3],
}

impl PlainScratch {
    /// Sizes the buffers for `n` pixels, padded to whole vectors of the widest backend.
    fn reset(&mut self, n: usize) {
        let padded = n.div_ceil(MAX_LANES) * MAX_LANES;
        for b in self.point.iter_mut().chain(&mut self.normal).chain(&mut self.albedo).chain(&mut self.colour) {
            b.clear();
            b.resize(padded, 0.0);
        }
        self.visible.clear();
        self.visible.resize(padded, 0.0);
    }

    /// Every pixel with a hit sees the whole light (shadows off).
    fn set_visible_where_hit(&mut self, hits: &[Option<Hit>]) {
        for (v, h) in self.visible.iter_mut().zip(hits) {
            *v = if h.is_some() { 1.0 } else { 0.0 };
        }
    }
}

/// The surfaces of a layer's hits (`rays[i]` hit `hits[i]`, all plain), written into the scratch buffers,
/// and, into `segments` when it is given, each surface's shadow segment to the light's centre (`None`
/// where there is no hit or the surface faces away from the light).
struct Surfaces<'a> {
    scene: &'a Scene,
    rays: &'a [Option<Ray>],
    hits: &'a [Option<Hit>],
    light: Vec3,
    epsilon: f32,
    segments: Option<&'a mut Vec<Option<Ray>>>,
    /// Whether to check each hit's material (some of the scene's are not plain).
    check: bool,
    sc: &'a mut PlainScratch,
}

impl Kernel for Surfaces<'_> {
    /// False, with the buffers half written, when some hit's surface is not plain.
    type Output = bool;

    #[inline(always)]
    fn run<V: Vf32>(self) -> bool {
        let Surfaces { scene, rays, hits, light, epsilon, mut segments, check, sc } = self;
        sc.reset(rays.len());
        if let Some(out) = segments.as_deref_mut() {
            out.clear();
            out.resize(rays.len(), None);
        }
        let (zero, one) = (V::splat(0.0), V::splat(1.0));
        let interpolate = !scene.normals.is_empty();
        // Each lane's ray and hit, and the triangle's face normal, material colour and vertex normals:
        // quantity `q` of lane `i` in `lanes[q][i]` (see `QUANTITIES`). Lanes without a hit keep an earlier
        // vector's values, whose results no one reads.
        let mut lanes = [[0.0f32; MAX_LANES]; QUANTITIES];
        for base in (0..rays.len()).step_by(V::LANES) {
            let mut present = 0u32;
            for i in 0..V::LANES.min(rays.len() - base) {
                let (Some(r), Some(h)) = (&rays[base + i], &hits[base + i]) else { continue };
                present |= 1 << i;
                let tri = &scene.triangles[h.tri as usize];
                let material = &scene.materials[tri.material as usize];
                if check && !is_plain(material) {
                    return false;
                }
                let face = scene.geometric_normal(h.tri as usize);
                let albedo = material.base_color;
                put(&mut lanes, i, 0, r.origin);
                put(&mut lanes, i, 3, r.dir);
                put(&mut lanes, i, 6, Vec3::new(h.t, h.u, h.v));
                put(&mut lanes, i, 9, face);
                put(&mut lanes, i, 12, albedo);
                if interpolate {
                    let [i0, i1, i2] = tri.v;
                    put(&mut lanes, i, 15, scene.normals[i0 as usize]);
                    put(&mut lanes, i, 18, scene.normals[i1 as usize]);
                    put(&mut lanes, i, 21, scene.normals[i2 as usize]);
                }
            }
            if present == 0 {
                continue;
            }
            let (org, dir) = (quantity3::<V>(&lanes, 0), quantity3::<V>(&lanes, 3));
            let [t, u, v] = quantity3::<V>(&lanes, 6);
            let face = quantity3::<V>(&lanes, 9);
            // Turned toward the side the ray came from (`Surface::at`).
            let entering = dot3(&face, &dir).lt(zero);
            let geometric = map3([0, 1, 2], |k| V::select(entering, face[k], negate(face[k])));
            // The interpolated normal, normalised, or the face normal where it vanishes
            // (`Scene::shading_normal`).
            let mut normal = face;
            if interpolate {
                let w = one - u - v;
                let (n0, n1, n2) = (quantity3::<V>(&lanes, 15), quantity3::<V>(&lanes, 18), quantity3::<V>(&lanes, 21));
                let n = [
                    n0[0] * w + n1[0] * u + n2[0] * v,
                    n0[1] * w + n1[1] * u + n2[1] * v,
                    n0[2] * w + n1[2] * u + n2[2] * v,
                ];
                let rcp = one / dot3(&n, &n).sqrt();
                let usable = rcp.abs().lt(V::splat(f32::INFINITY)) & rcp.gt(zero);
                normal = map3([0, 1, 2], |k| V::select(usable, n[k] * rcp, face[k]));
            }
            let behind = dot3(&normal, &geometric).lt(zero);
            let normal = map3([0, 1, 2], |k| V::select(behind, negate(normal[k]), normal[k]));
            let point = map3([0, 1, 2], |k| org[k] + dir[k] * t);
            // Lanes without a hit get no albedo, so their colour is black whatever their stale values.
            let hit = V::Mask::from_bits(present);
            for k in 0..3 {
                point[k].write_to(&mut sc.point[k][base..base + V::LANES]);
                normal[k].write_to(&mut sc.normal[k][base..base + V::LANES]);
                V::select(hit, quantity::<V>(&lanes, 12 + k), zero).write_to(&mut sc.albedo[k][base..base + V::LANES]);
            }
            if let Some(out) = segments.as_deref_mut() {
                write_segments(&point, &geometric, &normal, light, epsilon, hit, &mut out[base..]);
            }
        }
        true
    }
}

/// The shadow segments of one vector of surfaces to `light` (`shadow_ray` with the light's centre as the
/// target), for the lanes of `lit`; a lane whose surface faces away from the light, or whose segment is
/// empty or infinite, gets none.
#[inline(always)]
fn write_segments<V: Vf32>(
    point: &[V; 3],
    geometric: &[V; 3],
    normal: &[V; 3],
    light: Vec3,
    epsilon: f32,
    lit: V::Mask,
    out: &mut [Option<Ray>],
) {
    let c = [V::splat(light.x), V::splat(light.y), V::splat(light.z)];
    let to_light = map3([0, 1, 2], |k| c[k] - point[k]);
    let faces_away = (dot3(normal, &to_light) * dot3(normal, geometric)).le(V::splat(0.0));
    let eps = V::splat(epsilon);
    let q = map3([0, 1, 2], |k| point[k] + geometric[k] * eps);
    let v = map3([0, 1, 2], |k| c[k] - q[k]);
    let d = dot3(&v, &v).sqrt();
    let dir = map3([0, 1, 2], |k| v[k] / d);
    let ok = lit & !faces_away & d.gt(V::splat(0.0)) & d.abs().lt(V::splat(f32::INFINITY));
    let bits = ok.bits();
    let mut rows = [[0.0f32; MAX_LANES]; 7];
    for (row, x) in rows.iter_mut().zip([q[0], q[1], q[2], dir[0], dir[1], dir[2], d]) {
        x.write_to(&mut row[..V::LANES]);
    }
    for (i, o) in out.iter_mut().take(V::LANES).enumerate() {
        *o = (bits >> i & 1 == 1).then(|| {
            let origin = Vec3::new(rows[0][i], rows[1][i], rows[2][i]);
            Ray::segment(origin, Vec3::new(rows[3][i], rows[4][i], rows[5][i]), 0.0, rows[6][i])
        });
    }
}

/// The colours of a layer's `n` plain surfaces (from [`Surfaces`]) lit by `light` with the scratch's
/// visibility, into the scratch's colour buffers: `albedo * (ambient + direct * N.L * attenuation *
/// visibility)` as [`Surface::local`] computes it for a diffuse material; black where there is no hit (no
/// albedo there).
///
/// [`Surface::local`]: super::shade::Surface::local
struct Colours<'a> {
    n: usize,
    light: &'a PointLight,
    sc: &'a mut PlainScratch,
}

impl Kernel for Colours<'_> {
    type Output = ();

    #[inline(always)]
    fn run<V: Vf32>(self) {
        let Colours { n, light, sc } = self;
        let (zero, one) = (V::splat(0.0), V::splat(1.0));
        let lp = [V::splat(light.position.x), V::splat(light.position.y), V::splat(light.position.z)];
        let (c0, c1, c2) = (V::splat(light.constant), V::splat(light.linear), V::splat(light.quadratic));
        for base in (0..n).step_by(V::LANES) {
            let point = [load::<V>(&sc.point[0], base), load::<V>(&sc.point[1], base), load::<V>(&sc.point[2], base)];
            let normal =
                [load::<V>(&sc.normal[0], base), load::<V>(&sc.normal[1], base), load::<V>(&sc.normal[2], base)];
            let to_light = map3([0, 1, 2], |k| lp[k] - point[k]);
            let dist = dot3(&to_light, &to_light).sqrt();
            let away = dist.gt(zero);
            let l = map3([0, 1, 2], |k| V::select(away, to_light[k] / dist, normal[k]));
            let ndl = dot3(&normal, &l);
            // `f32::max(ndl, 0.0)`: NaN and negative cosines give 0.
            let ndl = V::select(ndl.gt(zero), ndl, zero);
            let denom = c0 + c1 * dist + c2 * dist * dist;
            let attenuation = V::select(denom.gt(one), one / denom, one);
            let lit = load::<V>(&sc.visible, base) * attenuation;
            let direct = V::splat(DIRECT) * (ndl * lit);
            for k in 0..3 {
                let c = load::<V>(&sc.albedo[k], base) * (V::splat(AMBIENT) + direct * V::splat(light.color[k]));
                c.write_to(&mut sc.colour[k][base..base + V::LANES]);
            }
        }
    }
}

/// How many per-lane quantities [`Surfaces`] gathers: origin (0-2), direction (3-5), hit distance and
/// barycentrics (6-8), face normal (9-11), albedo (12-14) and the three vertex normals (15-23).
const QUANTITIES: usize = 24;

/// Quantity `q` of every lane as a vector.
#[inline(always)]
fn quantity<V: Vf32>(lanes: &[[f32; MAX_LANES]; QUANTITIES], q: usize) -> V {
    V::from_slice(&lanes[q][..V::LANES])
}

/// Quantities `q..q + 3` of every lane as vectors.
#[inline(always)]
fn quantity3<V: Vf32>(lanes: &[[f32; MAX_LANES]; QUANTITIES], q: usize) -> [V; 3] {
    [quantity(lanes, q), quantity(lanes, q + 1), quantity(lanes, q + 2)]
}

/// Stores `x` as quantities `q..q + 3` of lane `i`.
#[inline(always)]
fn put(lanes: &mut [[f32; MAX_LANES]; QUANTITIES], i: usize, q: usize, x: Vec3) {
    (lanes[q][i], lanes[q + 1][i], lanes[q + 2][i]) = (x.x, x.y, x.z);
}

/// The vector of `b` that starts at `base`.
#[inline(always)]
fn load<V: Vf32>(b: &[f32], base: usize) -> V {
    V::from_slice(&b[base..base + V::LANES])
}

/// `-x` per lane, exactly (a multiplication by -1 only flips the sign bit).
#[inline(always)]
fn negate<V: Vf32>(x: V) -> V {
    x * V::splat(-1.0)
}

#[cfg(test)]
mod tests {
    use raylab_simd::{Backend, dispatch};

    use super::*;
    use crate::render::shade::{Surface, shadow_ray};
    use crate::scene::{SceneBuilder, Triangle};

    /// A small deterministic generator in `[-1, 1)` (no dependency for a test).
    fn next(state: &mut u64) -> f32 {
        *state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((*state >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
    }

    fn point(state: &mut u64, scale: f32) -> Vec3 {
        Vec3::new(next(state), next(state), next(state)) * scale
    }

    /// Random triangles of two diffuse colours, with random vertex normals (triangle 0's cancel out at
    /// `u = 0.5, v = 0`) when `normals` is set, or none; a third, specular material on the last triangle.
    fn scene(normals: bool, state: &mut u64) -> Scene {
        let mut b = SceneBuilder::new();
        let n = 30;
        b.positions = (0..3 * n).map(|_| point(state, 5.0)).collect();
        if normals {
            b.normals = (0..3 * n).map(|_| point(state, 1.0)).collect();
            (b.normals[0], b.normals[1], b.normals[2]) = (Vec3::X, Vec3::NEG_X, Vec3::ZERO);
        }
        b.triangles = (0..n as u32).map(|i| Triangle { v: [3 * i, 3 * i + 1, 3 * i + 2], material: i % 2 }).collect();
        b.triangles[n - 1].material = 2;
        b.materials = vec![
            Material::diffuse("warm", Vec3::new(0.9, 0.6, 0.3)),
            Material::diffuse("cool", Vec3::new(0.2, 0.5, 0.8)),
            Material::specular("shiny", Vec3::ONE, 20.0, 0.5),
        ];
        b.build()
    }

    #[test]
    fn a_scene_is_plain_when_its_materials_are() {
        let mut state = 9u64;
        let mut scene = scene(false, &mut state);
        assert_eq!(PlainMaterials::of(&scene), PlainMaterials::Some);
        scene.materials.truncate(2);
        assert_eq!(PlainMaterials::of(&scene), PlainMaterials::All);
        scene.materials[0].diffuse_texture = Some(0);
        scene.materials[1].kind = MaterialKind::Reflective;
        assert_eq!(PlainMaterials::of(&scene), PlainMaterials::None);
    }

    /// The plain path's shadow segments and colours are the per-hit path's (`Surface::at`, `shadow_ray`,
    /// `Surface::local`) to the bit, on every backend, with and without vertex normals (and black where there
    /// is no hit, whatever the lane held before): hits from both
    /// sides, a vanishing interpolated normal, a hit at the light itself, surfaces facing away from the
    /// light, missing rays and hits, and a layer that is not a whole number of vectors.
    #[test]
    fn plain_shading_equals_the_per_hit_path_on_every_backend() {
        let mut state = 5u64;
        let light = PointLight {
            position: Vec3::new(0.5, 1.0, -0.25),
            color: Vec3::new(1.0, 0.9, 0.7),
            constant: 0.5,
            linear: 0.1,
            quadratic: 0.02,
            radius: 0.0,
        };
        let epsilon = 1e-3;
        for normals in [true, false] {
            let scene = scene(normals, &mut state);
            let plain_tris = scene.triangles.len() as u32 - 1;
            let mut rays = Vec::new();
            let mut hits = Vec::new();
            for i in 0..37u32 {
                let origin = point(&mut state, 8.0);
                let dir = point(&mut state, 1.0).normalize();
                let (u, v) = (next(&mut state).abs() * 0.5, next(&mut state).abs() * 0.5);
                let hit = Hit { t: 1.0 + 4.0 * next(&mut state).abs(), tri: i % plain_tris, u, v };
                let (ray, hit) = match i {
                    3 => (None, None),
                    5 => (Some(Ray::new(origin, dir)), None),
                    // Triangle 0's normals cancel out here: the face normal stands in.
                    7 => (Some(Ray::new(origin, dir)), Some(Hit { tri: 0, u: 0.5, v: 0.0, ..hit })),
                    // The hit point is the light: no segment, and the normal stands in for the light direction.
                    11 => (Some(Ray::new(light.position + Vec3::Z * 2.0, Vec3::NEG_Z)), Some(Hit { t: 2.0, ..hit })),
                    _ => (Some(Ray::new(origin, dir)), Some(hit)),
                };
                rays.push(ray);
                hits.push(hit);
            }

            let surfaces: Vec<Option<Surface>> =
                rays.iter().zip(&hits).map(|(r, h)| Some(Surface::at(&scene, r.as_ref()?, h.as_ref()?))).collect();
            let segments: Vec<Option<Ray>> =
                surfaces.iter().map(|s| shadow_ray(s.as_ref()?, light.position, light.position, epsilon)).collect();
            assert!(segments.iter().filter(|s| s.is_some()).count() > 10, "some surfaces face the light");
            assert!(segments.iter().zip(&hits).filter(|(s, h)| s.is_none() && h.is_some()).count() > 3);
            // Blocked, lit, and partly lit (edge widths) points.
            let visible: Vec<f32> = (0..rays.len())
                .map(|i| if segments[i].is_some() { [1.0, 0.0, 0.25, 0.7][i % 4] } else { 0.0 })
                .collect();
            let colours: Vec<[u32; 3]> = surfaces
                .iter()
                .zip(&rays)
                .enumerate()
                .map(|(i, (s, r))| match (s, r) {
                    (Some(s), Some(r)) => s.local(r.dir, &light, visible[i]).to_array().map(f32::to_bits),
                    _ => [0; 3],
                })
                .collect();
            for backend in Backend::available() {
                let mut sc = PlainScratch::default();
                let (rays, hits) = (&rays, &hits);
                // Checked hit by hit (the scene has a specular material too) or not: every hit here is plain.
                for check in [true, false] {
                    let (light, mut out) = (light.position, Vec::new());
                    let segs = Some(&mut out);
                    let kernel =
                        Surfaces { scene: &scene, rays, hits, light, epsilon, segments: segs, check, sc: &mut sc };
                    assert!(dispatch(backend, kernel), "{backend:?}: every surface is plain");
                    assert_eq!(out, segments, "{backend:?}, normals {normals}, check {check}: shadow segments");
                }
                sc.visible[..visible.len()].copy_from_slice(&visible);
                dispatch(backend, Colours { n: hits.len(), light: &light, sc: &mut sc });
                let got: Vec<[u32; 3]> =
                    (0..hits.len()).map(|i| [0, 1, 2].map(|k| sc.colour[k][i].to_bits())).collect();
                assert_eq!(got, colours, "{backend:?}, normals {normals}: colours, black (+0) without a hit");
                // One hit on the specular triangle sends the layer down the per-hit path.
                let mut mixed = hits.clone();
                mixed[20] = mixed[20].map(|h| Hit { tri: plain_tris, ..h });
                let kernel = Surfaces {
                    scene: &scene,
                    rays,
                    hits: &mixed,
                    light: light.position,
                    epsilon,
                    segments: None,
                    check: true,
                    sc: &mut sc,
                };
                assert!(!dispatch(backend, kernel), "{backend:?}: a specular surface is not plain");
            }
        }
    }
}
