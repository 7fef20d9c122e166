//! `arena`: a Quake-III-style arena (the thesis's 12.8k-polygon Quake III map): few, large, mostly
//! axis-aligned polygons: a tiled floor, crenellated outer walls with panels, raised corner platforms with
//! stairs, a central bridge on pillars and jump pads.

use glam::{Affine3A, Vec3};
use raylab_core::scene::{Camera, Material, PointLight, Scene, View};

use super::Detail;
use crate::mesh::MeshBuilder;

const HALF: f32 = 20.0;
const WALL_H: f32 = 8.0;

pub(super) fn build(d: Detail) -> Scene {
    let mut m = MeshBuilder::new();
    let tiles = d.pick(24, 4);
    let dark = m.material(Material::diffuse("floor tile dark", Vec3::new(0.35, 0.3, 0.28)));
    let light = m.material(Material::diffuse("floor tile light", Vec3::new(0.55, 0.5, 0.42)));
    let size = 2.0 * HALF / tiles as f32;
    for j in 0..tiles {
        for i in 0..tiles {
            m.use_material(if (i + j) % 2 == 0 { dark } else { light });
            let (x, z) = (-HALF + i as f32 * size, -HALF + j as f32 * size);
            m.cuboid(Vec3::new(x + 0.02, -0.2, z + 0.02), Vec3::new(x + size - 0.02, 0.0, z + size - 0.02));
        }
    }
    m.material(Material::diffuse("metal wall", Vec3::new(0.45, 0.42, 0.4)));
    let merlons = d.pick(30, 4);
    let panels = d.pick(20, 3);
    for k in 0..4 {
        let rot = Affine3A::from_rotation_y(k as f32 * std::f32::consts::FRAC_PI_2);
        m.with_transform(rot, |m| {
            m.cuboid(Vec3::new(-HALF, 0.0, HALF), Vec3::new(HALF, WALL_H, HALF + 1.0));
            let step = 2.0 * HALF / merlons as f32;
            for i in 0..merlons {
                let x = -HALF + i as f32 * step;
                m.cuboid(Vec3::new(x, WALL_H, HALF), Vec3::new(x + step * 0.5, WALL_H + 1.0, HALF + 1.0));
            }
            let pstep = 2.0 * HALF / panels as f32;
            for i in 0..panels {
                let x = -HALF + i as f32 * pstep;
                m.cuboid(Vec3::new(x + 0.3, 1.0, HALF - 0.15), Vec3::new(x + pstep - 0.3, 5.5, HALF));
            }
        });
    }
    m.material(Material::diffuse("platform", Vec3::new(0.5, 0.45, 0.35)));
    let steps = d.pick(12, 3);
    for k in 0..4 {
        let rot = Affine3A::from_rotation_y(k as f32 * std::f32::consts::FRAC_PI_2);
        m.with_transform(rot, |m| {
            m.cuboid(Vec3::new(10.0, 0.0, 10.0), Vec3::new(HALF, 3.0, HALF));
            for s in 0..steps {
                let h = 3.0 * (s + 1) as f32 / steps as f32;
                let x = 10.0 - 0.5 * (steps - s) as f32;
                m.cuboid(Vec3::new(x, 0.0, 12.0), Vec3::new(x + 0.5, h, 15.0));
            }
        });
    }
    m.material(Material::specular("pillar", Vec3::new(0.6, 0.55, 0.5), 32.0, 0.2));
    let seg = d.pick(16, 6);
    for k in 0..d.pick(16, 4) {
        let a = k as f32 * std::f32::consts::TAU / d.pick(16, 4) as f32;
        let base = Vec3::new(8.0 * a.cos(), 0.0, 8.0 * a.sin());
        m.cylinder(base, 0.6, 4.0, seg);
        m.cuboid(base + Vec3::new(-0.8, 4.0, -0.8), base + Vec3::new(0.8, 4.4, 0.8));
    }
    m.material(Material::diffuse("bridge", Vec3::new(0.4, 0.38, 0.36)));
    m.cuboid(Vec3::new(-9.0, 4.4, -1.5), Vec3::new(9.0, 4.8, 1.5));
    m.cuboid(Vec3::new(-1.5, 4.4, -9.0), Vec3::new(1.5, 4.8, 9.0));
    m.material(Material::mirror("jump pad", Vec3::new(0.3, 0.5, 0.9), 0.3));
    for k in 0..4 {
        let a = (k as f32 + 0.5) * std::f32::consts::FRAC_PI_2;
        let c = Vec3::new(14.0 * a.cos(), 0.0, 14.0 * a.sin());
        m.cylinder(c, 1.2, 0.15, d.pick(24, 6));
        m.torus(c + Vec3::Y * 0.15, 1.2, 0.12, d.pick(24, 6), d.pick(8, 3));
    }
    let s = m.scene_mut();
    s.lights.push(PointLight { quadratic: 0.001, radius: 0.8, ..PointLight::at(Vec3::new(3.0, 14.0, 2.0)) });
    s.views.push(View {
        name: "overview".into(),
        camera: Camera::look_at(Vec3::new(-17.0, 7.0, -15.0), Vec3::new(5.0, 1.0, 5.0), Vec3::Y, 65.0),
    });
    s.views.push(View {
        name: "floor".into(),
        camera: Camera::look_at(Vec3::new(0.0, 1.7, -18.0), Vec3::new(0.0, 2.5, 0.0), Vec3::Y, 70.0),
    });
    m.build()
}
