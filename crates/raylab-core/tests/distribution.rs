//! The distribution ray tracer (MBVH RS paper's workload): the same image with every method, progressive
//! passes that add new samples, and depth of field that blurs only what is out of focus.

mod common;

use glam::Vec3;
use raylab_core::distribution::{Accumulator, DistributionSettings, render_pass};
use raylab_core::method::Method;
use raylab_core::trace::{TraceOptions, Tracer};
use raylab_scene::builtin::{self, Detail};

fn settings() -> DistributionSettings {
    DistributionSettings { width: 24, height: 16, tile: 4, spp: 4, bounces: 2, ..DistributionSettings::default() }
}

#[test]
fn every_method_traces_the_same_paths() {
    let scene = builtin::build("atrium", Detail::Test).unwrap();
    let methods = [Method::Mono, Method::Packet, Method::Mft, Method::Mbvh, Method::MbvhRs, Method::Dacrt];
    let structures = common::structures(&scene, &methods);
    let cam = scene.default_view().unwrap().camera;
    let light = scene.lights[0];
    let s = settings();
    let image = |method| {
        let tracer = Tracer::new(&structures, TraceOptions { method, ..TraceOptions::default() }).unwrap();
        let mut acc = Accumulator::new(s.width, s.height);
        let stats = render_pass(&scene, &tracer, &cam, light, &s, 0, &mut acc);
        assert_eq!(stats.len(), 3, "camera rays and two bounces");
        assert_eq!(stats[0].rays, (s.width * s.height * s.spp) as u64);
        assert!(stats[1].rays > 0 && stats[1].rays <= stats[0].rays);
        acc.rgba()
    };
    let want = image(Method::Mono);
    assert!(want.iter().any(|p| p[0] > 30), "the image is not black");
    for method in [Method::Packet, Method::Mft, Method::Mbvh, Method::MbvhRs, Method::Dacrt] {
        let got = image(method);
        let diff = got.iter().zip(&want).filter(|(a, b)| a != b).count();
        assert_eq!(diff, 0, "{method}: {diff} pixels differ from mono");
    }
}

#[test]
fn passes_accumulate_new_samples() {
    let scene = builtin::build("arena", Detail::Test).unwrap();
    let structures = common::structures(&scene, &[Method::Mono]);
    let tracer = Tracer::new(&structures, TraceOptions::default()).unwrap();
    let cam = scene.default_view().unwrap().camera;
    let s = settings();
    let mut one = Accumulator::new(s.width, s.height);
    render_pass(&scene, &tracer, &cam, scene.lights[0], &s, 0, &mut one);
    let mut two = one.clone();
    render_pass(&scene, &tracer, &cam, scene.lights[0], &s, 1, &mut two);
    assert_eq!((one.paths, two.paths), (4, 8));
    assert_ne!(one.sum, two.sum.iter().map(|c| *c * 0.5).collect::<Vec<Vec3>>(), "pass 1 draws new samples");
    let mut again = Accumulator::new(s.width, s.height);
    render_pass(&scene, &tracer, &cam, scene.lights[0], &s, 0, &mut again);
    assert_eq!(again.sum, one.sum, "a pass is reproducible");
}

#[test]
fn depth_of_field_keeps_the_focus_plane_sharp() {
    let scene = builtin::build("atrium", Detail::Test).unwrap();
    let structures = common::structures(&scene, &[Method::Mono]);
    let tracer = Tracer::new(&structures, TraceOptions::default()).unwrap();
    let mut cam = scene.default_view().unwrap().camera;
    let pin = cam.raster(9, 9).lens_ray(4.5, 4.5, glam::Vec2::ZERO);
    cam.aperture = 0.3;
    let raster = cam.raster(9, 9);
    // Every lens point sends the centre ray through the same point on the plane in focus.
    let forward = (cam.target - cam.eye).normalize();
    let focus = pin.origin + pin.dir * (cam.focus_distance / pin.dir.dot(forward));
    for lens in [glam::Vec2::new(1.0, 0.0), glam::Vec2::new(-0.5, 0.5), glam::Vec2::new(0.0, -1.0)] {
        let r = raster.lens_ray(4.5, 4.5, lens);
        assert!((r.origin - cam.eye).length() > 0.1, "the lens point moves the origin");
        let t = (focus - r.origin).dot(r.dir);
        assert!((r.at(t) - focus).length() < 1e-4, "{lens}: misses the focus point");
    }
    let mut acc = Accumulator::new(8, 8);
    let s = DistributionSettings { width: 8, height: 8, ..settings() };
    render_pass(&scene, &tracer, &cam, scene.lights[0], &s, 0, &mut acc);
    assert!(acc.sum.iter().all(|c| c.is_finite()));
}
