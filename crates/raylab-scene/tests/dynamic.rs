//! Moving geometry: the animation moves its objects rigidly; after a move, a refitted MBVH, a rebuilt kd-tree
//! and DACRT (set up again from the moved triangles) all equal brute force on the moved scene; bad moves are refused.

mod common;

use common::{adversarial_rays, check_hits};
use glam::Vec3;
use raylab_core::dacrt::Dacrt;
use raylab_core::kdtree::{KdParams, KdTree};
use raylab_core::mbvh::{Mbvh, MbvhParams};
use raylab_core::ray::Ray;
use raylab_core::scene::SceneBuilder;
use raylab_scene::animation::Animation;
use raylab_scene::builtin::{self, Detail};

#[test]
fn every_structure_follows_the_motion() {
    let base = builtin::build("atrium", Detail::Test).unwrap();
    let (mut scene, anim) = Animation::add_movers(&base);
    assert!(anim.moving_triangles() > 100);
    assert_eq!(scene.triangle_count(), base.triangle_count() + anim.moving_triangles());
    let rest = scene.positions.clone();
    let mut mbvh = Mbvh::build(&scene);
    // Spatial splits everywhere: leaves hold clipped parts of triangles, which a refit grows to whole ones.
    let mut spatial = Mbvh::build_with(&scene, &MbvhParams { spatial_min_refs: 0, ..MbvhParams::default() });
    let first_moving = base.positions.len();
    for (k, t) in [0.3f32, 1.1, 2.9].into_iter().enumerate() {
        anim.apply(&mut scene, t).unwrap();
        assert_eq!(scene.positions[..first_moving], rest[..first_moving], "the base scene stays put");
        assert!(scene.positions[first_moving..] != rest[first_moving..], "t = {t}: the objects moved");
        let refit = mbvh.refit(&scene).unwrap();
        assert!(refit.as_secs_f64() < 1.0);
        spatial.refit(&scene).unwrap();
        let kd = KdTree::build(&scene, &KdParams::default()).unwrap();
        let dacrt = Dacrt::new(&scene);
        // Rays aimed at the moving objects' vertices and random rays.
        let mut rays = adversarial_rays(&scene, &kd, 150, 40 + k as u32);
        let eye = scene.default_view().unwrap().camera.eye;
        rays.extend(scene.positions[first_moving..].iter().step_by(7).map(|&p| Ray::new(eye, p - eye)));
        let what = format!("t = {t}");
        check_hits(&scene, &mbvh, &rays, &format!("refitted MBVH, {what}"));
        check_hits(&scene, &spatial, &rays, &format!("refitted MBVH with spatial splits, {what}"));
        check_hits(&scene, &kd, &rays, &format!("rebuilt kd-tree, {what}"));
        check_hits(&scene, &dacrt, &rays[..400], &format!("DACRT, {what}"));
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
