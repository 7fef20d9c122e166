//! The SIMD backend chosen in `TraceOptions` reaches every kernel: the MBVH, MBVH RS and DACRT methods run
//! with the lanes of the backend asked for (scalar lanes for `scalar`), and every backend gives the same hits.

use glam::Vec3;
use raylab_core::method::{Method, Purpose};
use raylab_core::ray::Ray;
use raylab_core::scene::{Camera, Scene, SceneBuilder, Triangle};
use raylab_core::stats::TraversalStats;
use raylab_core::structures::{StructureParams, Structures};
use raylab_core::trace::{TraceOptions, Tracer};
use raylab_simd::{Backend, dispatch_log};

/// A few hundred small triangles scattered in a box, in a fixed pseudo-random pattern.
fn scattered() -> Scene {
    let mut b = SceneBuilder::new();
    let mut x = 0x2545_f491_u32;
    let mut next = || {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        x as f32 / u32::MAX as f32
    };
    for i in 0..400u32 {
        let c = Vec3::new(next() * 10.0 - 5.0, next() * 10.0 - 5.0, next() * 10.0 - 5.0);
        for _ in 0..3 {
            b.positions.push(c + Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5));
        }
        b.triangles.push(Triangle { v: [3 * i, 3 * i + 1, 3 * i + 2], material: 0 });
    }
    b.build()
}

/// Camera rays of a 32x32 tile, and the same rays as segments toward a point light.
fn rays() -> (Vec<Option<Ray>>, Vec<Option<Ray>>) {
    let cam = Camera::look_at(Vec3::new(0.0, 0.0, -14.0), Vec3::ZERO, Vec3::Y, 60.0);
    let raster = cam.raster(32, 32);
    let primary: Vec<Option<Ray>> =
        (0..32).flat_map(|y| (0..32).map(move |x| (x, y))).map(|(x, y)| Some(raster.primary(x, y))).collect();
    let light = Vec3::new(3.0, 8.0, -2.0);
    let shadow = primary
        .iter()
        .map(|r| r.map(|r| Ray::segment(r.origin + r.dir * 5.0, light - (r.origin + r.dir * 5.0), 1e-4, 1.0)))
        .collect();
    (primary, shadow)
}

#[test]
fn the_chosen_backend_drives_the_mbvh_stream_and_dacrt_kernels() {
    let scene = scattered();
    let methods = [Method::Mbvh, Method::MbvhRs, Method::Dacrt];
    let structures = Structures::build(&scene, &methods, Purpose::Rays, &StructureParams::default()).unwrap();
    let (primary, shadow) = rays();
    // One thread, so that every dispatch is counted on the one that reads the log (DACRT forks on a pool of two
    // or more).
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    for method in methods {
        let mut answers = Vec::new();
        for backend in Backend::available() {
            let tracer =
                Tracer::for_rays(&structures, TraceOptions { method, backend, ..TraceOptions::default() }).unwrap();
            let mut stats = TraversalStats::default();
            let (mut hits, mut blocked) = (vec![None; primary.len()], vec![false; shadow.len()]);
            let counts = pool.install(|| {
                dispatch_log::take();
                tracer.intersect_tile(&primary, 32, 32, &mut hits, &mut stats);
                tracer.occluded_tile(&shadow, 32, 32, None, &mut blocked, &mut stats);
                dispatch_log::take()
            });
            // These kernels are written for at most eight lanes: AVX-512 runs them as AVX2 does.
            let lanes = backend.at_most_eight_lanes();
            let order = [Backend::Scalar, Backend::Sse, Backend::Avx2, Backend::Avx512];
            let slot = order.iter().position(|&b| b == lanes).unwrap();
            assert!(counts[slot] > 0, "{method} {}: no dispatch with its lanes: {counts:?}", backend.name());
            let others: u64 = counts.iter().enumerate().filter(|&(k, _)| k != slot).map(|(_, &n)| n).sum();
            assert_eq!(others, 0, "{method} {}: dispatched other lanes: {counts:?}", backend.name());
            let hits: Vec<_> = hits.iter().map(|h| h.map(|h| (h.tri, h.t.to_bits()))).collect();
            answers.push((backend, hits, blocked));
        }
        let (_, hits, blocked) = &answers[0];
        assert!(hits.iter().filter(|h| h.is_some()).count() > 50, "{method}: the view hits the scene");
        for (backend, h, b) in &answers[1..] {
            assert_eq!(h, hits, "{method} {}: hits differ from the widest lanes'", backend.name());
            assert_eq!(b, blocked, "{method} {}: occlusion differs from the widest lanes'", backend.name());
        }
    }
}

#[test]
fn a_tracer_refuses_a_method_whose_structure_is_missing() {
    let scene = scattered();
    let structures = Structures::build(&scene, &[Method::Mbvh], Purpose::Rays, &StructureParams::default()).unwrap();
    for method in [Method::Mono, Method::Packet, Method::Dacrt, Method::Reference] {
        let e = Tracer::for_rays(&structures, TraceOptions { method, ..TraceOptions::default() }).err();
        let e = e.unwrap_or_else(|| panic!("{method}: accepted without its structure"));
        assert_eq!(e.method, method);
        assert!(e.to_string().contains(method.name()), "{e}");
    }
    // Frames of the MBVH methods also walk the thesis's kd-tree (edge-width and sampled shadows).
    let e = Tracer::new(&structures, TraceOptions { method: Method::MbvhRs, ..TraceOptions::default() }).err();
    assert_eq!(e.map(|e| e.structure), Some(raylab_core::method::Structure::ThesisKd));
    assert!(Tracer::for_rays(&structures, TraceOptions { method: Method::MbvhRs, ..TraceOptions::default() }).is_ok());
}
