//! `forest`: dense small-triangle detail in the manner of the Fairy Forest scene (174k polygons): a closed
//! terrain slab, trees with tapered trunks, branches and hundreds of small leaves each, grass blades, rocks
//! and mushrooms.

use glam::{Affine3A, Quat, Vec3};
use raylab_core::scene::{Camera, Material, PointLight, Scene, View};

use super::Detail;
use crate::mesh::{Jitter, MeshBuilder};

const HALF: f32 = 20.0;

fn height(x: f32, z: f32) -> f32 {
    0.6 * (x * 0.23).sin() * (z * 0.19).cos() + 0.3 * (x * 0.07 + z * 0.11).sin()
}

pub(super) fn build(d: Detail) -> Scene {
    let mut m = MeshBuilder::new();
    let mut rng = Jitter::new(11);
    m.material(Material::diffuse("ground", Vec3::new(0.3, 0.25, 0.15)));
    terrain(&mut m, d.pick(100, 8));

    let trees = d.pick(60, 3);
    let leaves = d.pick(300, 12);
    let bark = m.material(Material::diffuse("bark", Vec3::new(0.35, 0.22, 0.12)));
    let leaf = m.material(Material::diffuse("leaf", Vec3::new(0.2, 0.5, 0.15)));
    for _ in 0..trees {
        let (x, z) = (rng.range(-HALF + 2.0, HALF - 2.0), rng.range(-HALF + 2.0, HALF - 2.0));
        let base = Vec3::new(x, height(x, z) - 0.2, z);
        let h = rng.range(4.0, 7.0);
        m.use_material(bark);
        let trunk = [(0.0, 0.0), (0.35, 0.0), (0.28, 0.5), (0.2, h * 0.6), (0.1, h), (0.0, h)];
        m.lathe(base, &trunk, d.pick(12, 5));
        for b in 0..4 {
            let a = b as f32 * std::f32::consts::FRAC_PI_2 + rng.unit();
            let rot = Quat::from_rotation_y(a) * Quat::from_rotation_z(-0.9);
            let t = Affine3A::from_rotation_translation(rot, base + Vec3::Y * (h * 0.55 + 0.3 * b as f32));
            m.with_transform(t, |m| m.lathe(Vec3::ZERO, &[(0.0, 0.0), (0.08, 0.0), (0.0, 2.0)], 6));
        }
        m.use_material(leaf);
        for _ in 0..leaves {
            let c = base + Vec3::new(rng.range(-2.2, 2.2), rng.range(h * 0.45, h + 0.8), rng.range(-2.2, 2.2));
            let (u, v) = (Vec3::new(rng.range(-0.2, 0.2), rng.range(0.0, 0.15), 0.1), rng.range(0.08, 0.15));
            let side = u.cross(Vec3::Y).normalize_or_zero() * v;
            m.quad(c - side, c + u - side * 0.5, c + u * 1.6, c + u + side * 0.5);
            m.triangle(c + side * 0.2, c + u * 1.6, c - side * 0.2);
        }
    }
    m.material(Material::diffuse("grass", Vec3::new(0.25, 0.55, 0.2)));
    for _ in 0..d.pick(60_000, 150) {
        let (x, z) = (rng.range(-HALF, HALF), rng.range(-HALF, HALF));
        let g = Vec3::new(x, height(x, z), z);
        let (w, h) = (rng.range(0.02, 0.05), rng.range(0.15, 0.45));
        let lean = Vec3::new(rng.range(-0.1, 0.1), 0.0, rng.range(-0.1, 0.1));
        let a = rng.range(0.0, std::f32::consts::TAU);
        let side = Vec3::new(a.cos(), 0.0, a.sin()) * w;
        m.triangle(g - side - Vec3::Y * 0.05, g + side - Vec3::Y * 0.05, g + Vec3::Y * h + lean);
    }
    m.material(Material::diffuse("rock", Vec3::new(0.45, 0.45, 0.43)));
    for _ in 0..d.pick(30, 2) {
        let (x, z) = (rng.range(-HALF + 1.0, HALF - 1.0), rng.range(-HALF + 1.0, HALF - 1.0));
        let r = rng.range(0.3, 0.9);
        m.sphere(Vec3::new(x, height(x, z), z), r, d.pick(10, 4), d.pick(12, 5));
    }
    m.material(Material::specular("mushroom", Vec3::new(0.8, 0.15, 0.1), 32.0, 0.3));
    for _ in 0..d.pick(40, 2) {
        let (x, z) = (rng.range(-HALF + 1.0, HALF - 1.0), rng.range(-HALF + 1.0, HALF - 1.0));
        let cap = [(0.0, 0.0), (0.04, 0.0), (0.035, 0.15), (0.16, 0.15), (0.14, 0.2), (0.08, 0.25), (0.0, 0.26)];
        m.lathe(Vec3::new(x, height(x, z) - 0.02, z), &cap, d.pick(24, 6));
    }

    let s = m.scene_mut();
    s.lights.push(PointLight { quadratic: 0.0005, radius: 1.0, ..PointLight::at(Vec3::new(6.0, 25.0, -4.0)) });
    s.views.push(View {
        name: "clearing".into(),
        camera: Camera::look_at(Vec3::new(-16.0, 3.0, -16.0), Vec3::new(0.0, 2.0, 0.0), Vec3::Y, 60.0),
    });
    s.views.push(View {
        name: "grass".into(),
        camera: Camera::look_at(Vec3::new(2.0, 0.8, 4.0), Vec3::new(-3.0, 0.3, -1.0), Vec3::Y, 55.0),
    });
    m.build()
}

/// A closed terrain slab: a height-field top, vertical skirts and a flat bottom, all meeting at bit-identical
/// edge vertices.
fn terrain(m: &mut MeshBuilder, n: u32) {
    let at = |u: f32, v: f32| {
        let (x, z) = (-HALF + 2.0 * HALF * u, -HALF + 2.0 * HALF * v);
        Vec3::new(x, height(x, z), z)
    };
    m.grid(n, n, at);
    let bottom = -2.0;
    for k in 0..n {
        let (a, b) = (k as f32 / n as f32, (k + 1) as f32 / n as f32);
        for (p, q) in
            [(at(a, 0.0), at(b, 0.0)), (at(1.0, a), at(1.0, b)), (at(b, 1.0), at(a, 1.0)), (at(0.0, b), at(0.0, a))]
        {
            m.quad(p, Vec3::new(p.x, bottom, p.z), Vec3::new(q.x, bottom, q.z), q);
        }
    }
    // The bottom uses the same subdivision as the skirts, so no edge ends in the middle of another.
    m.grid(n, n, |u, v| Vec3::new(-HALF + 2.0 * HALF * u, bottom, -HALF + 2.0 * HALF * v));
}
