//! Divide-and-conquer ray tracing against the brute-force reference: every built-in scene with adversarial
//! and incoherent rays traced as one large set and as small sets, both split rules, several leaf thresholds,
//! both SIMD backends, closest hits, occlusion and first blockers; camera rays through the tracer as the
//! renderer sends them; and the degenerate scenes (empty, one triangle, huge and tiny coordinates, a
//! pathologically lopsided one).

mod common;

use common::{AXES, Lanes, adversarial_rays, check_hits, incoherent, scaled_scenes};
use glam::Vec3;
use raylab_core::dacrt::{Dacrt, DacrtParams, SplitRule};
use raylab_core::kdtree::{KdParams, KdTree};
use raylab_core::method::Method;
use raylab_core::ray::{Hit, Ray};
use raylab_core::reference::BruteForce;
use raylab_core::scene::{Scene, SceneBuilder, Triangle};
use raylab_core::stats::TraversalStats;
use raylab_core::trace::{TraceOptions, Tracer};
use raylab_scene::MeshBuilder;
use raylab_scene::builtin::{self, Detail};
use raylab_scene::mesh::Jitter;
use raylab_simd::Backend;

/// `adversarial` adversarial rays (seeded by `adversarial_seed`) then `random` incoherent ones (`random_seed`)
/// for `scene`.
fn mixed_rays(
    scene: &Scene,
    (adversarial, adversarial_seed): (usize, u32),
    (random, random_seed): (usize, u32),
) -> Vec<Ray> {
    let kd = KdTree::build(scene, &KdParams::default()).unwrap();
    let mut rays = adversarial_rays(scene, &kd, adversarial, adversarial_seed);
    rays.extend(incoherent(scene, random, random_seed));
    rays
}

/// Traces `rays` with `d` in sets of `set` rays and checks closest hits, occlusion and blockers against
/// brute force. Returns the counters.
fn check_sets(
    scene: &Scene,
    d: &Lanes<Dacrt>,
    p: &DacrtParams,
    rays: &[Ray],
    set: usize,
    what: &str,
) -> TraversalStats {
    let Lanes(d, backend) = *d;
    let bf = BruteForce::new(scene);
    let mut s = TraversalStats::default();
    let all: Vec<Option<Ray>> = rays.iter().copied().map(Some).collect();
    for (c, chunk) in all.chunks(set).enumerate() {
        let mut hits = vec![None; chunk.len()];
        let mut blocked = vec![false; chunk.len()];
        let mut blockers = vec![None; chunk.len()];
        d.intersect(p, backend, chunk, &mut hits, &mut s);
        d.occluded(p, backend, chunk, &mut blocked, &mut s);
        d.occluders(p, backend, chunk, &mut blockers, &mut s);
        for (i, r) in chunk.iter().enumerate() {
            let r = r.unwrap();
            let at = format!("{what}, set {c} ray {i} {r:?}");
            let want = bf.intersect(&r, &mut TraversalStats::default());
            match (hits[i], want) {
                (Some(g), Some(w)) => assert!(g.tri == w.tri && g.t == w.t, "{at}: {g:?} vs {w:?}"),
                (g, w) => assert_eq!(g, w, "{at}"),
            }
            let occ = bf.occluded(&r, &mut TraversalStats::default());
            assert_eq!(blocked[i], occ, "{at}: occlusion");
            assert_eq!(blockers[i].is_some(), occ, "{at}: blocker");
            if let Some(t) = blockers[i] {
                assert!(bf.blocks(&r, t), "{at}: reported blocker {t} does not block");
            }
        }
    }
    s
}

#[test]
fn dacrt_matches_brute_force_on_every_builtin_scene() {
    for name in builtin::names() {
        let scene = builtin::build(name, Detail::Test).unwrap();
        let rays = mixed_rays(&scene, (150, 3), (2500, 11));
        let d = Dacrt::new(&scene);
        let p = DacrtParams::default();
        for backend in Backend::available() {
            let s =
                check_sets(&scene, &Lanes(&d, backend), &p, &rays, rays.len(), &format!("{name} {}", backend.name()));
            assert_eq!(s.rays, 3 * rays.len() as u64);
            // Filtering and leaves do the work: far fewer tests than brute force.
            let brute = (rays.len() * scene.triangle_count()) as u64;
            assert!(s.isect_tests < brute, "{name}: {} tests vs {brute} brute force", s.isect_tests);
            assert!(s.nodes > 0 && s.leaves > 0 && s.box_tests > 0);
        }
        // Small sets, down to single rays.
        check_sets(&scene, &Lanes(&d, Backend::detect()), &p, &rays[..300], 7, name);
        check_hits(&scene, &Lanes(&d, Backend::detect()), &rays[..100], name);
    }
}

/// Sets smaller than [`raylab_core::dacrt::FORK_BELOW`] are traced against the two triangle groups on two
/// threads when the pool has them, on one thread otherwise: each way gives the reference's answers, and each
/// ray is counted once.
#[test]
fn small_sets_give_the_same_hits_forked_and_on_one_thread() {
    let scene = builtin::build("kitchen", Detail::Test).unwrap();
    let rays = mixed_rays(&scene, (100, 7), (1200, 23));
    assert!(rays.len() < raylab_core::dacrt::FORK_BELOW);
    let d = Dacrt::new(&scene);
    for threads in [1, 2, 3] {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        let what = format!("{threads} threads");
        let s = pool.install(|| {
            check_sets(&scene, &Lanes(&d, Backend::detect()), &DacrtParams::default(), &rays, rays.len(), &what)
        });
        assert_eq!(s.rays, 3 * rays.len() as u64, "{what}");
        let singles = pool.install(|| {
            check_sets(&scene, &Lanes(&d, Backend::detect()), &DacrtParams::default(), &rays[..40], 1, &what)
        });
        assert_eq!(singles.rays, 3 * 40, "{what}");
    }
}

/// A scene several times [`raylab_core::dacrt::DIVIDE_ONCE_ABOVE`] triangles has the top of its division made
/// at setup: calls with the SAH rule reuse it (whole sets, sets forked on two threads, single rays) and calls
/// with the median rule divide for themselves; every way gives the reference's answers.
#[test]
fn the_division_made_at_setup_gives_the_same_hits() {
    let mut mb = MeshBuilder::new();
    for k in 0..4 {
        mb.sphere(Vec3::new(3.0 * k as f32, 0.0, (k % 2) as f32), 1.2, 48, 64);
    }
    mb.cuboid(Vec3::new(-2.0, -1.5, -2.0), Vec3::new(11.0, -1.3, 3.0));
    let scene = mb.build();
    assert!(scene.triangle_count() > 4 * raylab_core::dacrt::DIVIDE_ONCE_ABOVE, "{}", scene.triangle_count());
    let rays = mixed_rays(&scene, (100, 13), (1500, 29));
    let d = Dacrt::new(&scene);
    assert!(d.setup_nodes() >= 7, "{} nodes divided at setup", d.setup_nodes());
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        for split in SplitRule::ALL {
            let p = DacrtParams { split, ..DacrtParams::default() };
            let what = format!("{split:?} on {threads} threads");
            pool.install(|| check_sets(&scene, &Lanes(&d, Backend::detect()), &p, &rays, rays.len(), &what));
            pool.install(|| check_sets(&scene, &Lanes(&d, Backend::detect()), &p, &rays[..60], 1, &what));
        }
    }
}

#[test]
fn every_split_rule_and_leaf_threshold_gives_the_same_hits() {
    let scene = builtin::build("atrium", Detail::Test).unwrap();
    let rays = mixed_rays(&scene, (100, 5), (1500, 17));
    let d = Dacrt::new(&scene);
    for split in SplitRule::ALL {
        for (leaf_rays, leaf_tris) in [(1, 1), (8, 8), (64, 2), (2, 64), (DacrtParams::MAX_LEAF, 1)] {
            let p = DacrtParams { leaf_rays, leaf_tris, split };
            check_sets(
                &scene,
                &Lanes(&d, Backend::detect()),
                &p,
                &rays,
                1024,
                &format!("{split:?} {leaf_rays}/{leaf_tris}"),
            );
        }
    }
}

/// Camera rays as the renderer sends them (a tile per set) and diffuse rays leaving surfaces: DACRT through the
/// tracer equals mono.
#[test]
fn camera_and_surface_rays_through_the_tracer_equal_mono() {
    let scene = builtin::build("kitchen", Detail::Test).unwrap();
    let structures = common::structures(&scene, &[Method::Mono, Method::Dacrt]);
    let cam = scene.default_view().unwrap().camera;
    let (w, h) = (64, 48);
    let raster = cam.raster(w, h);
    let rays: Vec<Option<Ray>> =
        (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).map(|(x, y)| Some(raster.primary(x, y))).collect();
    let mono = Tracer::new(&structures, TraceOptions::default()).unwrap();
    let dacrt = Tracer::new(&structures, TraceOptions { method: Method::Dacrt, ..TraceOptions::default() }).unwrap();
    let mut s = TraversalStats::default();
    let mut want = vec![None; rays.len()];
    let mut got = vec![None; rays.len()];
    mono.intersect_tile(&rays, w as usize, h as usize, &mut want, &mut s);
    dacrt.intersect_tile(&rays, w as usize, h as usize, &mut got, &mut s);
    assert_eq!(got, want);
    assert!(got.iter().filter(|h| h.is_some()).count() > rays.len() / 2);

    let eps = 1e-4 * scene.bounds().diagonal();
    let mut rng = Jitter::new(9);
    let secondary: Vec<Option<Ray>> = rays
        .iter()
        .zip(&want)
        .map(|(r, h)| {
            let (r, h): (Ray, Hit) = ((*r)?, (*h)?);
            let d = Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
            Some(Ray::segment(r.at(h.t), d, eps, f32::INFINITY))
        })
        .collect();
    let (mut a, mut b) = (vec![false; rays.len()], vec![false; rays.len()]);
    mono.occluded_tile(&secondary, rays.len(), 1, None, &mut a, &mut s);
    dacrt.occluded_tile(&secondary, rays.len(), 1, None, &mut b, &mut s);
    assert_eq!(a, b);
    let (mut a, mut b) = (vec![None; rays.len()], vec![None; rays.len()]);
    mono.intersect_tile(&secondary, rays.len(), 1, &mut a, &mut s);
    dacrt.intersect_tile(&secondary, rays.len(), 1, &mut b, &mut s);
    // Where two triangles are hit at exactly one distance (a shared edge), either may be reported.
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(x.map(|h| h.t), y.map(|h| h.t));
    }
}

#[test]
fn degenerate_scenes_and_extreme_coordinates() {
    let mut s = TraversalStats::default();
    let empty = Dacrt::new(&SceneBuilder::new().build());
    let rays = [Some(Ray::new(Vec3::ZERO, Vec3::X)), None, Some(Ray::new(Vec3::ONE, Vec3::ZERO))];
    let mut hits = [Some(Hit { t: 1.0, tri: 0, u: 0.0, v: 0.0 }); 3];
    empty.intersect(&DacrtParams::default(), Backend::detect(), &rays, &mut hits, &mut s);
    assert_eq!(hits, [None; 3], "results are reset, invalid rays skipped");

    let mut b = SceneBuilder::new();
    b.positions = vec![Vec3::ZERO, Vec3::X, Vec3::Y];
    b.triangles = vec![Triangle { v: [0, 1, 2], material: 0 }];
    let one = b.build();
    let d = Dacrt::new(&one);
    let nan = Ray::new(Vec3::new(f32::NAN, 0.0, 0.0), Vec3::Z);
    let rays = [
        Some(Ray::new(Vec3::new(0.25, 0.25, 1.0), Vec3::NEG_Z)),
        Some(nan),
        Some(Ray::new(Vec3::new(-1.0, 0.0, 0.0), Vec3::X)),
    ];
    let mut hits = [None; 3];
    d.intersect(&DacrtParams::default(), Backend::detect(), &rays, &mut hits, &mut s);
    assert_eq!(hits[0].map(|h| (h.tri, h.t)), Some((0, 1.0)));
    assert_eq!(hits[1], None);
    check_hits(
        &one,
        &Lanes(&d, Backend::detect()),
        &[Ray::new(Vec3::new(-1.0, 0.0, 0.0), Vec3::X), Ray::new(Vec3::new(0.5, -1.0, 0.0), Vec3::Y)],
        "one",
    );

    for (name, scene) in scaled_scenes() {
        let kd = KdTree::build(&scene, &KdParams::default()).unwrap();
        let d = Dacrt::new(&scene);
        let p = DacrtParams::default();
        check_sets(&scene, &Lanes(&d, Backend::detect()), &p, &adversarial_rays(&scene, &kd, 100, 9), 512, &name);
    }

    // Triangles spaced ever wider along a line: SAH cuts off one at a time, as deep as it can.
    let mut b = SceneBuilder::new();
    for k in 0..70 {
        let x = 1.6f32.powi(k);
        let base = b.positions.len() as u32;
        b.positions.extend([Vec3::new(x, 0.0, 0.0), Vec3::new(x, 1.0, 0.0), Vec3::new(x, 0.0, 1.0)]);
        b.triangles.push(Triangle { v: [base, base + 1, base + 2], material: 0 });
    }
    let deep = b.build();
    let kd = KdTree::build(&deep, &KdParams::default()).unwrap();
    let mut rays = adversarial_rays(&deep, &kd, 100, 4);
    rays.extend((0..200).map(|k| Ray::new(Vec3::new(-1.0, 0.2 + k as f32 * 1e-3, 0.3), Vec3::new(1.0, 0.0, 0.0))));
    rays.extend((0..50).map(|k| Ray::new(Vec3::new(2e15, 0.25, 0.25), Vec3::new(-1.0, 1e-4 * k as f32, 0.0))));
    let d = Dacrt::new(&deep);
    let p = DacrtParams { leaf_rays: 1, leaf_tris: 1, split: SplitRule::Sah };
    check_sets(&deep, &Lanes(&d, Backend::detect()), &p, &rays, rays.len(), "deep");
}

/// The camera inside geometry: origins inside walls and pillars, every axis direction and diagonals, as one set.
#[test]
fn camera_inside_geometry() {
    let scene = builtin::build("arena", Detail::Test).unwrap();
    let d = Dacrt::new(&scene);
    let p = DacrtParams::default();
    let inside = [Vec3::new(8.0, 2.0, 0.0), Vec3::new(-19.0, -0.1, -19.0), Vec3::new(0.0, 4.0, 20.5)];
    let dirs: Vec<Vec3> = AXES.into_iter().chain([Vec3::new(1.0, 1.0, -1.0), Vec3::new(-0.0, 1.0, 0.0)]).collect();
    let rays: Vec<Ray> = inside.iter().flat_map(|&o| dirs.iter().map(move |&d| Ray::new(o, d))).collect();
    check_sets(&scene, &Lanes(&d, Backend::detect()), &p, &rays, rays.len(), "inside geometry");
}
