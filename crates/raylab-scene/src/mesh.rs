//! A small modelling kit for the procedural scenes: closed boxes, solids of revolution, tori, extruded
//! arches, open quads and grids, with per-vertex normals and an affine transform.
//!
//! Solid primitives are closed: neighbouring faces reuse bit-identical corner positions (even where normals
//! differ and vertices are duplicated), so the watertight triangle test never lets a ray slip between them,
//! and edge-width soft shadows see an entry and an exit for every solid.

use std::f32::consts::TAU;

use glam::{Affine3A, Vec2, Vec3};
use raylab_core::scene::{Material, Scene, SceneBuilder, Triangle};

/// Builds a [`Scene`] piece by piece.
pub struct MeshBuilder {
    scene: SceneBuilder,
    material: u32,
    transform: Affine3A,
}

impl Default for MeshBuilder {
    fn default() -> Self {
        Self::new()
    }
}

impl MeshBuilder {
    /// An empty builder with a default material and the identity transform.
    pub fn new() -> Self {
        let mut scene = SceneBuilder::new();
        scene.add_material(Material::default());
        Self { scene, material: 0, transform: Affine3A::IDENTITY }
    }

    /// The scene under construction (for lights, views and materials).
    pub fn scene_mut(&mut self) -> &mut SceneBuilder {
        &mut self.scene
    }

    /// Adds a material and makes it current.
    pub fn material(&mut self, m: Material) -> u32 {
        self.material = self.scene.add_material(m);
        self.material
    }

    /// Makes an existing material current.
    pub fn use_material(&mut self, id: u32) {
        self.material = id;
    }

    /// Sets the transform applied to everything added from now on.
    pub fn set_transform(&mut self, t: Affine3A) {
        self.transform = t;
    }

    /// Runs `f` with `t` applied after the current transform, then restores it.
    pub fn with_transform(&mut self, t: Affine3A, f: impl FnOnce(&mut Self)) {
        let saved = self.transform;
        self.transform = saved * t;
        f(self);
        self.transform = saved;
    }

    /// Finishes the scene.
    pub fn build(self) -> Scene {
        self.scene.build()
    }

    fn vertex(&mut self, p: Vec3, n: Vec3) -> u32 {
        let s = &mut self.scene;
        s.positions.push(self.transform.transform_point3(p));
        s.normals.push(self.transform.transform_vector3(n).normalize_or_zero());
        s.uvs.push(Vec2::ZERO);
        (s.positions.len() - 1) as u32
    }

    fn tri(&mut self, a: u32, b: u32, c: u32) {
        self.scene.triangles.push(Triangle { v: [a, b, c], material: self.material });
    }

    /// A flat triangle with its face normal.
    pub fn triangle(&mut self, a: Vec3, b: Vec3, c: Vec3) {
        let n = (b - a).cross(c - a).normalize_or_zero();
        let (i, j, k) = (self.vertex(a, n), self.vertex(b, n), self.vertex(c, n));
        self.tri(i, j, k);
    }

    /// A flat quad `a b c d` (counter-clockwise seen from the front) as two triangles.
    pub fn quad(&mut self, a: Vec3, b: Vec3, c: Vec3, d: Vec3) {
        let n = (b - a).cross(c - a).normalize_or_zero();
        let v = [a, b, c, d].map(|p| self.vertex(p, n));
        self.tri(v[0], v[1], v[2]);
        self.tri(v[0], v[2], v[3]);
    }

    /// A closed axis-aligned box.
    pub fn cuboid(&mut self, min: Vec3, max: Vec3) {
        let c = |x: bool, y: bool, z: bool| {
            Vec3::new(if x { max.x } else { min.x }, if y { max.y } else { min.y }, if z { max.z } else { min.z })
        };
        let (f, t) = (false, true);
        self.quad(c(f, f, t), c(t, f, t), c(t, t, t), c(f, t, t)); // +z
        self.quad(c(t, f, f), c(f, f, f), c(f, t, f), c(t, t, f)); // -z
        self.quad(c(t, f, t), c(t, f, f), c(t, t, f), c(t, t, t)); // +x
        self.quad(c(f, f, f), c(f, f, t), c(f, t, t), c(f, t, f)); // -x
        self.quad(c(f, t, t), c(t, t, t), c(t, t, f), c(f, t, f)); // +y
        self.quad(c(f, f, f), c(t, f, f), c(t, f, t), c(f, f, t)); // -y
    }

    /// A closed solid of revolution about the local y axis through `base`. `profile` lists `(radius, y)`
    /// from bottom to top; a profile that starts and ends at radius 0 gives a closed solid, otherwise flat
    /// caps close it. Smooth normals on the sides.
    pub fn lathe(&mut self, base: Vec3, profile: &[(f32, f32)], segments: u32) {
        let seg = segments.max(3);
        let ring = |r: f32, y: f32, k: u32| {
            let a = TAU * (k % seg) as f32 / seg as f32;
            base + Vec3::new(r * a.cos(), y, -r * a.sin())
        };
        for w in profile.windows(2) {
            let ((r0, y0), (r1, y1)) = (w[0], w[1]);
            let slope = Vec2::new(y1 - y0, -(r1 - r0)).normalize_or_zero();
            for k in 0..seg {
                let p = [ring(r0, y0, k), ring(r0, y0, k + 1), ring(r1, y1, k + 1), ring(r1, y1, k)];
                let normal = |k: u32| {
                    let a = TAU * (k % seg) as f32 / seg as f32;
                    Vec3::new(slope.x * a.cos(), slope.y, -slope.x * a.sin())
                };
                let n = [normal(k), normal(k + 1), normal(k + 1), normal(k)];
                let v: Vec<u32> = p.iter().zip(n).map(|(&p, n)| self.vertex(p, n)).collect();
                if r0 > 0.0 {
                    self.tri(v[0], v[1], v[2]);
                }
                if r1 > 0.0 {
                    self.tri(v[0], v[2], v[3]);
                }
            }
        }
        let caps = [(profile.first(), -1.0f32), (profile.last(), 1.0)];
        for (end, dir) in caps {
            let Some(&(r, y)) = end else { continue };
            if r <= 0.0 {
                continue;
            }
            let n = Vec3::Y * dir;
            let centre = self.vertex(base + Vec3::Y * y, n);
            for k in 0..seg {
                let (a, b) = (self.vertex(ring(r, y, k), n), self.vertex(ring(r, y, k + 1), n));
                if dir > 0.0 { self.tri(centre, a, b) } else { self.tri(centre, b, a) }
            }
        }
    }

    /// A closed cylinder standing on `base`.
    pub fn cylinder(&mut self, base: Vec3, radius: f32, height: f32, segments: u32) {
        self.lathe(base, &[(radius, 0.0), (radius, height)], segments);
    }

    /// A closed UV sphere.
    pub fn sphere(&mut self, centre: Vec3, radius: f32, rings: u32, segments: u32) {
        let rings = rings.max(2);
        let profile: Vec<(f32, f32)> = (0..=rings)
            .map(|i| {
                let a = std::f32::consts::PI * i as f32 / rings as f32;
                if i == 0 || i == rings { (0.0, -radius * a.cos()) } else { (radius * a.sin(), -radius * a.cos()) }
            })
            .collect();
        self.lathe(centre, &profile, segments);
    }

    /// A closed torus about the local y axis (a ring moulding for column bases and capitals).
    pub fn torus(&mut self, centre: Vec3, major: f32, minor: f32, segments: u32, sides: u32) {
        let (seg, sides) = (segments.max(3), sides.max(3));
        let point = |i: u32, j: u32| {
            let a = TAU * (i % seg) as f32 / seg as f32;
            let b = TAU * (j % sides) as f32 / sides as f32;
            let radial = Vec3::new(a.cos(), 0.0, -a.sin());
            let n = radial * b.cos() + Vec3::Y * b.sin();
            (centre + radial * major + n * minor, n)
        };
        for i in 0..seg {
            for j in 0..sides {
                let q = [point(i, j), point(i + 1, j), point(i + 1, j + 1), point(i, j + 1)];
                let v: Vec<u32> = q.iter().map(|&(p, n)| self.vertex(p, n)).collect();
                self.tri(v[0], v[1], v[2]);
                self.tri(v[0], v[2], v[3]);
            }
        }
    }

    /// A closed semicircular arch band in the local xy plane, centred on `centre` at the springing line,
    /// between radii `inner` and `outer`, extruded from `z = -depth/2` to `z = depth/2`.
    pub fn arch(&mut self, centre: Vec3, inner: f32, outer: f32, depth: f32, segments: u32) {
        let seg = segments.max(2);
        let h = depth * 0.5;
        let at = |r: f32, k: u32, z: f32| {
            let a = std::f32::consts::PI * k as f32 / seg as f32;
            centre + Vec3::new(r * a.cos(), r * a.sin(), z)
        };
        for k in 0..seg {
            let (k1, k2) = (k, k + 1);
            self.quad(at(inner, k1, h), at(outer, k1, h), at(outer, k2, h), at(inner, k2, h));
            self.quad(at(outer, k1, -h), at(inner, k1, -h), at(inner, k2, -h), at(outer, k2, -h));
            self.quad(at(outer, k1, h), at(outer, k1, -h), at(outer, k2, -h), at(outer, k2, h));
            self.quad(at(inner, k1, -h), at(inner, k1, h), at(inner, k2, h), at(inner, k2, -h));
        }
        self.quad(at(inner, 0, -h), at(outer, 0, -h), at(outer, 0, h), at(inner, 0, h));
        self.quad(at(outer, seg, -h), at(inner, seg, -h), at(inner, seg, h), at(outer, seg, h));
    }

    /// An open grid of `nu x nv` quads over `f(u, v)` for `u, v` in `[0, 1]` (cloth, terrain tops, leaves).
    pub fn grid(&mut self, nu: u32, nv: u32, f: impl Fn(f32, f32) -> Vec3) {
        let (nu, nv) = (nu.max(1), nv.max(1));
        let p = |i: u32, j: u32| f(i as f32 / nu as f32, j as f32 / nv as f32);
        let base = self.scene.positions.len() as u32;
        for j in 0..=nv {
            for i in 0..=nu {
                let du = p((i + 1).min(nu), j) - p(i.saturating_sub(1), j);
                let dv = p(i, (j + 1).min(nv)) - p(i, j.saturating_sub(1));
                let pt = p(i, j);
                self.vertex(pt, du.cross(dv));
            }
        }
        let idx = |i: u32, j: u32| base + j * (nu + 1) + i;
        for j in 0..nv {
            for i in 0..nu {
                self.tri(idx(i, j), idx(i + 1, j), idx(i + 1, j + 1));
                self.tri(idx(i, j), idx(i + 1, j + 1), idx(i, j + 1));
            }
        }
    }
}

/// Deterministic pseudo-random numbers for scene layout, from the harness's PCG hash.
pub struct Jitter {
    state: u32,
}

impl Jitter {
    /// A sequence started from `seed`.
    pub fn new(seed: u32) -> Self {
        Self { state: seed }
    }

    /// The next value in `[0, 1)`.
    pub fn unit(&mut self) -> f32 {
        self.state = self.state.wrapping_add(1);
        (raylab_core::workload::pcg_hash(self.state) >> 8) as f32 / 16_777_216.0
    }

    /// The next value in `[lo, hi)`.
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }
}
