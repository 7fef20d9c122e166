//! The CPU half of the hybrid (G-buffer) mode: reflection rays built from a G-buffer and shaded one bounce deep
//! reproduce the Whitted renderer's first reflections, for every method and shadow technique; on a perfect
//! mirror they are exactly the Whitted frame's pixels.

mod common;

use glam::Vec3;
use raylab_core::method::Method;
use raylab_core::render::hybrid::{cpu_gbuffer, psnr, reference_reflections, reflection_ray, shade_reflections};
use raylab_core::render::shade::to_display;
use raylab_core::render::{RenderSettings, render, surface_epsilon};
use raylab_core::scene::{Camera, Material, PointLight};
use raylab_core::shadow::Shadows;
use raylab_core::trace::{TraceOptions, Tracer};
use raylab_scene::MeshBuilder;
use raylab_scene::builtin::{self, Detail};

#[test]
fn gbuffer_reflections_match_the_whitted_renderer() {
    let scene = builtin::build("atrium", Detail::Test).unwrap();
    let methods = [Method::Mono, Method::Mft, Method::Mbvh, Method::Dacrt];
    let structures = common::structures(&scene, &methods);
    let cam = scene.default_view().unwrap().camera;
    let light = scene.lights[0];
    let mono = Tracer::new(&structures, TraceOptions::default()).unwrap();
    for shadows in [Shadows::Hard, Shadows::None, Shadows::Cached] {
        let settings = RenderSettings { width: 96, height: 72, shadows, ..RenderSettings::default() };
        let want = reference_reflections(&scene, &mono, &cam, light, &settings);
        let reflective = want.iter().filter(|c| c.is_some()).count();
        assert!(reflective > 50, "the view shows the mirror ball ({reflective} reflective pixels)");
        let g = cpu_gbuffer(&scene, &mono, &cam, settings.width, settings.height);
        let eps = surface_epsilon(&scene);
        let rays: Vec<_> = g.iter().map(|p| reflection_ray(cam.eye, p, eps)).collect();
        assert_eq!(rays.iter().filter(|r| r.is_some()).count(), reflective, "the same pixels are reflective");
        for method in methods {
            let tracer = Tracer::new(&structures, TraceOptions { method, ..TraceOptions::default() }).unwrap();
            let (got, stats, _) = shade_reflections(&scene, &tracer, &cam, light, &settings, &rays);
            assert!(stats.rays >= reflective as u64);
            let pairs = got.iter().zip(&want).filter_map(|(g, w)| w.map(|w| (*g, w)));
            let db = psnr(pairs).unwrap();
            // The G-buffer's rays leave along the shading normal, the renderer's along the geometric one.
            assert!(db >= 45.0, "{shadows} {method}: {db:.1} dB");
        }
    }
}

#[test]
fn on_a_perfect_mirror_the_reflection_is_the_whitted_pixel() {
    let mut m = MeshBuilder::new();
    m.material(Material::diffuse("floor", Vec3::new(0.8, 0.3, 0.2)));
    m.cuboid(Vec3::new(-4.0, -1.0, -4.0), Vec3::new(4.0, -0.9, 4.0));
    m.material(Material::diffuse("box", Vec3::new(0.2, 0.7, 0.3)));
    m.cuboid(Vec3::new(-1.0, -0.9, 1.0), Vec3::new(1.0, 1.0, 2.0));
    m.material(Material::mirror("mirror", Vec3::ONE, 1.0));
    m.cuboid(Vec3::new(-3.0, -0.9, -2.2), Vec3::new(3.0, 2.5, -2.0));
    m.scene_mut().lights.push(PointLight::at(Vec3::new(0.0, 3.0, 3.0)));
    let scene = m.build();
    let structures = common::structures(&scene, &[Method::Mono]);
    let tracer = Tracer::new(&structures, TraceOptions::default()).unwrap();
    let cam = Camera {
        eye: Vec3::new(0.5, 0.8, 4.5),
        target: Vec3::new(0.0, 0.5, -2.0),
        up: Vec3::Y,
        vfov_deg: 60.0,
        aperture: 0.0,
        focus_distance: 1.0,
    };
    let light = scene.lights[0];
    let settings = RenderSettings { width: 80, height: 60, max_depth: 1, ..RenderSettings::default() };
    let frame = render(&scene, &tracer, &cam, light, &settings);
    let want = reference_reflections(&scene, &tracer, &cam, light, &settings);
    let mut compared = 0;
    for (px, r) in frame.rgba.iter().zip(&want) {
        if let Some(c) = r {
            assert_eq!([px[0], px[1], px[2]], [to_display(c.x), to_display(c.y), to_display(c.z)]);
            compared += 1;
        }
    }
    assert!(compared > 300, "{compared} mirror pixels");
}
