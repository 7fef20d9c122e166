//! Moving geometry: the animation moves its objects rigidly; after a move, `Structures::update` refits the MBVH,
//! rebuilds the kd-tree and sets DACRT up again, and all equal brute force on the moved scene; bad moves are
//! refused.

mod common;

use common::{adversarial_rays, check_hits};
use glam::Vec3;
use raylab_core::mbvh::{Mbvh, MbvhParams};
use raylab_core::method::{Method, Purpose, Structure};
use raylab_core::ray::Ray;
use raylab_core::scene::SceneBuilder;
use raylab_core::structures::{StructureParams, Structures};
use raylab_core::trace::{TraceOptions, Tracer};
use raylab_scene::animation::Animation;
use raylab_scene::builtin::{self, Detail};

#[test]
fn every_structure_follows_the_motion() {
    let base = builtin::build("atrium", Detail::Test).unwrap();
    let (mut scene, anim) = Animation::add_movers(&base);
    assert!(anim.moving_triangles() > 100);
    assert_eq!(scene.triangle_count(), base.triangle_count() + anim.moving_triangles());
    let rest = scene.positions.clone();
    let methods = [Method::Mono, Method::Mbvh, Method::Dacrt];
    let mut structures = Structures::build(&scene, &methods, Purpose::Rays, &StructureParams::default()).unwrap();
    // Spatial splits everywhere: leaves hold clipped parts of triangles, which a refit grows to whole ones.
    let spatial_params =
        StructureParams { mbvh: MbvhParams { spatial_min_refs: 0, ..MbvhParams::default() }, ..Default::default() };
    let mut spatial = Structures::build(&scene, &[Method::Mbvh], Purpose::Rays, &spatial_params).unwrap();
    let first_moving = base.positions.len();
    for (k, t) in [0.3f32, 1.1, 2.9].into_iter().enumerate() {
        anim.apply(&mut scene, t).unwrap();
        assert_eq!(scene.positions[..first_moving], rest[..first_moving], "the base scene stays put");
        assert!(scene.positions[first_moving..] != rest[first_moving..], "t = {t}: the objects moved");
        let times = structures.update(&scene).unwrap();
        let updated: Vec<Structure> = times.iter().map(|&(s, _)| s).collect();
        assert_eq!(updated, [Structure::ThesisKd, Structure::Mbvh, Structure::Dacrt]);
        let refit = times[1].1;
        assert!(refit.as_secs_f64() < 1.0);
        spatial.update(&scene).unwrap();
        let tracer = |s, method| Tracer::for_rays(s, TraceOptions { method, ..TraceOptions::default() }).unwrap();
        let kd = structures.kd(Structure::ThesisKd).unwrap();
        // Rays aimed at the moving objects' vertices and random rays.
        let mut rays = adversarial_rays(&scene, kd, 150, 40 + k as u32);
        let eye = scene.default_view().unwrap().camera.eye;
        rays.extend(scene.positions[first_moving..].iter().step_by(7).map(|&p| Ray::new(eye, p - eye)));
        let what = format!("t = {t}");
        check_hits(&scene, &tracer(&structures, Method::Mbvh), &rays, &format!("refitted MBVH, {what}"));
        let spatial_mbvh = tracer(&spatial, Method::Mbvh);
        check_hits(&scene, &spatial_mbvh, &rays, &format!("refitted MBVH with spatial splits, {what}"));
        check_hits(&scene, &tracer(&structures, Method::Mono), &rays, &format!("rebuilt kd-tree, {what}"));
        check_hits(&scene, &tracer(&structures, Method::Dacrt), &rays[..400], &format!("DACRT, {what}"));
    }
    // The pose depends on the time only: back at t = 0 the rest pose returns (up to rounding).
    anim.apply(&mut scene, 0.0).unwrap();
    for (a, b) in scene.positions.iter().zip(&rest) {
        assert!((*a - *b).length() <= 1e-4 * (1.0 + b.length()), "{a} vs {b}");
    }
}

#[test]
fn bad_moves_and_refits_are_refused() {
    let base = builtin::build("arena", Detail::Test).unwrap();
    let (mut scene, _) = Animation::add_movers(&base);
    let n = scene.positions.len();
    let before = scene.positions.clone();
    assert!(scene.set_vertices(n - 1, &[Vec3::ZERO, Vec3::ONE], None).unwrap_err().contains("past"));
    assert!(scene.set_vertices(0, &[Vec3::new(f32::NAN, 0.0, 0.0)], None).unwrap_err().contains("non-finite"));
    assert!(scene.set_vertices(0, &[Vec3::ZERO], Some(&[])).unwrap_err().contains("normals"));
    assert_eq!(scene.positions, before, "a refused move changes nothing");
    let mut mbvh = Mbvh::build(&base);
    let e = mbvh.refit(&scene).unwrap_err();
    assert_eq!((e.built, e.now), (base.triangle_count(), scene.triangle_count()));

    // An empty scene still gets its movers, in a unit box.
    let (empty, anim) = Animation::add_movers(&SceneBuilder::new().build());
    assert_eq!(empty.triangle_count(), anim.moving_triangles());
    assert!(!empty.bounds().is_empty());
}
