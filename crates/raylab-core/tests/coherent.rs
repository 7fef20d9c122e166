//! Every coherent method (packets, frustums, MFT), tile size, SIMD backend and culling setting returns the
//! same closest hit (triangle and t) and the same shadow occlusion as single-ray traversal for every pixel,
//! on every built-in scene and on adversarial cameras.

use glam::Vec3;
use raylab_core::kdtree::KdParams;
use raylab_core::method::{Method, Purpose, Structure};
use raylab_core::ray::{Hit, Ray};
use raylab_core::scene::{Camera, Scene};
use raylab_core::stats::TraversalStats;
use raylab_core::structures::{StructureParams, Structures};
use raylab_core::trace::{TraceOptions, Tracer};
use raylab_core::workload::{RayKind, WorkloadBuilder};
use raylab_scene::builtin::{self, Detail};
use raylab_simd::Backend;

const METHODS: [Method; 5] = [Method::Packet, Method::Frustum, Method::Mft, Method::Cone, Method::MftCone];
const TILES: [usize; 5] = [4, 8, 16, 32, 64];

/// Traces `rays` (a `w x h` image) tile by tile with `tracer`.
fn trace_image(
    tracer: &Tracer,
    rays: &[Option<Ray>],
    w: usize,
    h: usize,
    tile: usize,
    toward: Option<Vec3>,
) -> (Vec<Option<Hit>>, Vec<bool>) {
    let mut hits = vec![None; w * h];
    let mut occ = vec![false; w * h];
    let mut stats = TraversalStats::default();
    for ty in (0..h).step_by(tile) {
        for tx in (0..w).step_by(tile) {
            let (tw, th) = (tile.min(w - tx), tile.min(h - ty));
            let sub: Vec<Option<Ray>> =
                (0..th).flat_map(|y| (0..tw).map(move |x| (x, y))).map(|(x, y)| rays[(ty + y) * w + tx + x]).collect();
            let mut out_h = vec![None; tw * th];
            let mut out_o = vec![false; tw * th];
            tracer.intersect_tile(&sub, tw, th, &mut out_h, &mut stats);
            tracer.occluded_tile(&sub, tw, th, toward, &mut out_o, &mut stats);
            for y in 0..th {
                for x in 0..tw {
                    hits[(ty + y) * w + tx + x] = out_h[y * tw + x];
                    occ[(ty + y) * w + tx + x] = out_o[y * tw + x];
                }
            }
        }
    }
    (hits, occ)
}

fn same_hit(got: Option<Hit>, want: Option<Hit>) -> bool {
    match (got, want) {
        (None, None) => true,
        (Some(g), Some(w)) => g.tri == w.tri && g.t == w.t,
        _ => false,
    }
}

/// Compares every method against mono on the primary and shadow rays of one view: on mono's tree (the
/// thesis's cost model), and also on the tree built for the packet methods ([`StructureParams::packet_kd`]),
/// whose leaves are larger.
fn check_view(scene: &Scene, cam: &Camera, light: Vec3, w: usize, h: usize, what: &str) {
    let all: Vec<Method> = METHODS.into_iter().chain([Method::Mono]).collect();
    let own = Structures::build(scene, &all, Purpose::Frames, &StructureParams::default()).unwrap();
    // Every method on the thesis's tree: both kd-tree slots take its cost model.
    let thesis_params = StructureParams { packet_kd: KdParams::default(), ..StructureParams::default() };
    let thesis = Structures::build(scene, &METHODS, Purpose::Frames, &thesis_params).unwrap();
    let (tree, packet_tree) = (own.kd(Structure::ThesisKd).unwrap(), own.kd(Structure::PacketKd).unwrap());
    if scene.triangles.len() > 1000 {
        // Otherwise the second tree would test nothing new.
        assert!(packet_tree.nodes().len() < tree.nodes().len(), "{what}: the packet methods' tree is not coarser");
    }
    let wb = WorkloadBuilder::new(scene, cam, light, w as u32, h as u32, tree);
    let primary = wb.build(RayKind::Primary).rays;
    let shadow = wb.build(RayKind::Shadow).rays;
    let mono = Tracer::new(&own, TraceOptions { method: Method::Mono, ..Default::default() }).unwrap();
    let (want_hits, _) = trace_image(&mono, &primary, w, h, 8, None);
    let (_, want_occ) = trace_image(&mono, &shadow, w, h, 8, Some(light));
    let walks = METHODS.into_iter().flat_map(|m| {
        let own_tree = m.entry().packets().then_some((m, &own, "own tree"));
        [Some((m, &thesis, "mono's tree")), own_tree].into_iter().flatten()
    });
    for (method, walked, which) in walks {
        for backend in Backend::available() {
            for (cull, spread) in
                [(true, TraceOptions::SHADOW_SPREAD_LIMIT), (false, f32::INFINITY), (true, f32::INFINITY)]
            {
                for tile in TILES {
                    // An infinite spread limit sends every shadow tile down the frustum path.
                    let opts =
                        TraceOptions { method, cull, backend, shadow_spread_limit: spread, ..TraceOptions::default() };
                    let tracer = Tracer::new(walked, opts).unwrap();
                    let (hits, _) = trace_image(&tracer, &primary, w, h, tile, None);
                    let (_, occ) = trace_image(&tracer, &shadow, w, h, tile, Some(light));
                    for i in 0..w * h {
                        if primary[i].is_some() {
                            assert!(
                                same_hit(hits[i], want_hits[i]),
                                "{what}: {opts:?} on {which}, tile {tile} pixel {i}: {:?} vs mono {:?}",
                                hits[i],
                                want_hits[i]
                            );
                        }
                        assert_eq!(occ[i], want_occ[i], "{what}: {opts:?} on {which}, tile {tile} shadow pixel {i}");
                    }
                }
            }
        }
    }
}

#[test]
fn coherent_methods_match_mono_on_every_builtin_scene() {
    for name in builtin::names() {
        let scene = builtin::build(name, Detail::Test).unwrap();
        let cam = scene.default_view().unwrap().camera;
        let light = scene.lights[0].position;
        check_view(&scene, &cam, light, 45, 37, name);
    }
}

#[test]
fn coherent_methods_match_mono_on_adversarial_cameras() {
    let scene = builtin::build("atrium", Detail::Test).unwrap();
    let light = scene.lights[0].position;
    let views = [
        ("along +x", Camera::look_at(Vec3::new(-10.0, 2.0, 0.0), Vec3::new(10.0, 2.0, 0.0), Vec3::Y, 60.0), 40, 40),
        ("down -y", Camera::look_at(Vec3::new(0.5, 11.0, 0.5), Vec3::new(0.5, 0.0, 0.5), Vec3::X, 90.0), 33, 33),
        (
            "inside a column",
            Camera::look_at(Vec3::new(-3.0, 2.0, 4.0), Vec3::new(3.0, 2.5, -4.0), Vec3::Y, 70.0),
            24,
            17,
        ),
        ("fov 1", Camera::look_at(Vec3::new(-12.0, 2.5, 0.3), Vec3::new(10.0, 5.5, 0.0), Vec3::Y, 1.0), 20, 20),
        ("fov 170", Camera::look_at(Vec3::new(0.0, 3.0, 0.0), Vec3::new(5.0, 3.0, 1.0), Vec3::Y, 170.0), 50, 30),
        ("1x1", Camera::look_at(Vec3::new(-12.5, 2.5, 0.0), Vec3::new(10.0, 5.5, 0.0), Vec3::Y, 65.0), 1, 1),
        ("1x1000", Camera::look_at(Vec3::new(-12.5, 2.5, 0.0), Vec3::new(10.0, 5.5, 0.0), Vec3::Y, 65.0), 1, 1000),
        (
            "on a split plane",
            Camera::look_at(Vec3::new(0.0, 6.0, 4.0), Vec3::new(0.0, 6.0, -4.0), Vec3::Y, 80.0),
            31,
            29,
        ),
    ];
    for (what, cam, w, h) in views {
        check_view(&scene, &cam, light, w, h, what);
    }
}

#[test]
fn shadow_rays_from_a_light_on_a_split_plane() {
    // The light sits exactly on split planes of the tree and on a triangle's plane.
    let scene = builtin::build("arena", Detail::Test).unwrap();
    let cam = scene.default_view().unwrap().camera;
    for light in [Vec3::new(0.0, 4.8, 0.0), Vec3::new(8.0, 4.4, 0.0), Vec3::new(3.0, 14.0, 2.0)] {
        check_view(&scene, &cam, light, 40, 32, &format!("light {light}"));
    }
}

/// The renderer's pixels do not depend on the traversal method (primary hits and hard shadows).
#[test]
fn rendered_frames_are_identical_for_every_method() {
    use raylab_core::render::{RenderSettings, render};
    let scene = builtin::build("atrium", Detail::Test).unwrap();
    let thesis_params = StructureParams { packet_kd: KdParams::default(), ..StructureParams::default() };
    let methods = [Method::Mono, Method::Packet, Method::Frustum, Method::Mft, Method::Cone, Method::MftCone];
    let structures = Structures::build(&scene, &methods, Purpose::Frames, &thesis_params).unwrap();
    let cam = scene.default_view().unwrap().camera;
    let light = scene.lights[0];
    let mut frames = Vec::new();
    for method in methods {
        for tile in [4, 16] {
            let tracer = Tracer::new(&structures, TraceOptions { method, ..Default::default() }).unwrap();
            let settings = RenderSettings { width: 61, height: 43, tile, ..Default::default() };
            frames.push((method, tile, render(&scene, &tracer, &cam, light, &settings).rgba));
        }
    }
    for (method, tile, f) in &frames[1..] {
        let diff = f.iter().zip(&frames[0].2).filter(|(a, b)| a != b).count();
        assert_eq!(diff, 0, "{method} tile {tile}: {diff} pixels differ from mono");
    }
}

/// Invalid rays (zero or infinite direction, NaN origin or interval) inside a tile leave their pixels empty for
/// every coherent method, and the valid rays around them still get mono's answers.
#[test]
fn invalid_rays_in_a_tile_are_ignored() {
    let scene = builtin::build("arena", Detail::Test).unwrap();
    let cam = scene.default_view().unwrap().camera;
    let light = scene.lights[0].position;
    let thesis_params = StructureParams { packet_kd: KdParams::default(), ..StructureParams::default() };
    let structures = Structures::build(&scene, &METHODS, Purpose::Frames, &thesis_params).unwrap();
    let tree = structures.kd(Structure::ThesisKd).unwrap();
    let (w, h) = (16, 16);
    let mut rays = WorkloadBuilder::new(&scene, &cam, light, w as u32, h as u32, tree).build(RayKind::Primary).rays;
    let o = cam.eye;
    let bad = [
        Ray::new(o, Vec3::ZERO),
        Ray::new(Vec3::NAN, Vec3::X),
        Ray::new(o, Vec3::new(f32::INFINITY, 0.0, 0.0)),
        Ray::segment(o, Vec3::NEG_Y, 0.0, f32::NAN),
        Ray::segment(o, Vec3::NEG_Y, f32::NAN, 1.0),
    ];
    for (k, i) in (0..w * h).step_by(7).enumerate() {
        rays[i] = Some(bad[k % bad.len()]);
    }
    let mono = Tracer::new(&structures, TraceOptions { method: Method::Mono, ..Default::default() }).unwrap();
    let (want_hits, want_occ) = trace_image(&mono, &rays, w, h, 8, None);
    for (k, i) in (0..w * h).step_by(7).enumerate() {
        assert!(want_hits[i].is_none() && !want_occ[i], "mono traced bad ray {k}");
    }
    for method in METHODS {
        for backend in Backend::available() {
            for tile in [4, 8, 16] {
                let opts = TraceOptions { method, backend, ..TraceOptions::default() };
                let tracer = Tracer::new(&structures, opts).unwrap();
                let (hits, occ) = trace_image(&tracer, &rays, w, h, tile, None);
                for i in 0..w * h {
                    assert!(same_hit(hits[i], want_hits[i]), "{method} {backend:?} tile {tile} pixel {i}");
                    assert_eq!(occ[i], want_occ[i], "{method} {backend:?} tile {tile} pixel {i} occlusion");
                }
            }
        }
    }
}
