//! The scene model: indexed triangles with optional normals and UVs, materials, lights and named views.
//!
//! Scenes are made through [`SceneBuilder`], which drops triangles that no tracer could hit reliably
//! (non-finite or zero-area) and counts them, so every acceleration structure can assume clean input.

mod camera;
mod light;
mod material;
mod texture;

pub use camera::{Camera, CameraError, CameraRaster, PrimaryGrid, View};
pub use light::PointLight;
pub use material::{Material, MaterialKind, TextureId};
pub use texture::{Texture, WrapMode};

use glam::{DVec3, Vec2, Vec3};

use crate::aabb::Aabb;
use crate::ray::Hit;

/// One triangle: three vertex indices and a material index.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Triangle {
    /// Indices into [`Scene::positions`] (and the normal and UV arrays when present).
    pub v: [u32; 3],
    /// Index into [`Scene::materials`].
    pub material: u32,
}

/// How many triangles [`SceneBuilder::build`] removed, by reason.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DroppedTriangles {
    /// A vertex index was out of range.
    pub bad_index: usize,
    /// A vertex had a NaN or infinite coordinate.
    pub non_finite: usize,
    /// The three vertices were collinear or coincident (zero area in double precision).
    pub degenerate: usize,
}

impl DroppedTriangles {
    /// Total number of dropped triangles.
    pub fn total(&self) -> usize {
        self.bad_index + self.non_finite + self.degenerate
    }
}

/// A finished scene, ready for acceleration-structure builds.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    /// Vertex positions; move them with [`Scene::set_vertices`], which keeps the bounds and the face normals
    /// in step.
    pub positions: Vec<Vec3>,
    /// Per-vertex normals: empty, or one per position.
    pub normals: Vec<Vec3>,
    /// Per-vertex texture coordinates: empty, or one per position.
    pub uvs: Vec<Vec2>,
    /// The triangles; a triangle's index is its id in hits and counters. Fixed once built: the face normals
    /// are kept per triangle.
    pub triangles: Vec<Triangle>,
    /// Materials; every triangle's material index is valid.
    pub materials: Vec<Material>,
    /// Textures referenced by materials.
    pub textures: Vec<Texture>,
    /// Lights; the first is the benchmark light.
    pub lights: Vec<PointLight>,
    /// Named viewpoints; the first is the default view.
    pub views: Vec<View>,
    /// What the builder removed.
    pub dropped: DroppedTriangles,
    bounds: Aabb,
    /// Unit geometric normal of each triangle, kept with the positions (every shaded hit needs one).
    face_normals: Vec<Vec3>,
}

impl Scene {
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Bounds of all triangle vertices (empty for an empty scene).
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// The three corner positions of triangle `i`.
    #[inline]
    pub fn vertices(&self, i: usize) -> [Vec3; 3] {
        let t = &self.triangles[i];
        [self.positions[t.v[0] as usize], self.positions[t.v[1] as usize], self.positions[t.v[2] as usize]]
    }

    /// Moves vertices, for animation: `positions` replace the positions from vertex `first` on, and `normals`
    /// (when given and the scene has normals) the normals; the scene's bounds follow. A range past the end or
    /// a non-finite position is refused with a message, leaving the scene unchanged. Rigid motions keep every
    /// triangle's area, so the builder's guarantees (finite, non-degenerate triangles) still hold.
    pub fn set_vertices(&mut self, first: usize, positions: &[Vec3], normals: Option<&[Vec3]>) -> Result<(), String> {
        let end = first + positions.len();
        if end > self.positions.len() {
            return Err(format!("vertices {first}..{end} are past the scene's {}", self.positions.len()));
        }
        if let Some(p) = positions.iter().find(|p| !p.is_finite()) {
            return Err(format!("non-finite vertex position {p}"));
        }
        if let Some(n) = normals.filter(|_| !self.normals.is_empty()) {
            if n.len() != positions.len() {
                return Err(format!("{} normals for {} positions", n.len(), positions.len()));
            }
            self.normals[first..end].copy_from_slice(n);
        }
        self.positions[first..end].copy_from_slice(positions);
        self.bounds = bounds_of(&self.triangles, &self.positions);
        let moved = first as u32..end as u32;
        for (i, t) in self.triangles.iter().enumerate() {
            if t.v.iter().any(|v| moved.contains(v)) {
                self.face_normals[i] = face_normal(&self.positions, t);
            }
        }
        Ok(())
    }

    /// Bounds of triangle `i`.
    pub fn triangle_bounds(&self, i: usize) -> Aabb {
        Aabb::from_points(self.vertices(i))
    }

    /// Geometric normal of triangle `i` before normalisation, `(v1 - v0) x (v2 - v0)` in `f32`: the same
    /// vector, bit for bit, as Embree's `Ng`.
    pub fn geometric_normal_unnormalized(&self, i: usize) -> Vec3 {
        let [a, b, c] = self.vertices(i);
        (b - a).cross(c - a)
    }

    /// Unit geometric normal of triangle `i`: [`Scene::geometric_normal_unnormalized`] normalised, computed
    /// when the scene is built and when its vertices move.
    #[inline]
    pub fn geometric_normal(&self, i: usize) -> Vec3 {
        self.face_normals[i]
    }

    /// The shading normal at a hit: interpolated vertex normals when the scene has them, else the geometric
    /// normal. Not flipped toward the viewer.
    #[inline(always)]
    pub fn shading_normal(&self, hit: &Hit) -> Vec3 {
        // The builder keeps the normals only when there is one per position.
        if !self.normals.is_empty() {
            let [i0, i1, i2] = self.triangles[hit.tri as usize].v;
            let [n0, n1, n2] = [self.normals[i0 as usize], self.normals[i1 as usize], self.normals[i2 as usize]];
            let n = n0 * (1.0 - hit.u - hit.v) + n1 * hit.u + n2 * hit.v;
            // `normalize_or_zero`, with its zero case going to the face normal.
            let rcp = n.length_recip();
            if rcp.is_finite() && rcp > 0.0 {
                return n * rcp;
            }
        }
        self.geometric_normal(hit.tri as usize)
    }

    /// The default view, if the scene has any.
    pub fn default_view(&self) -> Option<&View> {
        self.views.first()
    }

    /// The view called `name`.
    pub fn view(&self, name: &str) -> Option<&View> {
        self.views.iter().find(|v| v.name == name)
    }
}

/// Collects geometry and scene data, then validates it into a [`Scene`].
#[derive(Clone, Debug, Default)]
pub struct SceneBuilder {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Per-vertex normals (leave empty, or give one per position).
    pub normals: Vec<Vec3>,
    /// Per-vertex UVs (leave empty, or give one per position).
    pub uvs: Vec<Vec2>,
    /// Triangles.
    pub triangles: Vec<Triangle>,
    /// Materials (a default one is added if a triangle needs one and none exists).
    pub materials: Vec<Material>,
    /// Textures.
    pub textures: Vec<Texture>,
    /// Lights.
    pub lights: Vec<PointLight>,
    /// Named views.
    pub views: Vec<View>,
}

impl SceneBuilder {
    /// An empty builder.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a material and returns its index.
    pub fn add_material(&mut self, m: Material) -> u32 {
        self.materials.push(m);
        (self.materials.len() - 1) as u32
    }

    /// Validates and finishes the scene.
    ///
    /// Drops triangles with an out-of-range index, a non-finite vertex, or zero area, and counts each
    /// reason in [`Scene::dropped`]. Normal and UV arrays whose length does not match the positions are
    /// discarded. Material indices out of range are redirected to a default material.
    pub fn build(mut self) -> Scene {
        let n = self.positions.len();
        let mut dropped = DroppedTriangles::default();
        let positions = &self.positions;
        self.triangles.retain(|t| {
            if t.v.iter().any(|&i| i as usize >= n) {
                dropped.bad_index += 1;
                return false;
            }
            let [a, b, c] = t.v.map(|i| positions[i as usize]);
            if !(a.is_finite() && b.is_finite() && c.is_finite()) {
                dropped.non_finite += 1;
                return false;
            }
            let (a, b, c) = (a.as_dvec3(), b.as_dvec3(), c.as_dvec3());
            if (b - a).cross(c - a) == DVec3::ZERO {
                dropped.degenerate += 1;
                return false;
            }
            true
        });
        if self.normals.len() != n || self.normals.iter().any(|v| !v.is_finite()) {
            self.normals.clear();
        }
        if self.uvs.len() != n || self.uvs.iter().any(|v| !v.is_finite()) {
            self.uvs.clear();
        }
        let n_mat = self.materials.len() as u32;
        if self.triangles.iter().any(|t| t.material >= n_mat) {
            let fallback = self.add_material(Material::default());
            for t in &mut self.triangles {
                if t.material >= n_mat {
                    t.material = fallback;
                }
            }
        }
        let bounds = bounds_of(&self.triangles, &self.positions);
        let face_normals = self.triangles.iter().map(|t| face_normal(&self.positions, t)).collect();
        Scene {
            positions: self.positions,
            normals: self.normals,
            uvs: self.uvs,
            triangles: self.triangles,
            materials: self.materials,
            textures: self.textures,
            lights: self.lights,
            views: self.views,
            dropped,
            bounds,
            face_normals,
        }
    }
}

/// Unit normal of triangle `t`, `(v1 - v0) x (v2 - v0)` normalised (zero for a degenerate one).
fn face_normal(positions: &[Vec3], t: &Triangle) -> Vec3 {
    let [a, b, c] = t.v.map(|i| positions[i as usize]);
    (b - a).cross(c - a).normalize_or_zero()
}

/// Bounds of the vertices the triangles use.
fn bounds_of(triangles: &[Triangle], positions: &[Vec3]) -> Aabb {
    triangles.iter().flat_map(|t| t.v).fold(Aabb::EMPTY, |b, i| b.grow(positions[i as usize]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builder_drops_bad_triangles_and_counts_them() {
        let mut b = SceneBuilder::new();
        b.positions = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(2.0, 0.0, 0.0), Vec3::new(f32::NAN, 0.0, 0.0)];
        b.triangles = vec![
            Triangle { v: [0, 1, 2], material: 0 },
            Triangle { v: [0, 1, 3], material: 0 }, // collinear
            Triangle { v: [0, 1, 4], material: 0 }, // NaN vertex
            Triangle { v: [0, 1, 9], material: 0 }, // out of range
            Triangle { v: [0, 0, 2], material: 0 }, // repeated vertex
        ];
        let s = b.build();
        assert_eq!(s.triangle_count(), 1);
        assert_eq!(s.dropped, DroppedTriangles { bad_index: 1, non_finite: 1, degenerate: 2 });
        assert_eq!(s.materials.len(), 1, "a default material is added for the orphan index");
        assert_eq!(s.bounds(), Aabb::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0)));
        assert_eq!(s.geometric_normal(0), Vec3::Z);
    }

    /// The stored face normals follow the vertices: after a move, every triangle's normal is its corners'
    /// cross product normalised, for the moved triangles and the untouched ones alike.
    #[test]
    fn face_normals_follow_moved_vertices() {
        let mut b = SceneBuilder::new();
        b.positions = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(5.0, 0.0, 0.0), Vec3::new(5.0, 0.0, 1.0)];
        b.triangles = vec![Triangle { v: [0, 1, 2], material: 0 }, Triangle { v: [1, 3, 4], material: 0 }];
        let mut s = b.build();
        assert_eq!(s.geometric_normal(0), Vec3::Z);
        assert_eq!(s.geometric_normal(1), Vec3::NEG_Y);
        // Turn the second triangle's free corners upward and swap the first's winding through vertex 2.
        s.set_vertices(2, &[Vec3::NEG_Y, Vec3::new(5.0, 1.0, 0.0), Vec3::new(5.0, 1.0, 1.0)], None).unwrap();
        for i in 0..s.triangle_count() {
            assert_eq!(s.geometric_normal(i), s.geometric_normal_unnormalized(i).normalize_or_zero(), "triangle {i}");
        }
        assert_eq!(s.geometric_normal(0), Vec3::NEG_Z);
        assert!(s.geometric_normal(1).dot(Vec3::NEG_Y) < 0.99, "the moved triangle's normal turned");
    }

    #[test]
    fn empty_scene_has_empty_bounds() {
        let s = SceneBuilder::new().build();
        assert_eq!(s.triangle_count(), 0);
        assert!(s.bounds().is_empty());
    }
}
