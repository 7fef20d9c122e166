//! Bundles walked under a proxy built from a spherical light's face (the cone and the circumscribed pyramid of
//! thesis 4.1.9) report the same occlusion as the brute-force reference for every ray toward it: the
//! renderer's stratified samples, points anywhere on the disc, apexes lifted off the point the disc faces,
//! lights of every size, lights inside geometry, points right next to the light and far from the origin, on
//! every built-in scene, SIMD backend and culling setting.

use glam::Vec3;
use raylab_core::kdtree::{KdParams, KdTree};
use raylab_core::method::{Method, Purpose, Structure};
use raylab_core::packet::{Cone, Disc, Frustum};
use raylab_core::ray::Ray;
use raylab_core::reference::BruteForce;
use raylab_core::scene::Scene;
use raylab_core::shadow::LightSamples;
use raylab_core::stats::TraversalStats;
use raylab_core::structures::{StructureParams, Structures};
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

    /// A point inside the unit disc.
    fn in_disc(&mut self) -> (f32, f32) {
        loop {
            let (a, b) = (self.next() * 2.0 - 1.0, self.next() * 2.0 - 1.0);
            if a * a + b * b <= 1.0 {
                return (a, b);
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

/// Checks both proxies of `disc` seen from `apex` on `targets` against brute force.
/// The packet method's structures, on the thesis's kd-tree.
fn packets_on_thesis_tree(scene: &Scene) -> Structures {
    let params = StructureParams { packet_kd: KdParams::default(), ..StructureParams::default() };
    Structures::build(scene, &[Method::Packet], Purpose::Frames, &params).unwrap()
}

fn check(structures: &Structures, bf: &BruteForce, apex: Vec3, disc: &Disc, targets: &[Vec3], what: &str) {
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
    let proxies =
        [Frustum::around_disc(apex, disc).map(Proxy::Pyramid), Cone::around_disc(apex, disc).map(Proxy::Cone)];
    for proxy in proxies.iter().flatten() {
        for backend in Backend::available() {
            for cull in [true, false] {
                let opts = TraceOptions { method: Method::Packet, cull, backend, ..TraceOptions::default() };
                let tracer = Tracer::new(structures, opts).unwrap();
                let mut got = vec![false; rays.len()];
                let size = (4, rays.len() / 4);
                tracer.occluded_in_proxy(proxy, &rays, size, &mut got, &mut stats);
                assert_eq!(got, want, "{what}: {proxy:?} {backend:?} cull {cull}");
            }
        }
    }
}

/// Checks the proxies of each light seen from each of `points`, lifted off it a little as a shadow ray's
/// origin is, on the light's stratified samples and on random points of its disc.
fn check_scene(scene: &Scene, points: &[Vec3], lights: &[(Vec3, f32)], what: &str) {
    let structures = packets_on_thesis_tree(scene);
    let bf = BruteForce::new(scene);
    let mut rng = Rng(0x5eed);
    let mut samples = LightSamples::default();
    for (i, &p) in points.iter().enumerate() {
        let lift = Vec3::new(rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5) * 2e-3;
        let apex = p + lift;
        for &(center, radius) in lights {
            samples.generate(center, radius, p, 16, i as u32);
            let disc = samples.disc;
            check(&structures, &bf, apex, &disc, &samples.points, what);
            let (u, v) = disc.normal.any_orthonormal_pair();
            let on_disc: Vec<Vec3> = (0..32)
                .map(|_| {
                    let (a, b) = rng.in_disc();
                    center + (u * a + v * b) * radius
                })
                .collect();
            check(&structures, &bf, apex, &disc, &on_disc, what);
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
    let structures = packets_on_thesis_tree(&scene);
    let tree = structures.kd(Structure::ThesisKd).unwrap();
    let bf = BruteForce::new(&scene);
    let center = scene.lights[0].position;
    // Right in front of the light the proxies open to their widest, and then there are none.
    let disc = Disc { center, normal: Vec3::new(0.3, 1.0, 0.2).normalize(), radius: 1.0 };
    let (u, _) = disc.normal.any_orthonormal_pair();
    let targets: Vec<Vec3> = (0..16).map(|k| center + u * ((k as f32 - 7.5) / 7.5)).collect();
    for gap in [2.0f32, 0.5, 0.34, 0.1, 1e-4] {
        check(&structures, &bf, center - disc.normal * gap, &disc, &targets, &format!("gap {gap}"));
    }
    assert!(Cone::around_disc(center - disc.normal * 0.1, &disc).is_none(), "too wide");
    assert!(Cone::around_disc(center, &disc).is_none(), "an apex on the disc has no proxy");
    assert!(Frustum::around_disc(center + disc.normal, &disc).is_none(), "nor one behind it");
    assert!(Cone::around_disc(Vec3::ZERO, &Disc { center: Vec3::NAN, ..disc }).is_none());
    // A scene shifted far from the origin: coordinates carry large absolute rounding errors.
    let shift = Vec3::new(1.0e5, -2.0e5, 3.0e5);
    let apexes: Vec<Vec3> = surface_points(&scene, tree, 10).into_iter().map(|p| p + shift).collect();
    let mut far = scene.clone();
    let moved: Vec<Vec3> = far.positions.iter().map(|&p| p + shift).collect();
    far.set_vertices(0, &moved, None).unwrap();
    check_scene(&far, &apexes, &[(center + shift, 1.0), (center + shift, 20.0)], "shifted arena");
}
