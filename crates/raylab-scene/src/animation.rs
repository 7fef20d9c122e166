//! Moving geometry for dynamic-scene work (seed 003 traces reflections of scenes that change every frame):
//! a spinning mirror slab and a bouncing mirror ball added to any scene, sized to its bounds, and moved
//! rigidly to the pose of any time. Moving vertices keeps triangle ids, so an MBVH can be refitted, a kd-tree
//! must be rebuilt, and DACRT only copies the triangles and divides the top of them again.

use std::f32::consts::TAU;

use glam::{Affine3A, Quat, Vec3};
use raylab_core::scene::{Material, Scene, SceneBuilder};

use crate::mesh::MeshBuilder;

/// How one object moves.
#[derive(Clone, Copy, Debug)]
enum Motion {
    /// Turns about a vertical axis through its pivot, once per `period` seconds.
    Spin { period: f32 },
    /// Bounces on the floor: a parabola of `height` world units, one bounce per `period` seconds.
    Bounce { height: f32, period: f32 },
}

/// One rigidly moving object: its vertices in the scene and their rest pose.
#[derive(Clone, Debug)]
struct Mover {
    first: usize,
    rest: Vec<Vec3>,
    rest_normals: Vec<Vec3>,
    pivot: Vec3,
    motion: Motion,
}

impl Mover {
    fn transform(&self, t: f32) -> Affine3A {
        match self.motion {
            Motion::Spin { period } => {
                let turn = Quat::from_rotation_y(TAU * (t / period).fract());
                Affine3A::from_translation(self.pivot)
                    * Affine3A::from_quat(turn)
                    * Affine3A::from_translation(-self.pivot)
            }
            Motion::Bounce { height, period } => {
                let s = (t / period).fract() * 2.0 - 1.0;
                Affine3A::from_translation(Vec3::Y * height * (1.0 - s * s))
            }
        }
    }
}

/// The moving objects of a scene.
#[derive(Clone, Debug, Default)]
pub struct Animation {
    movers: Vec<Mover>,
    triangles: usize,
}

impl Animation {
    /// `scene` with two moving objects added near the centre of its floor (the bottom of its bounds): a mirror
    /// slab turning about a vertical axis (4 s a turn) and a mirror ball bouncing (1.5 s a bounce), each about
    /// a tenth of the scene's size; and the animation that moves them. An empty scene gets them in a unit box.
    pub fn add_movers(scene: &Scene) -> (Scene, Animation) {
        let b = if scene.bounds().is_empty() {
            raylab_core::aabb::Aabb::new(Vec3::splat(-1.0), Vec3::ONE)
        } else {
            scene.bounds()
        };
        let size = b.extent().max_element().max(f32::MIN_POSITIVE) * 0.1;
        let floor = Vec3::new(b.center().x, b.min.y, b.center().z);
        let mut m = MeshBuilder::new();
        *m.scene_mut() = builder_of(scene);
        let base_vertices = scene.positions.len();
        m.material(Material::mirror("spinning mirror", Vec3::new(0.85, 0.9, 0.95), 0.9));
        let slab_pivot = floor + Vec3::new(-size, size * 0.75, 0.0);
        m.cuboid(
            slab_pivot - Vec3::new(size * 0.5, size * 0.7, size * 0.04),
            slab_pivot + Vec3::new(size * 0.5, size * 0.7, size * 0.04),
        );
        let slab_end = m.scene_mut().positions.len();
        m.material(Material::mirror("bouncing ball", Vec3::new(0.95, 0.8, 0.6), 0.7));
        let radius = size * 0.3;
        let ball_centre = floor + Vec3::new(size, radius * 1.01, 0.0);
        m.sphere(ball_centre, radius, 12, 18);
        let mut out = m.scene_mut().clone();
        if scene.normals.is_empty() {
            out.normals.clear();
        }
        if scene.uvs.is_empty() {
            out.uvs.clear();
        }
        let added = out.triangles.len() - scene.triangle_count();
        let scene = out.build();
        let rest = |r: std::ops::Range<usize>| scene.positions[r].to_vec();
        let rest_n =
            |r: std::ops::Range<usize>| if scene.normals.is_empty() { Vec::new() } else { scene.normals[r].to_vec() };
        let end = scene.positions.len();
        let movers = vec![
            Mover {
                first: base_vertices,
                rest: rest(base_vertices..slab_end),
                rest_normals: rest_n(base_vertices..slab_end),
                pivot: slab_pivot,
                motion: Motion::Spin { period: 4.0 },
            },
            Mover {
                first: slab_end,
                rest: rest(slab_end..end),
                rest_normals: rest_n(slab_end..end),
                pivot: ball_centre,
                motion: Motion::Bounce { height: size * 1.5, period: 1.5 },
            },
        ];
        (scene, Animation { movers, triangles: added })
    }

    /// Moves every object of `scene` (made by [`Animation::add_movers`]) to its pose at time `t` seconds.
    pub fn apply(&self, scene: &mut Scene, t: f32) -> Result<(), String> {
        for m in &self.movers {
            let xf = m.transform(if t.is_finite() { t } else { 0.0 });
            let p: Vec<Vec3> = m.rest.iter().map(|&p| xf.transform_point3(p)).collect();
            let n: Vec<Vec3> = m.rest_normals.iter().map(|&n| xf.transform_vector3(n)).collect();
            scene.set_vertices(m.first, &p, (!n.is_empty()).then_some(&n[..]))?;
        }
        Ok(())
    }

    /// Triangles that move.
    pub fn moving_triangles(&self) -> usize {
        self.triangles
    }
}

/// A builder holding everything `scene` holds, to add to.
fn builder_of(scene: &Scene) -> SceneBuilder {
    let mut b = SceneBuilder::new();
    b.positions = scene.positions.clone();
    b.normals = if scene.normals.is_empty() { vec![Vec3::Y; scene.positions.len()] } else { scene.normals.clone() };
    b.uvs = if scene.uvs.is_empty() { vec![glam::Vec2::ZERO; scene.positions.len()] } else { scene.uvs.clone() };
    b.triangles = scene.triangles.clone();
    b.materials = scene.materials.clone();
    b.textures = scene.textures.clone();
    b.lights = scene.lights.clone();
    b.views = scene.views.clone();
    b
}
