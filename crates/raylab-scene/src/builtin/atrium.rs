//! `atrium`: a Sponza-style courtyard (the thesis's Sponza, 67k triangles): a floor, two storeys of round
//! arches on columns with moulded bases and capitals along both long sides, a gallery railing of turned
//! balusters, outer walls with windows, hanging cloth drapes (thin open geometry), a mirror ball on a
//! pedestal and a glass block. The long axis is x, +y is up.

use glam::{Affine3A, Vec3};
use raylab_core::scene::{Camera, Material, PointLight, Scene, View};

use super::Detail;
use crate::mesh::MeshBuilder;

const HALF_LEN: f32 = 15.0;
const HALF_WIDTH: f32 = 6.5;
const ARCADE_Z: f32 = 4.0;
const BAY: f32 = 3.0;
const GALLERY_Y: f32 = 6.0;
const TOP_Y: f32 = 12.0;

pub(super) fn build(d: Detail) -> Scene {
    let mut m = MeshBuilder::new();
    let seg = d.pick(32, 8);
    let stone = m.material(Material::diffuse("stone", Vec3::new(0.74, 0.68, 0.58)));
    let marble = m.material(Material::specular("marble", Vec3::new(0.86, 0.84, 0.8), 48.0, 0.3));
    let floor = m.material(Material::specular("floor", Vec3::new(0.55, 0.5, 0.45), 16.0, 0.15));

    m.use_material(floor);
    m.cuboid(Vec3::new(-HALF_LEN - 0.5, -0.3, -HALF_WIDTH - 0.5), Vec3::new(HALF_LEN + 0.5, 0.0, HALF_WIDTH + 0.5));

    let bays = d.pick(9, 3) as i32;
    for side in [-1.0f32, 1.0] {
        let z = side * ARCADE_Z;
        for (storey, (y0, height)) in [(0.0f32, 4.0f32), (GALLERY_Y, 3.0)].into_iter().enumerate() {
            for i in 0..bays {
                let x = (i - bays / 2) as f32 * BAY;
                m.use_material(marble);
                column(&mut m, Vec3::new(x, y0, z), height, seg);
                if i + 1 < bays {
                    m.use_material(stone);
                    let cx = x + BAY * 0.5;
                    let spring = y0 + height + 0.35;
                    m.arch(Vec3::new(cx, spring, z), BAY * 0.5 - 0.3, BAY * 0.5, 0.6, seg * 3 / 4);
                    // The wall band above the arch up to the next floor.
                    let top = if storey == 0 { GALLERY_Y - 0.4 } else { TOP_Y - 1.0 };
                    m.cuboid(Vec3::new(x, spring + BAY * 0.5, z - 0.3), Vec3::new(x + BAY, top, z + 0.3));
                    if storey == 1 {
                        railing(&mut m, x, z, seg, d);
                        drape(&mut m, cx, z - side * 0.35, spring + 0.9, d, (i as usize + side as usize) % 3);
                    }
                }
            }
        }
        // Gallery floor between the arcade and the outer wall.
        m.use_material(stone);
        let (z0, z1) = if side > 0.0 { (ARCADE_Z - 0.3, HALF_WIDTH) } else { (-HALF_WIDTH, -ARCADE_Z + 0.3) };
        let span = (bays / 2) as f32 * BAY + 0.5;
        m.cuboid(Vec3::new(-span, GALLERY_Y - 0.4, z0), Vec3::new(span, GALLERY_Y, z1));
        // Outer long wall with a row of windows on each storey.
        let zw = side * (HALF_WIDTH + 0.25);
        windowed_wall(&mut m, zw, 0.25, bays, d);
    }
    // Short end walls.
    m.use_material(stone);
    for side in [-1.0f32, 1.0] {
        let x = side * HALF_LEN;
        m.cuboid(Vec3::new(x - 0.25, 0.0, -HALF_WIDTH), Vec3::new(x + 0.25, TOP_Y, HALF_WIDTH));
    }

    // Mirror ball on a pedestal and a glass block.
    let mirror = m.material(Material::mirror("mirror ball", Vec3::new(0.9, 0.9, 0.95), 0.85));
    m.use_material(marble);
    m.lathe(Vec3::ZERO, &[(0.0, 0.0), (0.7, 0.0), (0.7, 0.2), (0.4, 0.4), (0.35, 1.2), (0.6, 1.4), (0.0, 1.4)], seg);
    m.use_material(mirror);
    m.sphere(Vec3::new(0.0, 2.4, 0.0), 1.0, d.pick(32, 8), d.pick(48, 12));
    m.material(Material::glass("glass block", Vec3::new(0.9, 0.97, 1.0), 1.5, Vec3::new(0.05, 0.02, 0.01)));
    m.with_transform(Affine3A::from_rotation_y(0.5), |m| {
        m.cuboid(Vec3::new(4.0, 0.0, 0.5), Vec3::new(5.6, 1.6, 2.1));
    });

    let s = m.scene_mut();
    let light = PointLight { quadratic: 0.002, radius: 0.6, ..PointLight::at(Vec3::new(0.0, 11.0, 0.0)) };
    s.lights.push(light);
    let view = |name: &str, eye: Vec3, target: Vec3, fov: f32| View {
        name: name.into(),
        camera: Camera::look_at(eye, target, Vec3::Y, fov),
    };
    s.views.push(view("nave", Vec3::new(-12.5, 2.5, 0.0), Vec3::new(10.0, 5.5, 0.0), 65.0));
    s.views.push(view("gallery", Vec3::new(-10.0, 7.8, 5.2), Vec3::new(6.0, 4.0, -3.0), 60.0));
    s.views.push(view("ball", Vec3::new(3.0, 2.0, 6.0), Vec3::new(0.0, 2.2, 0.0), 50.0));
    m.build()
}

/// A column: square plinth, torus base moulding, shaft, torus capital and square abacus.
fn column(m: &mut MeshBuilder, base: Vec3, height: f32, seg: u32) {
    let r = 0.3;
    m.cuboid(base + Vec3::new(-0.45, 0.0, -0.45), base + Vec3::new(0.45, 0.15, 0.45));
    m.torus(base + Vec3::Y * 0.25, r + 0.05, 0.1, seg, seg / 4);
    m.cylinder(base + Vec3::Y * 0.15, r, height - 0.3, seg);
    m.torus(base + Vec3::Y * (height - 0.25), r + 0.05, 0.1, seg, seg / 4);
    m.cuboid(base + Vec3::new(-0.45, height - 0.15, -0.45), base + Vec3::new(0.45, height + 0.35, 0.45));
}

/// Balusters and a hand rail across the gallery bay that starts at `x`.
fn railing(m: &mut MeshBuilder, x: f32, z: f32, seg: u32, d: Detail) {
    let n = d.pick(5, 2);
    let y = GALLERY_Y;
    let profile = [(0.0, 0.0), (0.09, 0.0), (0.09, 0.1), (0.05, 0.25), (0.08, 0.5), (0.04, 0.8), (0.0, 0.8)];
    for k in 0..n {
        let bx = x + 0.6 + (BAY - 1.2) * (k as f32 + 0.5) / n as f32;
        m.lathe(Vec3::new(bx, y, z), &profile, (seg / 2).max(4));
    }
    m.cuboid(Vec3::new(x + 0.45, y + 0.8, z - 0.1), Vec3::new(x + BAY - 0.45, y + 0.95, z + 0.1));
}

/// A cloth drape hanging from a rod: an open, folded sheet.
fn drape(m: &mut MeshBuilder, cx: f32, z: f32, top: f32, d: Detail, colour: usize) {
    let colours = [Vec3::new(0.6, 0.08, 0.08), Vec3::new(0.1, 0.35, 0.15), Vec3::new(0.12, 0.15, 0.5)];
    m.material(Material::diffuse("cloth", colours[colour % 3]));
    let (w, h) = (BAY - 1.1, 2.6);
    m.grid(d.pick(16, 3), d.pick(24, 3), |u, v| {
        let fold = 0.12 * (u * 6.0 * std::f32::consts::PI).sin() * (0.3 + v);
        Vec3::new(cx - w * 0.5 + w * u, top - h * v, z + fold + 0.25 * v * v)
    });
}

/// An outer wall at `z`, built of solid courses and piers so that each storey has a window per bay.
fn windowed_wall(m: &mut MeshBuilder, z: f32, half_thick: f32, bays: i32, d: Detail) {
    let (z0, z1) = (z - half_thick, z + half_thick);
    let span = HALF_LEN;
    let windows: Vec<(f32, f32)> = vec![(1.2, 3.2), (7.2, 10.0)];
    let mut y = 0.0;
    for &(w0, w1) in &windows {
        m.cuboid(Vec3::new(-span, y, z0), Vec3::new(span, w0, z1));
        // Piers between the window openings.
        let piers = d.pick(bays as u32 + 1, 4);
        let step = 2.0 * span / (piers - 1) as f32;
        for k in 0..piers {
            let px = -span + step * k as f32;
            let (a, b) = ((px - 0.6).max(-span), (px + 0.6).min(span));
            m.cuboid(Vec3::new(a, w0, z0), Vec3::new(b, w1, z1));
        }
        y = w1;
    }
    m.cuboid(Vec3::new(-span, y, z0), Vec3::new(span, TOP_Y, z1));
}
