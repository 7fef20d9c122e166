//! Bundles walked under a proxy built from a spherical light (the cone and the circumscribed pyramid of thesis
//! 4.1.9) report the same occlusion as the brute-force reference for every ray toward the light: samples on
//! the disc the renderer uses, points anywhere inside the sphere, lights of every size, lights inside
//! geometry, and points right next to the light, on every built-in scene, SIMD backend and culling setting.

use glam::Vec3;
use raylab_core::kdtree::{KdParams, KdTree};
use raylab_core::method::Method;
use raylab_core::packet::{Cone, Frustum};
use raylab_core::ray::Ray;
use raylab_core::reference::BruteForce;
use raylab_core::scene::Scene;
use raylab_core::shadow::LightSamples;
use raylab_core::stats::TraversalStats;
use raylab_core::trace::{Proxy, TraceOptions, Tracer};
use raylab_core::workload::{RayKind, WorkloadBuilder};
use raylab_scene::builtin::{self, Detail};
use raylab_simd::Backend;

/// A small deterministic generator of numbers in `[0, 1)`.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }

    /// A point inside the unit ball.
    fn in_ball(&mut self) -> Vec3 {
        loop {
            let p = Vec3::new(self.next(), self.next(), self.next()) * 2.0 - Vec3::ONE;
            if p.length_squared() <= 1.0 {
                return p;
            }
        }
    }
}

/// Points just in front of the surfaces the scene's default view sees (a shaded point's shadow-ray origin).
fn surface_points(scene: &Scene, tree: &KdTree, n: u32) -> Vec<Vec3> {
    let cam = scene.default_view().unwrap().camera;
    let wb = WorkloadBuilder::new(scene, &cam, scene.lights[0].position, n, n, tree);
    let mut stats = TraversalStats::default();
    wb.build(RayKind::Primary)
        .rays
        .iter()
        .flatten()
        .filter_map(|r| tree.intersect(r, &mut stats).map(|h| r.at(h.t) - r.dir * 1e-3))
        .collect()
}

/// Checks both proxies of the light (`center`, `radius`) seen from `apex` on `targets` against brute force.
fn check(tree: &KdTree, bf: &BruteForce, apex: Vec3, center: Vec3, radius: f32, targets: &[Vec3], what: &str) {
    let rays: Vec<Option<Ray>> = targets
        .iter()
        .map(|&p| {
            let v = p - apex;
            let d = v.length();
            (d > 0.0).then(|| Ray::segment(apex, v / d, 0.0, d))
        })
        .collect();
    let mut stats = TraversalStats::default();
    let want: Vec<bool> = rays.iter().map(|r| r.is_some_and(|r| bf.occluded(&r, &mut stats))).collect();
    let proxies = [
        Frustum::around_sphere(apex, center, radius).map(Proxy::Pyramid),
        Cone::around_sphere(apex, center, radius).map(Proxy::Cone),
    ];
    for proxy in proxies.iter().flatten() {
        for backend in Backend::available() {
            for cull in [true, false] {
                let opts = TraceOptions { method: Method::Packet, cull, backend, ..TraceOptions::default() };
                let tracer = Tracer::new(tree, None, opts);
                let mut got = vec![false; rays.len()];
                let size = (4, rays.len() / 4);
                tracer.occluded_in_proxy(proxy, &rays, size, &mut got, &mut stats);
                assert_eq!(got, want, "{what}: {proxy:?} {backend:?} cull {cull}");
            }
        }
    }
}

/// Checks the proxies of each light seen from each of `apexes`, on its disc samples and on points in its volume.
fn check_scene(scene: &Scene, apexes: &[Vec3], lights: &[(Vec3, f32)], what: &str) {
    let tree = KdTree::build(scene, &KdParams::default()).unwrap();
    let bf = BruteForce::new(scene);
    let mut rng = Rng(0x5eed);
    let mut samples = LightSamples::default();
    for (i, &apex) in apexes.iter().enumerate() {
        for &(center, radius) in lights {
            samples.generate(center, radius, apex, 16, i as u32);
            check(&tree, &bf, apex, center, radius, &samples.points, what);
            let inside: Vec<Vec3> = (0..32).map(|_| center + rng.in_ball() * radius).collect();
            check(&tree, &bf, apex, center, radius, &inside, what);
        }
    }
}

#[test]
fn proxies_match_brute_force_on_every_builtin_scene() {
    for name in builtin::names() {
        let scene = builtin::build(name, Detail::Test).unwrap();
        let light = scene.lights[0].position;
        let span = scene.bounds().max - scene.bounds().min;
        let lights = [(light, 1.0), (light, 0.05), (light, span.max_element() * 0.3), (scene.bounds().center(), 2.0)];
        let tree = KdTree::build(&scene, &KdParams::default()).unwrap();
        check_scene(&scene, &surface_points(&scene, &tree, 12), &lights, name);
    }
}

#[test]
fn proxies_hold_next_to_the_light_and_far_from_the_origin() {
    let scene = builtin::build("arena", Detail::Test).unwrap();
    let tree = KdTree::build(&scene, &KdParams::default()).unwrap();
    let bf = BruteForce::new(&scene);
    let center = scene.lights[0].position;
    // Just outside the sphere the cone opens to its widest and then there is no proxy.
    for gap in [1.0f32, 0.1, 0.01, 1e-4] {
        let apex = center + Vec3::new(0.3, -1.0, 0.2).normalize() * (1.0 + gap);
        let targets: Vec<Vec3> = (0..16).map(|k| center + Vec3::new((k % 4) as f32 - 1.5, 0.0, 0.0) * 0.5).collect();
        check(&tree, &bf, apex, center, 1.0, &targets, &format!("gap {gap}"));
    }
    assert!(Cone::around_sphere(center, center, 1.0).is_none(), "an apex inside the light has no proxy");
    assert!(Frustum::around_sphere(center + Vec3::X * 0.5, center, 1.0).is_none());
    assert!(Cone::around_sphere(Vec3::ZERO, Vec3::new(f32::NAN, 0.0, 0.0), 1.0).is_none());
    // A scene shifted far from the origin: coordinates carry large absolute rounding errors.
    let shift = Vec3::new(1.0e5, -2.0e5, 3.0e5);
    let apexes: Vec<Vec3> = surface_points(&scene, &tree, 10).into_iter().map(|p| p + shift).collect();
    let mut far = scene.clone();
    let moved: Vec<Vec3> = far.positions.iter().map(|&p| p + shift).collect();
    far.set_vertices(0, &moved, None).unwrap();
    check_scene(&far, &apexes, &[(center + shift, 1.0), (center + shift, 20.0)], "shifted arena");
}
