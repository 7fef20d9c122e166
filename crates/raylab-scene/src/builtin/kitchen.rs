//! `kitchen`: the thesis's "transformed kitchen" (110k polygons): a room with cabinets, a table and chairs
//! laden with plates, bowls, cups, bottles, pots and fruit, all solids of revolution or boxes, and the whole
//! scene rotated off the coordinate axes so that almost no polygon is axis-aligned.

use glam::{Affine3A, Quat, Vec3};
use raylab_core::scene::{Camera, Material, PointLight, Scene, View};

use super::Detail;
use crate::mesh::{Jitter, MeshBuilder};

pub(super) fn build(d: Detail) -> Scene {
    let mut m = MeshBuilder::new();
    let tilt = Affine3A::from_quat(Quat::from_axis_angle(Vec3::new(0.3, 1.0, 0.2).normalize(), 0.45));
    m.set_transform(tilt);
    let mut rng = Jitter::new(7);
    let seg = d.pick(48, 8);

    m.material(Material::diffuse("floor", Vec3::new(0.6, 0.55, 0.5)));
    let tiles = d.pick(20, 3);
    let size = 10.0 / tiles as f32;
    for j in 0..tiles {
        for i in 0..tiles {
            let (x, z) = (-5.0 + i as f32 * size, -5.0 + j as f32 * size);
            m.cuboid(Vec3::new(x + 0.01, -0.1, z + 0.01), Vec3::new(x + size - 0.01, 0.0, z + size - 0.01));
        }
    }
    m.material(Material::diffuse("wall", Vec3::new(0.8, 0.78, 0.7)));
    m.cuboid(Vec3::new(-5.2, 0.0, -5.2), Vec3::new(5.2, 4.0, -5.0));
    m.cuboid(Vec3::new(-5.2, 0.0, -5.0), Vec3::new(-5.0, 4.0, 5.2));

    m.material(Material::specular("cabinet", Vec3::new(0.55, 0.35, 0.2), 24.0, 0.2));
    let cabinets = d.pick(10, 2);
    for i in 0..cabinets {
        let x = -4.8 + i as f32 * 0.95;
        m.cuboid(Vec3::new(x, 0.0, -5.0), Vec3::new(x + 0.9, 0.9, -4.4));
        m.cuboid(Vec3::new(x + 0.05, 0.1, -4.4), Vec3::new(x + 0.85, 0.8, -4.37));
        m.cylinder(Vec3::new(x + 0.75, 0.45, -4.32), 0.02, 0.2, 12);
        m.cuboid(Vec3::new(x, 2.0, -5.0), Vec3::new(x + 0.9, 3.0, -4.65));
    }
    m.material(Material::specular("counter", Vec3::new(0.3, 0.3, 0.32), 64.0, 0.4));
    m.cuboid(Vec3::new(-5.0, 0.9, -5.0), Vec3::new(4.8, 0.96, -4.3));

    m.material(Material::specular("table", Vec3::new(0.5, 0.32, 0.18), 32.0, 0.25));
    m.cuboid(Vec3::new(-1.5, 0.75, -1.0), Vec3::new(1.5, 0.82, 1.0));
    for (x, z) in [(-1.35, -0.85), (1.35, -0.85), (-1.35, 0.85), (1.35, 0.85)] {
        m.lathe(Vec3::new(x, 0.0, z), &[(0.0, 0.0), (0.05, 0.0), (0.04, 0.4), (0.06, 0.75), (0.0, 0.75)], 16);
    }
    for (x, z, r) in [
        (0.0, -1.5, 0.0),
        (0.0, 1.5, std::f32::consts::PI),
        (-2.0, 0.0, std::f32::consts::FRAC_PI_2),
        (2.0, 0.0, -std::f32::consts::FRAC_PI_2),
    ] {
        let at = Affine3A::from_translation(Vec3::new(x, 0.0, z)) * Affine3A::from_rotation_y(r);
        m.with_transform(at, chair);
    }

    let plates = d.pick(40, 2);
    let bowls = d.pick(20, 1);
    let cups = d.pick(30, 2);
    let bottles = d.pick(30, 2);
    let pots = d.pick(8, 1);
    let fruit = d.pick(45, 2);
    let on_surface = |rng: &mut Jitter, i: u32| {
        if i.is_multiple_of(2) {
            Vec3::new(rng.range(-1.3, 1.3), 0.82, rng.range(-0.8, 0.8))
        } else {
            Vec3::new(rng.range(-4.6, 4.4), 0.96, rng.range(-4.9, -4.4))
        }
    };
    m.material(Material::specular("porcelain", Vec3::new(0.92, 0.92, 0.9), 96.0, 0.5));
    for i in 0..plates {
        let p = on_surface(&mut rng, i);
        let plate = [(0.0, 0.0), (0.07, 0.0), (0.09, 0.01), (0.13, 0.02), (0.14, 0.025), (0.0, 0.012)];
        m.lathe(p, &plate, seg);
    }
    for i in 0..bowls {
        let p = on_surface(&mut rng, i);
        let bowl = [(0.0, 0.0), (0.05, 0.0), (0.09, 0.04), (0.11, 0.08), (0.1, 0.08), (0.07, 0.03), (0.0, 0.02)];
        m.lathe(p, &bowl, seg);
    }
    m.material(Material::specular("cup", Vec3::new(0.8, 0.3, 0.2), 64.0, 0.4));
    for i in 0..cups {
        let p = on_surface(&mut rng, i);
        m.lathe(p, &[(0.0, 0.0), (0.035, 0.0), (0.045, 0.09), (0.0, 0.09)], seg / 2);
        let handle = Affine3A::from_translation(p + Vec3::new(0.05, 0.045, 0.0))
            * Affine3A::from_rotation_x(std::f32::consts::FRAC_PI_2);
        m.with_transform(handle, |m| m.torus(Vec3::ZERO, 0.025, 0.006, seg / 2, d.pick(8, 3)));
    }
    m.material(Material::glass("bottle glass", Vec3::new(0.7, 0.9, 0.75), 1.5, Vec3::new(0.4, 0.1, 0.3)));
    for i in 0..bottles {
        let p = on_surface(&mut rng, i);
        let bottle = [
            (0.0, 0.0),
            (0.04, 0.0),
            (0.045, 0.01),
            (0.045, 0.18),
            (0.035, 0.22),
            (0.015, 0.26),
            (0.013, 0.3),
            (0.016, 0.31),
            (0.0, 0.31),
        ];
        m.lathe(p, &bottle, seg * 2 / 3);
    }
    m.material(Material::mirror("steel pot", Vec3::new(0.7, 0.7, 0.72), 0.5));
    for i in 0..pots {
        let p = on_surface(&mut rng, i + 1);
        let pot = [(0.0, 0.0), (0.12, 0.0), (0.13, 0.01), (0.13, 0.14), (0.14, 0.15), (0.12, 0.15), (0.0, 0.02)];
        m.lathe(p, &pot, seg);
        m.torus(p + Vec3::Y * 0.15, 0.16, 0.008, seg, d.pick(8, 3));
    }
    m.material(Material::specular("fruit", Vec3::new(0.85, 0.55, 0.1), 40.0, 0.3));
    for i in 0..fruit {
        let p = on_surface(&mut rng, i);
        let r = rng.range(0.03, 0.05);
        m.sphere(p + Vec3::Y * r, r, d.pick(16, 4), d.pick(24, 6));
    }

    let s = m.scene_mut();
    let pos = tilt.transform_point3(Vec3::new(0.5, 3.6, 1.0));
    s.lights.push(PointLight { quadratic: 0.02, radius: 0.3, ..PointLight::at(pos) });
    let up = tilt.transform_vector3(Vec3::Y);
    let eye = tilt.transform_point3(Vec3::new(3.8, 1.9, 3.8));
    let target = tilt.transform_point3(Vec3::new(-0.8, 0.8, -1.2));
    s.views.push(View { name: "room".into(), camera: Camera::look_at(eye, target, up, 60.0) });
    let eye = tilt.transform_point3(Vec3::new(0.9, 1.3, 1.1));
    let target = tilt.transform_point3(Vec3::new(0.0, 0.82, 0.0));
    s.views.push(View { name: "table".into(), camera: Camera::look_at(eye, target, up, 55.0) });
    m.build()
}

/// A chair facing -z at the local origin.
fn chair(m: &mut MeshBuilder) {
    m.cuboid(Vec3::new(-0.22, 0.45, -0.22), Vec3::new(0.22, 0.5, 0.22));
    for (x, z) in [(-0.2, -0.2), (0.2, -0.2), (-0.2, 0.2), (0.2, 0.2)] {
        m.cuboid(Vec3::new(x - 0.02, 0.0, z - 0.02), Vec3::new(x + 0.02, 0.45, z + 0.02));
    }
    for k in 0..5 {
        let x = -0.2 + k as f32 * 0.1;
        m.cuboid(Vec3::new(x - 0.015, 0.5, 0.19), Vec3::new(x + 0.015, 0.95, 0.22));
    }
    m.cuboid(Vec3::new(-0.22, 0.95, 0.18), Vec3::new(0.22, 1.0, 0.23));
}
