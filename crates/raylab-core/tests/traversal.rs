//! Every traversal method against the brute-force reference, on every built-in scene and on adversarial
//! cases: empty scenes, one triangle, cameras inside geometry, huge and tiny coordinates.

mod common;

use common::{adversarial_rays, check_hits};
use glam::{Affine3A, Vec3};
use raylab_core::kdtree::{KdParams, KdTree};
use raylab_core::ray::Ray;
use raylab_core::scene::{Scene, SceneBuilder, Triangle};
use raylab_core::stats::TraversalStats;
use raylab_scene::MeshBuilder;
use raylab_scene::builtin::{self, Detail};

fn tree(scene: &Scene) -> KdTree {
    KdTree::build(scene, &KdParams::default()).expect("build")
}

#[test]
fn mono_matches_brute_force_on_every_builtin_scene() {
    for name in builtin::names() {
        let scene = builtin::build(name, Detail::Test).expect("built-in");
        let t = tree(&scene);
        let rays = adversarial_rays(&scene, &t, 300, 17);
        check_hits(&scene, &t, &rays, name);
        // Camera rays from the scene's own views, including the corners of the image.
        let cam = scene.default_view().expect("view").camera;
        let raster = cam.raster(37, 23);
        let primary: Vec<Ray> =
            (0..23).flat_map(|y| (0..37).map(move |x| (x, y))).map(|(x, y)| raster.primary(x, y)).collect();
        check_hits(&scene, &t, &primary, name);
    }
}

#[test]
fn mono_matches_brute_force_with_other_tree_parameters() {
    let scene = builtin::build("atrium", Detail::Test).unwrap();
    for params in [
        KdParams { max_depth: Some(3), ..KdParams::default() },
        KdParams { empty_bonus: 0.0, c_isect: 1.5, ..KdParams::default() },
        KdParams { parallel_min_tris: 64, ..KdParams::default() },
        KdParams { strategy: raylab_core::kdtree::SplitStrategy::Middle, ..KdParams::default() },
    ] {
        let t = KdTree::build(&scene, &params).unwrap();
        check_hits(&scene, &t, &adversarial_rays(&scene, &t, 150, 5), &format!("{params:?}"));
    }
}

#[test]
fn empty_scene_and_single_triangle() {
    let empty = SceneBuilder::new().build();
    let t = tree(&empty);
    let mut s = TraversalStats::default();
    let r = Ray::new(Vec3::ZERO, Vec3::X);
    assert_eq!(t.intersect(&r, &mut s), None);
    assert!(!t.occluded(&r, &mut s));
    assert_eq!(s.rays, 2);

    let mut b = SceneBuilder::new();
    b.positions = vec![Vec3::ZERO, Vec3::X, Vec3::Y];
    b.triangles = vec![Triangle { v: [0, 1, 2], material: 0 }];
    let one = b.build();
    let t = tree(&one);
    let hit = t.intersect(&Ray::new(Vec3::new(0.2, 0.2, 1.0), Vec3::NEG_Z), &mut s).expect("hit");
    assert_eq!((hit.tri, hit.t), (0, 1.0));
    check_hits(&one, &t, &adversarial_rays(&one, &t, 200, 3), "one triangle");
}

#[test]
fn camera_inside_geometry() {
    let scene = builtin::build("arena", Detail::Test).unwrap();
    let t = tree(&scene);
    // Origins inside pillars, tiles and walls of the arena, shooting in every axis direction and diagonally.
    let inside = [Vec3::new(8.0, 2.0, 0.0), Vec3::new(-19.0, -0.1, -19.0), Vec3::new(0.0, 4.0, 20.5)];
    let dirs = [Vec3::X, Vec3::NEG_Y, Vec3::Z, Vec3::new(1.0, 1.0, 1.0), Vec3::new(-0.3, 0.2, -1.0)];
    let rays: Vec<Ray> = inside.iter().flat_map(|&o| dirs.iter().map(move |&d| Ray::new(o, d))).collect();
    check_hits(&scene, &t, &rays, "inside geometry");
}

fn scaled(scale: f32, offset: Vec3) -> Scene {
    let mut m = MeshBuilder::new();
    m.set_transform(Affine3A::from_translation(offset) * Affine3A::from_scale(Vec3::splat(scale)));
    m.cuboid(Vec3::splat(-1.0), Vec3::splat(1.0));
    m.sphere(Vec3::new(3.0, 0.0, 0.0), 1.0, 8, 12);
    m.torus(Vec3::new(-3.0, 0.5, 0.0), 1.0, 0.3, 12, 6);
    m.cylinder(Vec3::new(0.0, 2.0, 2.0), 0.5, 2.0, 10);
    m.build()
}

#[test]
fn huge_and_tiny_coordinates() {
    for (scale, offset) in [(1e4, Vec3::ZERO), (1e-4, Vec3::ZERO), (1.0, Vec3::splat(1e5)), (1e-3, Vec3::splat(-50.0))]
    {
        let scene = scaled(scale, offset);
        let t = tree(&scene);
        check_hits(&scene, &t, &adversarial_rays(&scene, &t, 200, 9), &format!("scale {scale} offset {offset}"));
    }
}

#[test]
fn invalid_rays_never_hit() {
    let scene = builtin::build("arena", Detail::Test).unwrap();
    let t = tree(&scene);
    let mut s = TraversalStats::default();
    for r in [
        Ray::new(Vec3::ZERO, Vec3::ZERO),
        Ray::new(Vec3::NAN, Vec3::X),
        Ray::new(Vec3::ZERO, Vec3::new(f32::INFINITY, 0.0, 0.0)),
        Ray::segment(Vec3::new(0.0, 1.0, 0.0), Vec3::NEG_Y, 0.0, f32::NAN),
    ] {
        assert_eq!(t.intersect(&r, &mut s), None, "{r:?}");
        assert!(!t.occluded(&r, &mut s), "{r:?}");
    }
}

#[test]
fn counters_add_up() {
    let scene = builtin::build("atrium", Detail::Test).unwrap();
    let t = tree(&scene);
    let cam = scene.default_view().unwrap().camera.raster(16, 16);
    let mut s = TraversalStats::default();
    let mut hits = 0;
    for y in 0..16 {
        for x in 0..16 {
            hits += t.intersect(&cam.primary(x, y), &mut s).is_some() as u32;
        }
    }
    assert_eq!(s.rays, 256);
    assert!(hits > 128, "the default view looks at geometry ({hits} hits)");
    assert!(s.leaves >= 256 && s.nodes > s.leaves && s.isect_tests > 0, "{s:?}");
}

/// Every coherent method against brute force on the adversarial rays (different origins, zero and -0
/// direction components, mixed signs, vertex- and edge-aimed, in split planes, segments), traced as 4x2
/// tiles: frustum methods find no common origin and trace packets with mixed origins, which is exactly what
/// this exercises.
#[test]
fn coherent_methods_match_brute_force_on_adversarial_rays() {
    use raylab_core::method::{Method, Purpose, Structure};
    use raylab_core::reference::BruteForce;
    use raylab_core::structures::{StructureParams, Structures};
    use raylab_core::trace::{TraceOptions, Tracer};
    use raylab_simd::Backend;
    for name in builtin::names() {
        let scene = builtin::build(name, Detail::Test).unwrap();
        // The coherent methods on the thesis's tree (both kd-tree slots take its cost model).
        let params = StructureParams { packet_kd: KdParams::default(), ..StructureParams::default() };
        let methods = [Method::Packet, Method::Frustum, Method::Mft, Method::Cone, Method::MftCone];
        let structures = Structures::build(&scene, &methods, Purpose::Frames, &params).unwrap();
        let t = structures.kd(Structure::ThesisKd).unwrap();
        let bf = BruteForce::new(&scene);
        let rays: Vec<Option<Ray>> = adversarial_rays(&scene, t, 120, 23).into_iter().map(Some).collect();
        for method in methods {
            for backend in Backend::available() {
                let tracer = Tracer::new(&structures, TraceOptions { method, backend, ..Default::default() }).unwrap();
                let mut s = TraversalStats::default();
                for chunk in rays.chunks(8) {
                    let mut tile = chunk.to_vec();
                    tile.resize(8, None);
                    let (mut hits, mut occ) = (vec![None; 8], vec![false; 8]);
                    tracer.intersect_tile(&tile, 4, 2, &mut hits, &mut s);
                    tracer.occluded_tile(&tile, 4, 2, None, &mut occ, &mut s);
                    for (i, r) in chunk.iter().enumerate() {
                        let r = r.as_ref().unwrap();
                        let want = bf.intersect(r, &mut s);
                        let ok = match (hits[i], want) {
                            (None, None) => true,
                            (Some(g), Some(w)) => g.tri == w.tri && g.t == w.t,
                            _ => false,
                        };
                        assert!(ok, "{name} {method} {backend:?}: {r:?}: got {:?}, reference {want:?}", hits[i]);
                        assert_eq!(occ[i], bf.occluded(r, &mut s), "{name} {method} {backend:?}: occlusion of {r:?}");
                    }
                }
            }
        }
    }
}
