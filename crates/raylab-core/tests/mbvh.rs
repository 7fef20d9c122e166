//! The 4-wide MBVH's single-ray traversal against the brute-force reference: every built-in scene with
//! adversarial rays, large sets of random incoherent rays (origins inside and outside, tmin > 0, finite tmax),
//! rays leaving surfaces as secondary rays do, both SIMD backends, and the degenerate scenes.

mod common;

use common::{Lanes, adversarial_rays, check_hits, incoherent, scaled_scenes};
use glam::Vec3;
use raylab_core::kdtree::{KdParams, KdTree};
use raylab_core::mbvh::{EMPTY, Mbvh, MbvhParams};
use raylab_core::method::{Method, Purpose};
use raylab_core::ray::Ray;
use raylab_core::reference::BruteForce;
use raylab_core::scene::{SceneBuilder, Triangle};
use raylab_core::stats::TraversalStats;
use raylab_core::structures::{StructureParams, Structures};
use raylab_scene::builtin::{self, Detail};
use raylab_scene::mesh::Jitter;
use raylab_simd::Backend;

/// Spatial splits tried at every node, so that the test scenes (smaller than the default's limit) get them.
fn spatial_everywhere() -> MbvhParams {
    MbvhParams { spatial_min_refs: 0, ..MbvhParams::default() }
}

/// The trees each test checks: the default build and one with spatial splits everywhere.
fn trees(scene: &raylab_core::scene::Scene) -> [(&'static str, Mbvh); 2] {
    [("default", Mbvh::build(scene)), ("spatial", Mbvh::build_with(scene, &spatial_everywhere()))]
}

#[test]
fn mbvh_matches_brute_force_on_every_builtin_scene_and_backend() {
    for name in builtin::names() {
        let scene = builtin::build(name, Detail::Test).unwrap();
        let kd = KdTree::build(&scene, &KdParams::default()).unwrap();
        for (tree, m) in trees(&scene) {
            for backend in Backend::available() {
                let what = format!("{name} {tree} {}", backend.name());
                check_hits(&scene, &Lanes(&m, backend), &adversarial_rays(&scene, &kd, 200, 3), &what);
                check_hits(&scene, &Lanes(&m, backend), &incoherent(&scene, 3000, 11), &what);
            }
        }
    }
}

/// Diffuse-style secondary rays that start exactly on a surface. With a small tmin (as renderers use) the MBVH
/// and mono both match brute force exactly. With tmin = 0, a hit within rounding of the origin (the surface
/// itself) may or may not be reported by any of them; beyond that they agree.
#[test]
fn rays_leaving_surfaces_behave_like_mono() {
    let scene = builtin::build("atrium", Detail::Test).unwrap();
    let kd = KdTree::build(&scene, &KdParams::default()).unwrap();
    let m = Mbvh::build(&scene);
    let cam = scene.default_view().unwrap().camera;
    let raster = cam.raster(40, 30);
    let mut s = TraversalStats::default();
    let mut rng = Jitter::new(5);
    let eps = 1e-5 * scene.bounds().diagonal();
    let (mut offset, mut exact) = (Vec::new(), Vec::new());
    for y in 0..30 {
        for x in 0..40 {
            let r = raster.primary(x, y);
            let Some(h) = kd.intersect(&r, &mut s) else { continue };
            let p = r.at(h.t);
            let d = Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
            offset.push(Ray::segment(p, d, eps, 50.0));
            exact.push(Ray::new(p, d));
        }
    }
    assert!(offset.len() > 500);
    check_hits(&scene, &Lanes(&m, Backend::detect()), &offset, "MBVH");
    check_hits(&scene, &kd, &offset, "mono");
    let self_hit = |h: Option<raylab_core::ray::Hit>| h.is_some_and(|h| h.t < eps);
    let mut compared = 0;
    for r in &exact {
        let (a, b) = (kd.intersect(r, &mut s), m.intersect(r, Backend::detect(), &mut s));
        if self_hit(a) || self_hit(b) {
            continue;
        }
        // Two triangles sharing an edge may both be hit, a last bit apart.
        match (a, b) {
            (Some(a), Some(b)) => assert!((a.t - b.t).abs() <= 1e-5 * a.t, "{r:?}: {a:?} vs {b:?}"),
            (a, b) => assert_eq!(a, b, "{r:?}"),
        }
        compared += 1;
    }
    // About half the random directions point into the surface and hit it at once.
    assert!(compared * 3 > exact.len(), "{compared} of {} compared", exact.len());
}

#[test]
fn empty_scene_single_triangle_and_extreme_coordinates() {
    let empty = SceneBuilder::new().build();
    let m = Mbvh::build(&empty);
    let mut s = TraversalStats::default();
    assert_eq!(m.intersect(&Ray::new(Vec3::ZERO, Vec3::X), Backend::detect(), &mut s), None);
    assert!(m.nodes()[0].child.iter().all(|&c| c == EMPTY));

    let mut b = SceneBuilder::new();
    b.positions = vec![Vec3::ZERO, Vec3::X, Vec3::Y];
    b.triangles = vec![Triangle { v: [0, 1, 2], material: 0 }];
    let one = b.build();
    let m = Mbvh::build(&one);
    let hit = m.intersect(&Ray::new(Vec3::new(0.25, 0.25, 1.0), Vec3::NEG_Z), Backend::detect(), &mut s).unwrap();
    assert_eq!((hit.tri, hit.t), (0, 1.0));
    // A ray in the triangle's plane, along an axis (zero direction components).
    check_hits(
        &one,
        &Lanes(&m, Backend::detect()),
        &[Ray::new(Vec3::new(-1.0, 0.0, 0.0), Vec3::X), Ray::new(Vec3::new(0.5, -1.0, 0.0), Vec3::Y)],
        "one",
    );

    for (name, scene) in scaled_scenes() {
        let kd = KdTree::build(&scene, &KdParams::default()).unwrap();
        for (tree, m) in trees(&scene) {
            check_hits(
                &scene,
                &Lanes(&m, Backend::detect()),
                &adversarial_rays(&scene, &kd, 100, 9),
                &format!("{name} {tree}"),
            );
        }
    }
}

/// Every triangle is in at least one leaf and at most once in each; spatial splits put some in several,
/// and every point of a triangle lies in the box of one of its leaves.
#[test]
fn every_triangle_is_covered_by_its_leaves_and_lanes_are_well_formed() {
    let scene = builtin::build("kitchen", Detail::Test).unwrap();
    for (tree, m) in trees(&scene) {
        let mut boxes: Vec<Vec<([f32; 3], [f32; 3])>> = vec![Vec::new(); scene.triangle_count()];
        for n in m.nodes() {
            for k in 0..4 {
                if n.is_leaf(k) {
                    let ids = &m.tri_ids()[n.child[k] as usize..(n.child[k] + n.count[k]) as usize];
                    for (j, &id) in ids.iter().enumerate() {
                        assert!(!ids[..j].contains(&id), "{tree}: triangle {id} twice in one leaf");
                        boxes[id as usize].push(([0, 1, 2].map(|a| n.min[a][k]), [0, 1, 2].map(|a| n.max[a][k])));
                    }
                } else if !n.is_empty(k) {
                    assert!((n.child[k] as usize) < m.nodes().len());
                }
            }
        }
        for (id, leaf_boxes) in boxes.iter().enumerate() {
            assert!(!leaf_boxes.is_empty(), "{tree}: triangle {id} is in no leaf");
            let [a, b, c] = scene.vertices(id);
            for i in 0..=6 {
                for j in 0..=6 - i {
                    let (u, v) = (i as f32 / 6.0, j as f32 / 6.0);
                    let p = a + (b - a) * u + (c - a) * v;
                    let inside = |(lo, hi): &([f32; 3], [f32; 3])| (0..3).all(|k| lo[k] <= p[k] && p[k] <= hi[k]);
                    assert!(
                        leaf_boxes.iter().any(inside),
                        "{tree}: point {p} of triangle {id} is in none of its leaves"
                    );
                }
            }
        }
        let st = m.stats();
        assert!(st.lane_fill_percent > 60.0 && st.depth > 2, "{tree}: {st:?}");
        let copies = st.references - scene.triangle_count();
        if tree == "spatial" {
            assert!(copies > 0, "spatial splits cut no triangle: {st:?}");
            assert!(st.references as f32 <= scene.triangle_count() as f32 * 1.3, "over the budget: {st:?}");
        }
        // The brute-force reference agrees on a few hundred more random rays.
        let bf = BruteForce::new(&scene);
        let mut s = TraversalStats::default();
        for r in incoherent(&scene, 300, 2) {
            assert_eq!(
                m.intersect(&r, Backend::detect(), &mut s).map(|h| h.t),
                bf.intersect(&r, &mut s).map(|h| h.t),
                "{tree}: {r:?}"
            );
        }
    }
}

/// MBVH RS (ray streams) against brute force: incoherent and adversarial rays in groups of 2^4 to 2^12, with
/// and without the ordering heuristic, with both leaf tests, closest hits (triangle and distance) and
/// occlusion.
#[test]
fn ray_streams_match_brute_force() {
    use raylab_core::mbvh::StreamLeaves;
    use raylab_core::trace::{TraceOptions, Tracer};
    for name in ["atrium", "forest"] {
        let scene = builtin::build(name, Detail::Test).unwrap();
        let kd = KdTree::build(&scene, &KdParams::default()).unwrap();
        let params = StructureParams::default();
        let default = Structures::build(&scene, &[Method::MbvhRs], Purpose::Rays, &params).unwrap();
        let spatial_params = StructureParams { mbvh: spatial_everywhere(), ..params };
        let spatial = Structures::build(&scene, &[Method::MbvhRs], Purpose::Rays, &spatial_params).unwrap();
        let bf = BruteForce::new(&scene);
        // Incoherent rays, then the adversarial set: zero direction components of both signs, rays in split
        // planes and along triangle planes, through vertices and edges, short segments.
        let mut rays: Vec<Option<Ray>> = incoherent(&scene, 4096, 23).into_iter().map(Some).collect();
        rays.extend(adversarial_rays(&scene, &kd, 200, 29).into_iter().map(Some));
        let total = rays.len() as u64;
        let check = |label: &str, rays: &[Option<Ray>], hits: &[Option<raylab_core::ray::Hit>], blocked: &[bool]| {
            for ((r, h), b) in rays.iter().zip(hits).zip(blocked) {
                let r = r.unwrap();
                let want = bf.intersect(&r, &mut TraversalStats::default());
                assert_eq!(h.map(|h| (h.tri, h.t)), want.map(|w| (w.tri, w.t)), "{name} {label}: {r:?}");
                assert_eq!(*b, bf.occluded(&r, &mut TraversalStats::default()), "{name} {label}: {r:?}");
            }
        };
        // Every backend: eight lanes test two rays per node and per leaf block test, four one, a task's rays
        // eight or four at a time (odd and partial last chunks included). Both leaf tests, both trees (the
        // default build and one with spatial splits everywhere).
        let cases = Backend::available().into_iter().flat_map(|b| {
            [(16, true), (256, true), (256, false), (4095, true)].into_iter().map(move |(g, o)| (b, g, o))
        });
        let cases = cases.flat_map(|c| StreamLeaves::ALL.map(|l| (c, l)));
        let cases = cases.flat_map(|c| [("default", &default, c), ("spatial", &spatial, c)]);
        for (tree, structures, ((backend, group, ordered), leaves)) in cases {
            let opts = TraceOptions {
                method: Method::MbvhRs,
                backend,
                stream_order: ordered,
                stream_leaves: leaves,
                ..TraceOptions::default()
            };
            let tracer = Tracer::for_rays(structures, opts).unwrap();
            let mut s = TraversalStats::default();
            for chunk in rays.chunks(group) {
                let mut hits = vec![None; chunk.len()];
                let mut blocked = vec![false; chunk.len()];
                tracer.intersect_tile(chunk, chunk.len(), 1, &mut hits, &mut s);
                tracer.occluded_tile(chunk, chunk.len(), 1, None, &mut blocked, &mut s);
                check(&format!("{tree} tree, group {group}, {} leaves", leaves.name()), chunk, &hits, &blocked);
            }
            assert_eq!(s.rays, 2 * total);
            assert!(s.box_tests > 0 && s.leaf_rays > 0);
            let u = s.leaf_utilisation();
            assert!(u[0] >= u[1] && u[1] >= u[2] && u[0] <= 100.0, "{u:?}");
        }
        // Groups the tracer cuts from a 64x50 tile along the Z-order curve, odd powers of two (2:1 blocks) and a
        // ragged last row included; every ray is traced exactly once.
        let tile = &rays[..64 * 50];
        let mut fetches = Vec::new();
        for group in [16, 32, 512] {
            let opts = TraceOptions { method: Method::MbvhRs, stream_group: Some(group), ..TraceOptions::default() };
            let tracer = Tracer::for_rays(&default, opts).unwrap();
            let mut s = TraversalStats::default();
            let mut hits = vec![None; tile.len()];
            let mut blocked = vec![false; tile.len()];
            tracer.intersect_tile(tile, 64, 50, &mut hits, &mut s);
            tracer.occluded_tile(tile, 64, 50, None, &mut blocked, &mut s);
            check(&format!("tile cut into groups of {group}"), tile, &hits, &blocked);
            assert_eq!(s.rays, 2 * tile.len() as u64);
            fetches.push(s.nodes);
        }
        // Smaller groups share fewer node fetches: the tile really was cut.
        assert!(fetches[0] > fetches[1] && fetches[1] > fetches[2], "{name}: {fetches:?}");
    }
}

/// MBVH RS on the degenerate scenes: empty, one triangle (rays in its plane and along axes among them), huge
/// and tiny coordinates; every backend, both leaf tests, hits and occlusion exactly as brute force.
#[test]
fn ray_streams_on_degenerate_scenes() {
    use raylab_core::mbvh::StreamLeaves;
    use raylab_core::trace::{TraceOptions, Tracer};
    let mut b = SceneBuilder::new();
    b.positions = vec![Vec3::ZERO, Vec3::X, Vec3::Y];
    b.triangles = vec![Triangle { v: [0, 1, 2], material: 0 }];
    let mut scenes = vec![("empty".to_string(), SceneBuilder::new().build()), ("one".to_string(), b.build())];
    scenes.extend(scaled_scenes());
    for (name, scene) in scenes {
        let kd = KdTree::build(&scene, &KdParams::default()).unwrap();
        let bf = BruteForce::new(&scene);
        let mut rays = vec![Ray::new(Vec3::new(-1.0, 0.0, 0.0), Vec3::X), Ray::new(Vec3::new(0.5, -1.0, 0.0), Vec3::Y)];
        rays.push(Ray::new(Vec3::new(0.25, 0.25, 1.0), Vec3::NEG_Z));
        if scene.triangle_count() > 0 {
            rays.extend(adversarial_rays(&scene, &kd, 60, 13));
        }
        let rays: Vec<Option<Ray>> = rays.into_iter().map(Some).collect();
        let structures = Structures::build(&scene, &[Method::MbvhRs], Purpose::Rays, &StructureParams::default());
        let structures = structures.unwrap();
        for backend in Backend::available() {
            for leaves in StreamLeaves::ALL {
                let opts =
                    TraceOptions { method: Method::MbvhRs, backend, stream_leaves: leaves, ..TraceOptions::default() };
                let tracer = Tracer::for_rays(&structures, opts).unwrap();
                let mut s = TraversalStats::default();
                let mut hits = vec![None; rays.len()];
                let mut blocked = vec![false; rays.len()];
                tracer.intersect_tile(&rays, rays.len(), 1, &mut hits, &mut s);
                tracer.occluded_tile(&rays, rays.len(), 1, None, &mut blocked, &mut s);
                let what = format!("{name}, {}, {} leaves", backend.name(), leaves.name());
                for ((r, h), b) in rays.iter().zip(&hits).zip(&blocked) {
                    let r = r.unwrap();
                    let want = bf.intersect(&r, &mut TraversalStats::default());
                    assert_eq!(h.map(|h| (h.tri, h.t)), want.map(|w| (w.tri, w.t)), "{what}: {r:?}");
                    assert_eq!(*b, bf.occluded(&r, &mut TraversalStats::default()), "{what}: {r:?}");
                }
            }
        }
    }
}

/// Triangles spaced ever wider along a line make SAH split a few off at a time: a lopsided tree, as deep as
/// the build allows, still traced right.
#[test]
fn a_pathologically_deep_tree_still_traces_right() {
    let mut b = SceneBuilder::new();
    for k in 0..160 {
        let x = 1.6f32.powi(k);
        let base = b.positions.len() as u32;
        b.positions.extend([Vec3::new(x, 0.0, 0.0), Vec3::new(x, 1.0, 0.0), Vec3::new(x, 0.0, 1.0)]);
        b.triangles.push(Triangle { v: [base, base + 1, base + 2], material: 0 });
    }
    let scene = b.build();
    let m = Mbvh::build(&scene);
    assert!(m.stats().depth >= 10, "depth {}", m.stats().depth);
    let kd = KdTree::build(&scene, &KdParams::default()).unwrap();
    let mut rays = adversarial_rays(&scene, &kd, 100, 4);
    rays.extend((0..200).map(|k| Ray::new(Vec3::new(-1.0, 0.2 + k as f32 * 1e-3, 0.3), Vec3::new(1.0, 0.0, 0.0))));
    rays.extend((0..50).map(|k| Ray::new(Vec3::new(2e15, 0.25, 0.25), Vec3::new(-1.0, 1e-4 * k as f32, 0.0))));
    check_hits(&scene, &Lanes(&m, Backend::detect()), &rays, "deep");
}
