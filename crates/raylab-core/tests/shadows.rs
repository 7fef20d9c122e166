//! Shadow techniques (thesis chapter 5 and 4.1.9, the shadow cache of Ray Tracing II): each gives the same
//! pixels with every traversal method, the kd-tree's edge-width rays agree with brute force, and each
//! technique meets a case with a known answer.

mod common;

use glam::Vec3;
use raylab_core::edge_width::EdgeWidth;
use raylab_core::kdtree::KdParams;
use raylab_core::method::{Method, Purpose, Structure};
use raylab_core::packet::MAX_LANES;
use raylab_core::ray::Ray;
use raylab_core::reference::BruteForce;
use raylab_core::render::shade::Surface;
use raylab_core::render::{RenderSettings, ShadowScratch, ShadowTracer, render, surface_epsilon};
use raylab_core::scene::{Camera, Material, PointLight, Scene};
use raylab_core::shadow::{SampleBound, Shadows};
use raylab_core::stats::TraversalStats;
use raylab_core::structures::{StructureParams, Structures};
use raylab_core::trace::{TraceOptions, Tracer};
use raylab_scene::builtin::{self, Detail};
use raylab_scene::mesh::{Jitter, MeshBuilder};
use raylab_simd::Backend;

/// The methods compared with mono (the MBVH's single rays and DACRT's sets included).
const COHERENT: [Method; 7] =
    [Method::Packet, Method::Frustum, Method::Mft, Method::Cone, Method::MftCone, Method::Mbvh, Method::Dacrt];

fn techniques(light: &PointLight) -> Vec<Shadows> {
    let r = light.radius.max(0.1);
    let mut t = vec![
        Shadows::None,
        Shadows::Hard,
        Shadows::Cached,
        Shadows::EdgeWidth { radius: r, leak_fix: false },
        Shadows::EdgeWidth { radius: r * 3.0, leak_fix: true },
    ];
    for bound in SampleBound::ALL {
        t.push(Shadows::MultiSample { samples: 4, bound });
    }
    t.push(Shadows::MultiSample { samples: 16, bound: SampleBound::Cone });
    t
}

fn frame(scene: &Scene, tracer: &Tracer, cam: &Camera, light: PointLight, shadows: Shadows, tile: u32) -> Vec<[u8; 4]> {
    let settings = RenderSettings { width: 37, height: 27, tile, shadows, ..Default::default() };
    render(scene, tracer, cam, light, &settings).rgba
}

/// Every technique, reflections and refractions included, gives the same pixels with every method, and with
/// the brute-force reference.
#[test]
fn every_technique_gives_the_same_pixels_with_every_method() {
    for name in ["atrium", "arena"] {
        let scene = builtin::build(name, Detail::Test).unwrap();
        let structures = on_thesis_tree(&scene);
        let cam = scene.default_view().unwrap().camera;
        let light = scene.lights[0];
        for shadows in techniques(&light) {
            let mono = Tracer::new(&structures, TraceOptions::default()).unwrap();
            let want = frame(&scene, &mono, &cam, light, shadows, 8);
            let lit = want.iter().filter(|p| p[0] > 40).count();
            assert!(lit > want.len() / 4, "{name} {shadows}: the frame is mostly dark ({lit} lit pixels)");
            // Triangles hit at exactly the same distance (coplanar faces of touching solids) are a tie: brute
            // force and DACRT take the lowest id, the kd-tree's and the MBVH's walks the one they meet last in
            // their own order, so methods off the kd-tree may show the other face's material in a pixel or two
            // (the MBVH's hits equal the reference's up to such ties: tests/mbvh.rs), never a different
            // distance.
            let ties = |method| if matches!(method, Method::Dacrt | Method::Mbvh) { 2 } else { 0 };
            for method in COHERENT {
                for tile in [4, 16] {
                    let tracer = Tracer::new(&structures, TraceOptions { method, ..Default::default() }).unwrap();
                    let got = frame(&scene, &tracer, &cam, light, shadows, tile);
                    let diff = got.iter().zip(&want).filter(|(a, b)| a != b).count();
                    assert!(
                        diff <= ties(method),
                        "{name}, {shadows}, {method} tile {tile}: {diff} pixels differ from mono"
                    );
                }
            }
            if !matches!(shadows, Shadows::MultiSample { samples: 16, .. }) {
                let reference =
                    Tracer::new(&structures, TraceOptions { method: Method::Reference, ..Default::default() }).unwrap();
                let got = frame(&scene, &reference, &cam, light, shadows, 8);
                let diff = got.iter().zip(&want).filter(|(a, b)| a != b).count();
                assert!(diff <= 2, "{name}, {shadows}: {diff} pixels differ from the brute-force reference");
                // DACRT breaks ties as brute force does, so it gives the reference's pixels exactly.
                let tracer =
                    Tracer::new(&structures, TraceOptions { method: Method::Dacrt, ..Default::default() }).unwrap();
                let dacrt_frame = frame(&scene, &tracer, &cam, light, shadows, 8);
                let diff = dacrt_frame.iter().zip(&got).filter(|(a, b)| a != b).count();
                assert_eq!(diff, 0, "{name}, {shadows}: {diff} DACRT pixels differ from the brute-force reference");
            }
        }
    }
}

/// The cache only skips work: its pixels are the hard shadow's, and its counters add up (whether it pays
/// depends on the scene; `raylab-bench tables` reports its hit rate).
#[test]
fn the_shadow_cache_changes_speed_not_pixels() {
    let scene = builtin::build("atrium", Detail::Test).unwrap();
    let structures = common::structures(&scene, &[Method::Mono]);
    let tracer = Tracer::new(&structures, TraceOptions::default()).unwrap();
    let cam = scene.default_view().unwrap().camera;
    let light = scene.lights[0];
    let settings = |shadows| RenderSettings { width: 64, height: 48, shadows, max_depth: 0, ..Default::default() };
    let hard = render(&scene, &tracer, &cam, light, &settings(Shadows::Hard));
    let cached = render(&scene, &tracer, &cam, light, &settings(Shadows::Cached));
    assert_eq!(hard.rgba, cached.rgba);
    let s = cached.stats;
    assert!(s.cache_lookups > 0 && s.cache_hits > 0, "{s:?}");
    assert!(s.cache_hits <= s.cache_lookups && s.cache_lookups < hard.stats.rays);
    assert_eq!(hard.stats.cache_lookups, 0);
    // Each tile starts with an empty cache, whichever worker takes it after whichever tile, so the counters do
    // not depend on how the tiles fall to threads.
    for threads in [1, 3] {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        let again = pool.install(|| render(&scene, &tracer, &cam, light, &settings(Shadows::Cached)));
        assert_eq!(again.rgba, cached.rgba);
        assert_eq!(again.stats, cached.stats, "{threads} threads");
    }
    // Every shadow ray is counted once, whether the cache answered it or a traversal did.
    assert_eq!(s.rays, hard.stats.rays);
    assert!(s.nodes < hard.stats.nodes, "cache hits skip traversals");
}

/// Random shadow segments through the built-in scenes: the kd-tree's edge-width walk finds the same
/// crossings, and so the same occlusion, as testing every triangle.
#[test]
fn kd_edge_widths_match_brute_force() {
    for name in ["atrium", "arena", "kitchen", "forest"] {
        let scene = builtin::build(name, Detail::Test).unwrap();
        let structures = on_thesis_tree(&scene);
        let tree = structures.kd(Structure::ThesisKd).unwrap();
        let bf = BruteForce::new(&scene);
        let b = scene.bounds();
        let mut rng = Jitter::new(7);
        let mut point =
            || Vec3::new(rng.range(b.min.x, b.max.x), rng.range(b.min.y, b.max.y), rng.range(b.min.z, b.max.z));
        let (mut s, mut partial) = (TraversalStats::default(), 0);
        for leak_fix in [false, true] {
            let mut a = EdgeWidth::new(b.diagonal() * 0.02, leak_fix);
            let mut c = a.clone();
            for i in 0..3000 {
                let (from, to) = (point(), point());
                let d = to - from;
                let ray = Ray::segment(from, d / d.length(), 0.0, d.length());
                let got = tree.edge_width(&ray, &mut a, &mut s);
                let want = bf.edge_width(&ray, &mut c, &mut s);
                assert_eq!(got, want, "{name} ray {i} {ray:?} (leak fix {leak_fix})");
                partial += (got > 0.0 && got < 1.0) as usize;
            }
        }
        assert!(partial > 10, "{name}: only {partial} penumbra rays; the test says little");
    }
}

/// Edge-width walks traced in packets (every SIMD backend) give each ray the occlusion of its single walk:
/// random segments in all directions (packets of one sign class), segments converging on a light (the
/// renderer's case), axis-parallel ones with zero and negative-zero components, and segments starting on a
/// scene's bounding planes.
#[test]
fn packet_edge_widths_equal_single_walks() {
    for name in ["atrium", "arena", "kitchen", "forest"] {
        let scene = builtin::build(name, Detail::Test).unwrap();
        let structures = on_thesis_tree(&scene);
        let tree = structures.kd(Structure::ThesisKd).unwrap();
        let b = scene.bounds();
        let mut rng = Jitter::new(11);
        let mut point =
            || Vec3::new(rng.range(b.min.x, b.max.x), rng.range(b.min.y, b.max.y), rng.range(b.min.z, b.max.z));
        let segment = |from: Vec3, to: Vec3| {
            let d = to - from;
            Ray::segment(from, d / d.length(), 0.0, d.length())
        };
        let mut rays: Vec<Ray> = (0..1500).map(|_| segment(point(), point())).collect();
        let light = point();
        rays.extend((0..1500).map(|_| segment(point(), light)));
        for dir in [Vec3::X, Vec3::NEG_Y, Vec3::Z, Vec3::new(-0.0, 1.0, 0.0), Vec3::new(0.0, -0.0, -1.0)] {
            rays.extend((0..200).map(|_| Ray::segment(point(), dir, 0.0, b.diagonal())));
        }
        rays.extend((0..200).map(|_| {
            let mut from = point();
            from.x = b.min.x;
            segment(from, point())
        }));
        let mut s = TraversalStats::default();
        for leak_fix in [false, true] {
            let mut single = EdgeWidth::new(b.diagonal() * 0.02, leak_fix);
            let want: Vec<f32> = rays.iter().map(|r| tree.edge_width(r, &mut single, &mut s)).collect();
            let partial = want.iter().filter(|&&w| w > 0.0 && w < 1.0).count();
            assert!(partial > 10, "{name}: only {partial} penumbra rays; the test says little");
            for backend in Backend::available() {
                let tracer =
                    Tracer::new(&structures, TraceOptions { method: Method::Packet, backend, ..Default::default() })
                        .unwrap();
                let mut states = vec![single.clone(); rays.len()];
                let mut got = vec![-1.0; rays.len()];
                tracer.edge_widths(&rays, None, &mut states, &mut got, &mut s);
                for (i, (g, w)) in got.iter().zip(&want).enumerate() {
                    assert_eq!(g, w, "{name} {backend:?} ray {i} {:?} (leak fix {leak_fix})", rays[i]);
                }
            }
        }
    }
}

/// Edge-width walks of the bundled methods (the segments of a tile, which end at the light, walked as
/// one frustum or cone from there) give each ray the occlusion of its single walk, on every backend, with
/// culling on and off: groups of one to a few hundred segments from around random spots, some right under
/// the light (direction signs mixed inside one bundle, zero components) and some too wide for a bundle
/// (which go as packets).
#[test]
fn bundle_edge_widths_equal_single_walks() {
    for name in ["atrium", "arena", "kitchen", "forest"] {
        let scene = builtin::build(name, Detail::Test).unwrap();
        let structures = on_thesis_tree(&scene);
        let tree = structures.kd(Structure::ThesisKd).unwrap();
        let b = scene.bounds();
        let mut rng = Jitter::new(5);
        let mut point =
            || Vec3::new(rng.range(b.min.x, b.max.x), rng.range(b.min.y, b.max.y), rng.range(b.min.z, b.max.z));
        // Half the groups end at the scene's light, half at a random point (maybe inside geometry, so that
        // crossings lie near both ends).
        let mut groups: Vec<(Vec3, Vec<Ray>)> = Vec::new();
        for g in 0..80 {
            let light = if g % 2 == 0 { scene.lights[0].position } else { point() };
            let mut centre = point();
            if g % 4 == 0 {
                (centre.x, centre.z) = (light.x, light.z);
            }
            // Most groups are narrow bundles; every sixth spreads over the whole scene.
            let spread = if g % 6 == 5 { b.diagonal() } else { (centre - light).length() * 0.02 };
            let n = [1, 37, 128, 300][(g / 4) % 4];
            groups.push((
                light,
                (0..n)
                    .map(|i| {
                        let mut p = centre + spread * (point() - b.center()) / b.diagonal();
                        if g % 4 == 0 && i % 3 == 0 {
                            p.x = light.x;
                        }
                        let d = light - p;
                        Ray::segment(p, d / d.length(), 0.0, d.length())
                    })
                    .collect(),
            ));
        }
        for leak_fix in [false, true] {
            let mut single = EdgeWidth::new(b.diagonal() * 0.05, leak_fix);
            let mut s = TraversalStats::default();
            let want: Vec<Vec<f32>> = groups
                .iter()
                .map(|(_, g)| g.iter().map(|r| tree.edge_width(r, &mut single, &mut s)).collect())
                .collect();
            let partial = want.iter().flatten().filter(|&&w| w > 0.0 && w < 1.0).count();
            assert!(partial > 10, "{name}: only {partial} penumbra rays; the test says little");
            for method in [Method::Frustum, Method::Mft, Method::Cone, Method::MftCone] {
                for cull in [true, false] {
                    for backend in Backend::available() {
                        let options = TraceOptions { method, backend, cull, ..Default::default() };
                        let tracer = Tracer::new(&structures, options).unwrap();
                        let mut s = TraversalStats::default();
                        for ((light, g), want) in groups.iter().zip(&want) {
                            let mut states = vec![single.clone(); g.len().max(MAX_LANES)];
                            let mut got = vec![-1.0; g.len()];
                            tracer.edge_widths(g, Some(*light), &mut states, &mut got, &mut s);
                            for (i, (a, w)) in got.iter().zip(want).enumerate() {
                                assert_eq!(a, w, "{name} {method:?} {backend:?} cull {cull} ray {i} {:?}", g[i]);
                            }
                        }
                        assert!(s.packets_tested > 0, "{name} {method:?}: no group went as a bundle");
                    }
                }
            }
        }
    }
}

/// A floor, and a closed box floating over it, lit from straight above.
fn box_over_floor(open_quad: bool) -> Scene {
    let mut m = MeshBuilder::new();
    m.material(Material::diffuse("floor", Vec3::ONE));
    m.quad(
        Vec3::new(-20.0, 0.0, 20.0),
        Vec3::new(20.0, 0.0, 20.0),
        Vec3::new(20.0, 0.0, -20.0),
        Vec3::new(-20.0, 0.0, -20.0),
    );
    if open_quad {
        m.quad(
            Vec3::new(-1.0, 2.5, 1.0),
            Vec3::new(1.0, 2.5, 1.0),
            Vec3::new(1.0, 2.5, -1.0),
            Vec3::new(-1.0, 2.5, -1.0),
        );
    } else {
        m.cuboid(Vec3::new(-1.0, 0.5, -1.0), Vec3::new(1.0, 2.5, 1.0));
    }
    let mut s = m.build();
    s.lights.push(PointLight { radius: 1.0, ..PointLight::at(Vec3::new(0.0, 10.0, 0.0)) });
    s
}

/// Visibility of the floor point `(x, 0, 0.05)` under `shadows`.
fn floor_visibility(scene: &Scene, structures: &Structures, shadows: Shadows, x: f32) -> f32 {
    let tracer = Tracer::new(structures, TraceOptions::default()).unwrap();
    let tree = structures.kd(Structure::ThesisKd).unwrap();
    let st = ShadowTracer { tracer: &tracer, light: scene.lights[0], shadows, epsilon: surface_epsilon(scene) };
    let ray = Ray::new(Vec3::new(x, 1e-3 + 0.4, 0.05), Vec3::NEG_Y);
    let hit = tree.intersect(&ray, &mut TraversalStats::default()).expect("the floor");
    st.at_hit(scene, &ray, &hit, 0, &mut TraversalStats::default())
}

/// The box's shadow: an umbra where the hard shadow is deep, a penumbra band inside the hard shadow's edge
/// whose width grows with R, and the chord widths Equation 5.1 predicts.
#[test]
fn a_closed_box_casts_an_umbra_and_a_penumbra_that_widens_with_r() {
    let scene = box_over_floor(false);
    let structures = on_thesis_tree(&scene);
    // The chord of a floor point's shadow segment through the box, by clipping it to the box's slabs; the
    // hard shadow ends near x = 4/3, where the segment just touches the box's top edge.
    let eps = surface_epsilon(&scene);
    let chord = |x: f32| {
        let (o, light) = (Vec3::new(x, eps, 0.05), scene.lights[0].position);
        let (lo, hi) = (Vec3::new(-1.0, 0.5, -1.0), Vec3::new(1.0, 2.5, 1.0));
        let d = light - o;
        let (mut t0, mut t1) = (0.0f32, 1.0f32);
        for k in 0..3 {
            if d[k] == 0.0 {
                if o[k] < lo[k] || o[k] > hi[k] {
                    return 0.0;
                }
                continue;
            }
            let (a, b) = ((lo[k] - o[k]) / d[k], (hi[k] - o[k]) / d[k]);
            t0 = t0.max(a.min(b));
            t1 = t1.min(a.max(b));
        }
        (t1 - t0).max(0.0) * d.length()
    };
    let mut band = Vec::new();
    for r in [0.5f32, 1.0] {
        let edge = Shadows::EdgeWidth { radius: r, leak_fix: false };
        let mut penumbra = 0;
        for k in 0..=160 {
            let x = k as f32 / 100.0;
            let hard = floor_visibility(&scene, &structures, Shadows::Hard, x);
            let soft = floor_visibility(&scene, &structures, edge, x);
            let predicted = 1.0 - (chord(x) / r).min(1.0);
            assert!((soft - predicted).abs() < 2e-3, "R {r}, x {x}: visibility {soft}, predicted {predicted}");
            if hard == 1.0 {
                assert_eq!(soft, 1.0, "R {r}, x {x}: shadow outside the hard shadow");
            }
            if x < 0.9 {
                assert_eq!(soft, 0.0, "R {r}, x {x}: no umbra under the box");
            }
            penumbra += (soft > 0.0 && soft < 1.0) as usize;
        }
        band.push(penumbra);
    }
    assert!(band[0] > 3 && band[1] > band[0], "penumbra widths {band:?} should grow with R");
}

/// An open quad has no exit crossing: its shadow is hard whatever R is.
#[test]
fn a_thin_open_quad_falls_back_to_a_hard_shadow() {
    let scene = box_over_floor(true);
    let structures = on_thesis_tree(&scene);
    for k in 0..=40 {
        let x = k as f32 / 20.0;
        let hard = floor_visibility(&scene, &structures, Shadows::Hard, x);
        for r in [0.2, 5.0] {
            let soft = floor_visibility(&scene, &structures, Shadows::EdgeWidth { radius: r, leak_fix: false }, x);
            assert_eq!(soft, hard, "x {x}, R {r}");
        }
    }
    assert_eq!(floor_visibility(&scene, &structures, Shadows::Hard, 0.0), 0.0);
}

/// A sphere light of radius 1 at height 10 over a point, half hidden by a straight edge at height 5: the seen
/// share of the light is a circular segment, and multi-sampling converges to it with every bound.
#[test]
fn multi_sampled_visibility_converges_to_the_analytic_fraction() {
    for edge_x in [-0.3f32, 0.0, 0.2, 0.45] {
        let mut m = MeshBuilder::new();
        m.quad(
            Vec3::new(-20.0, 0.0, 20.0),
            Vec3::new(20.0, 0.0, 20.0),
            Vec3::new(20.0, 0.0, -20.0),
            Vec3::new(-20.0, 0.0, -20.0),
        );
        m.quad(
            Vec3::new(-50.0, 5.0, -50.0),
            Vec3::new(-50.0, 5.0, 50.0),
            Vec3::new(edge_x, 5.0, 50.0),
            Vec3::new(edge_x, 5.0, -50.0),
        );
        let mut scene = m.build();
        scene.lights.push(PointLight { radius: 1.0, ..PointLight::at(Vec3::new(0.0, 10.0, 0.0)) });
        let structures = on_thesis_tree(&scene);
        let tree = structures.kd(Structure::ThesisKd).unwrap();
        // Seen from the origin, the edge falls on the light's disc at x = 2 * edge_x; the disc beyond it shows.
        let d = 2.0 * edge_x as f64;
        let analytic = (d.clamp(-1.0, 1.0).acos() - d * (1.0 - d * d).max(0.0).sqrt()) / std::f64::consts::PI;
        let tracer = Tracer::new(&structures, TraceOptions::default()).unwrap();
        let ray = Ray::new(Vec3::new(0.0, 0.5, 0.0), Vec3::NEG_Y);
        let hit = tree.intersect(&ray, &mut TraversalStats::default()).unwrap();
        for (samples, tol) in [(1024, 0.01), (32, 0.06)] {
            for bound in SampleBound::ALL {
                let st = ShadowTracer {
                    tracer: &tracer,
                    light: scene.lights[0],
                    shadows: Shadows::MultiSample { samples, bound },
                    epsilon: surface_epsilon(&scene),
                };
                let mean =
                    (0..8).map(|seed| st.at_hit(&scene, &ray, &hit, seed, &mut TraversalStats::default())).sum::<f32>()
                        / 8.0;
                assert!(
                    (mean as f64 - analytic).abs() < tol,
                    "edge at {edge_x}, {samples} samples, {} bound: {mean}, analytic {analytic}",
                    bound.name()
                );
            }
        }
    }
}

/// Plain packets share their lanes among neighbouring points when a point's samples fill only part of one
/// (4 samples in 8 or 16 lanes, 8 in 16): on every SIMD backend each point of a layer keeps exactly the lit
/// fraction that tracing its own samples ray by ray gives, with points missing (sky) or facing away from the
/// light in between and a layer whose size is no multiple of the points per packet.
#[test]
fn packets_shared_by_neighbouring_points_keep_each_points_visibility() {
    let scene = builtin::build("atrium", Detail::Test).unwrap();
    let structures = on_thesis_tree(&scene);
    let tree = structures.kd(Structure::ThesisKd).unwrap();
    let cam = scene.default_view().unwrap().camera;
    let light = PointLight { radius: scene.lights[0].radius.max(0.5), ..scene.lights[0] };
    let (w, h) = (37u32, 27u32);
    let raster = cam.raster(w, h);
    let rays: Vec<Ray> = (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).map(|(x, y)| raster.primary(x, y)).collect();
    let mut stats = TraversalStats::default();
    let hits: Vec<_> = rays.iter().map(|r| tree.intersect(r, &mut stats)).collect();
    let surfaces: Vec<_> = rays.iter().zip(&hits).map(|(r, h)| h.map(|h| Surface::at(&scene, r, &h))).collect();
    assert!(surfaces.iter().any(Option::is_none) && surfaces.iter().any(Option::is_some));
    let seeds: Vec<u32> = (0..w * h).collect();
    let dims = (w as usize, h as usize);
    let reference = Tracer::new(&structures, TraceOptions { method: Method::Reference, ..Default::default() }).unwrap();
    for samples in [4, 8, 16] {
        let shadows = Shadows::MultiSample { samples, bound: SampleBound::Packets };
        let visibility = |tracer: &Tracer| {
            let st = ShadowTracer { tracer, light, shadows, epsilon: surface_epsilon(&scene) };
            st.visibility(&surfaces, dims, &seeds, &mut TraversalStats::default(), &mut ShadowScratch::default())
        };
        let want = visibility(&reference);
        let penumbra = want.iter().filter(|&&v| v > 0.0 && v < 1.0).count();
        assert!(penumbra > 10, "{samples} samples: only {penumbra} points in penumbra");
        for backend in Backend::available() {
            let tracer =
                Tracer::new(&structures, TraceOptions { method: Method::Mft, backend, ..Default::default() }).unwrap();
            let got = visibility(&tracer);
            for (i, (g, v)) in got.iter().zip(&want).enumerate() {
                assert_eq!(g, v, "{samples} samples, {backend:?}: point {i}");
            }
            assert_eq!(got.len(), want.len());
        }
    }
}

/// With a light of radius zero every soft technique is the hard shadow.
#[test]
fn a_point_light_makes_every_technique_hard() {
    let scene = builtin::build("arena", Detail::Test).unwrap();
    let structures = on_thesis_tree(&scene);
    let tracer = Tracer::new(&structures, TraceOptions { method: Method::Mft, ..Default::default() }).unwrap();
    let cam = scene.default_view().unwrap().camera;
    let light = PointLight { radius: 0.0, ..scene.lights[0] };
    let hard = frame(&scene, &tracer, &cam, light, Shadows::Hard, 8);
    for shadows in [
        Shadows::EdgeWidth { radius: 0.0, leak_fix: false },
        Shadows::MultiSample { samples: 4, bound: SampleBound::Pyramid },
        Shadows::MultiSample { samples: 8, bound: SampleBound::Cone },
    ] {
        assert_eq!(frame(&scene, &tracer, &cam, light, shadows, 8), hard, "{shadows}");
    }
}

/// Every method's structures for frames, with the thesis's kd-tree for every kd-tree method (both slots take
/// its cost model), and the brute-force reference.
fn on_thesis_tree(scene: &Scene) -> Structures {
    let params = StructureParams { packet_kd: KdParams::default(), ..StructureParams::default() };
    Structures::build(scene, &Method::ALL, Purpose::Frames, &params).unwrap()
}
