//! The fixed-function materials (thesis Listing 4.7) and their secondary rays, against known answers: a
//! mirror shows what it should where it should, clear glass of index 1 changes nothing, Beer's law darkens
//! with thickness, and light inside glass past the critical angle reflects.

mod common;

use glam::Vec3;
use raylab_core::method::Method;
use raylab_core::render::{Frame, RenderSettings, render};
use raylab_core::scene::{Camera, Material, MaterialKind, PointLight, Scene};
use raylab_core::shadow::Shadows;
use raylab_core::trace::{TraceOptions, Tracer};
use raylab_scene::mesh::MeshBuilder;

fn draw(scene: &Scene, cam: &Camera, size: (u32, u32), method: Method) -> Frame {
    let structures = common::structures(scene, &[method]);
    let tracer = Tracer::new(&structures, TraceOptions { method, ..Default::default() }).unwrap();
    let settings =
        RenderSettings { width: size.0, height: size.1, tile: 8, shadows: Shadows::None, ..Default::default() };
    render(scene, &tracer, cam, scene.lights[0], &settings)
}

/// The pixel whose primary ray points most nearly at `p`.
fn pixel_toward(cam: &Camera, size: (u32, u32), p: Vec3) -> (u32, u32) {
    let raster = cam.raster(size.0, size.1);
    let want = (p - cam.eye).normalize();
    let mut best = (0, 0, -2.0f32);
    for y in 0..size.1 {
        for x in 0..size.0 {
            let c = raster.primary(x, y).dir.normalize().dot(want);
            if c > best.2 {
                best = (x, y, c);
            }
        }
    }
    (best.0, best.1)
}

fn at(f: &Frame, (x, y): (u32, u32)) -> [u8; 4] {
    f.rgba[(y * f.width + x) as usize]
}

fn floor(m: &mut MeshBuilder, y: f32, half: f32) {
    m.quad(Vec3::new(-half, y, half), Vec3::new(half, y, half), Vec3::new(half, y, -half), Vec3::new(-half, y, -half));
}

/// A red box over a mirror floor: its reflection appears at the pixel that looks at its mirror image, for
/// single rays and packets alike.
#[test]
fn a_mirror_shows_the_reflection_at_the_predicted_pixel() {
    let mut m = MeshBuilder::new();
    m.material(Material { reflect_blend: 1.0, ..Material::mirror("mirror", Vec3::ONE, 1.0) });
    floor(&mut m, 0.0, 30.0);
    m.material(Material::diffuse("red", Vec3::new(1.0, 0.0, 0.0)));
    let centre = Vec3::new(0.0, 1.5, -6.0);
    m.cuboid(centre - Vec3::splat(0.5), centre + Vec3::splat(0.5));
    let mut scene = m.build();
    scene.lights.push(PointLight::at(Vec3::new(0.0, 8.0, 0.0)));
    let cam = Camera::look_at(Vec3::new(0.0, 3.0, 4.0), Vec3::new(0.0, -1.0, -6.0), Vec3::Y, 50.0);
    let size = (96, 72);
    let mirrored = Vec3::new(centre.x, -centre.y, centre.z);
    for method in [Method::Mono, Method::Packet, Method::Mft] {
        let f = draw(&scene, &cam, size, method);
        let [r, g, b, _] = at(&f, pixel_toward(&cam, size, mirrored));
        assert!(r > 100 && g < 10 && b < 10, "{method}: the mirror image of the red box is ({r}, {g}, {b})");
        let [r, g, b, _] = at(&f, pixel_toward(&cam, size, centre));
        assert!(r > 100 && g < 10 && b < 10, "{method}: the box itself is ({r}, {g}, {b})");
        // Between the box and its image the mirror shows the black sky.
        let [r, g, b, _] = at(&f, pixel_toward(&cam, size, Vec3::new(3.0, 0.0, -6.0)));
        assert!(r < 10 && g < 10 && b < 10, "{method}: the mirror off the box is ({r}, {g}, {b})");
    }
    // With no bounces allowed the mirror is its own dim base colour, and the image is gone.
    let structures = common::structures(&scene, &[Method::Mono]);
    let tracer = Tracer::new(&structures, TraceOptions::default()).unwrap();
    let s =
        RenderSettings { width: size.0, height: size.1, shadows: Shadows::None, max_depth: 0, ..Default::default() };
    let f = render(&scene, &tracer, &cam, scene.lights[0], &s);
    let [r, g, _, _] = at(&f, pixel_toward(&cam, size, mirrored));
    assert!(r == g, "depth 0 shows no reflection");
}

/// A wall of coloured tiles, a light, a camera looking at it, and optionally a glass slab in between.
fn tiles_behind(slab: Option<(Material, f32)>) -> (Scene, Camera) {
    let mut m = MeshBuilder::new();
    let colours = [Vec3::new(0.9, 0.2, 0.1), Vec3::new(0.1, 0.8, 0.3), Vec3::new(0.2, 0.3, 0.9), Vec3::splat(0.9)];
    for i in 0..6 {
        for j in 0..4 {
            m.material(Material::diffuse("tile", colours[(i + j) % 4]));
            let (x, y) = (-3.0 + i as f32, -2.0 + j as f32);
            m.quad(
                Vec3::new(x, y, -5.0),
                Vec3::new(x + 1.0, y, -5.0),
                Vec3::new(x + 1.0, y + 1.0, -5.0),
                Vec3::new(x, y + 1.0, -5.0),
            );
        }
    }
    if let Some((glass, thickness)) = slab {
        m.material(glass);
        m.cuboid(Vec3::new(-10.0, -10.0, -2.0 - thickness), Vec3::new(10.0, 10.0, -2.0));
    }
    let mut scene = m.build();
    scene.lights.push(PointLight::at(Vec3::new(0.5, 0.5, 3.0)));
    (scene, Camera::look_at(Vec3::new(0.2, 0.1, 4.0), Vec3::new(0.0, 0.0, -5.0), Vec3::Y, 60.0))
}

fn clear_glass(ior: f32, absorption: Vec3) -> Material {
    Material {
        kind: MaterialKind::Transparent,
        transmit_blend: 1.0,
        ior,
        absorption,
        ..Material::diffuse("glass", Vec3::new(1.0, 0.0, 1.0))
    }
}

/// Index 1 and no absorption: the slab is no interface at all, and the image is the one without it.
#[test]
fn glass_of_index_one_leaves_the_image_unchanged() {
    let size = (80, 60);
    let (bare, cam) = tiles_behind(None);
    let want = draw(&bare, &cam, size, Method::Mono);
    for kind in [MaterialKind::Transparent, MaterialKind::TransparentReflective] {
        let glass = Material { kind, reflect_blend: 0.0, specular_blend: 0.0, ..clear_glass(1.0, Vec3::ZERO) };
        let (scene, _) = tiles_behind(Some((glass, 1.5)));
        for method in [Method::Mono, Method::Mft] {
            let got = draw(&scene, &cam, size, method);
            let off: Vec<u8> = got
                .rgba
                .iter()
                .zip(&want.rgba)
                .map(|(a, b)| (0..3).map(|k| a[k].abs_diff(b[k])).max().unwrap())
                .collect();
            let far = off.iter().filter(|&&d| d > 1).count();
            assert!(far * 200 <= off.len(), "{kind:?}, {method}: {far} pixels changed by more than one level");
            assert!(
                off.iter().filter(|&&d| d == 0).count() * 10 >= off.len() * 9,
                "{kind:?}: most pixels are identical"
            );
        }
    }
}

/// Beer's law: through a slab of thickness s absorbing c per unit, the light left is exp(-c s).
#[test]
fn beer_darkens_with_thickness_exponentially() {
    let size = (40, 30);
    let (bare, cam) = tiles_behind(None);
    let lin = |v: u8| (v as f32 / 255.0).powf(2.2);
    let c = Vec3::new(0.3, 0.6, 0.1);
    let base = draw(&bare, &cam, size, Method::Mono);
    for thickness in [0.5f32, 1.0, 2.0] {
        let (scene, _) = tiles_behind(Some((clear_glass(1.0, c), thickness)));
        let f = draw(&scene, &cam, size, Method::Mono);
        let mut checked = 0;
        for (a, b) in f.rgba.iter().zip(&base.rgba) {
            for k in 0..3 {
                if b[k] < 120 {
                    continue;
                }
                // The rays are nearly head-on: their path in the slab is thickness / cos, within 5%.
                let got = lin(a[k]) / lin(b[k]);
                let want = (-c[k] * thickness).exp();
                let path = (-c[k] * thickness * 1.05).exp();
                assert!(
                    got <= want * 1.03 + 0.01 && got >= path * 0.97 - 0.01,
                    "s {thickness}, channel {k}: {got} vs exp(-c s) = {want}"
                );
                checked += 1;
            }
        }
        assert!(checked > 200, "only {checked} channels checked");
    }
}

/// Looking out of a glass block at 60 degrees from the normal (critical angle 41.8 degrees at index 1.5) the
/// top face is a mirror and shows the red tile inside; at 12 degrees the ray leaves and sees the green sky
/// panel above.
#[test]
fn past_the_critical_angle_glass_reflects_totally() {
    let mut m = MeshBuilder::new();
    m.material(Material { ior: 1.5, ..clear_glass(1.5, Vec3::ZERO) });
    m.cuboid(Vec3::new(-10.0, -10.0, -10.0), Vec3::new(10.0, 1.0, 10.0));
    m.material(Material::diffuse("red", Vec3::new(1.0, 0.0, 0.0)));
    m.quad(
        Vec3::new(2.0, -0.5, 3.0),
        Vec3::new(8.0, -0.5, 3.0),
        Vec3::new(8.0, -0.5, -3.0),
        Vec3::new(2.0, -0.5, -3.0),
    );
    m.material(Material::diffuse("green", Vec3::new(0.0, 1.0, 0.0)));
    m.quad(
        Vec3::new(-30.0, 3.0, -30.0),
        Vec3::new(30.0, 3.0, -30.0),
        Vec3::new(30.0, 3.0, 30.0),
        Vec3::new(-30.0, 3.0, 30.0),
    );
    let mut scene = m.build();
    scene.lights.push(PointLight::at(Vec3::new(4.0, 0.5, 0.0)));
    let eye = Vec3::ZERO;
    for (angle, want_red) in [(60.0f32, true), (12.0, false)] {
        let a = angle.to_radians();
        let cam = Camera::look_at(eye, eye + Vec3::new(a.sin(), a.cos(), 0.0), Vec3::Z, 1.0);
        let f = draw(&scene, &cam, (3, 3), Method::Mono);
        let [r, g, _, _] = at(&f, (1, 1));
        if want_red {
            assert!(r > 30 && g == 0, "at {angle} degrees: ({r}, {g}), expected the red tile by reflection");
        } else {
            assert!(g > 30 && r == 0, "at {angle} degrees: ({r}, {g}), expected the green panel through the glass");
        }
    }
}
