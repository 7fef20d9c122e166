//! Rays from inside closed meshes, aimed exactly at their vertices and edge midpoints, must always hit:
//! the watertight triangle test never lets a ray slip between two triangles that share an edge.

use glam::{Affine3A, Quat, Vec3};
use raylab_core::kdtree::{KdParams, KdTree};
use raylab_core::ray::Ray;
use raylab_core::reference::BruteForce;
use raylab_core::stats::TraversalStats;
use raylab_scene::MeshBuilder;

/// Adds one closed solid to a builder.
type Solid = Box<dyn Fn(&mut MeshBuilder)>;

#[test]
fn closed_meshes_never_leak() {
    // Each solid with a point inside it; a rotation puts the edges off the axes.
    let solids: Vec<(Solid, Vec3)> = vec![
        (Box::new(|m| m.sphere(Vec3::ZERO, 1.0, 12, 16)), Vec3::new(0.1, -0.05, 0.02)),
        (Box::new(|m| m.cuboid(Vec3::splat(-1.0), Vec3::new(1.0, 0.5, 2.0))), Vec3::new(0.3, 0.1, -0.2)),
        (Box::new(|m| m.torus(Vec3::ZERO, 1.0, 0.35, 16, 8)), Vec3::new(1.0, 0.0, 0.0)),
        (Box::new(|m| m.cylinder(Vec3::ZERO, 0.7, 1.5, 20)), Vec3::new(0.1, 0.7, 0.1)),
        (Box::new(|m| m.arch(Vec3::ZERO, 1.0, 1.4, 0.5, 12)), Vec3::new(0.0, 1.2, 0.0)),
    ];
    for (k, (make, inside)) in solids.iter().enumerate() {
        for rot in [Affine3A::IDENTITY, Affine3A::from_quat(Quat::from_euler(glam::EulerRot::XYZ, 0.3, 0.7, -0.2))] {
            let mut m = MeshBuilder::new();
            m.set_transform(rot);
            make(&mut m);
            let scene = m.build();
            let origin = rot.transform_point3(*inside);
            let tree = KdTree::build(&scene, &KdParams::default()).unwrap();
            let bf = BruteForce::new(&scene);
            let mut s = TraversalStats::default();
            let mut aimed = 0;
            for i in 0..scene.triangle_count() {
                let [a, b, c] = scene.vertices(i);
                for target in [a, b, c, (a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5] {
                    let ray = Ray::new(origin, target - origin);
                    aimed += 1;
                    assert!(bf.intersect(&ray, &mut s).is_some(), "solid {k}: brute force leaked at {target}");
                    assert!(tree.intersect(&ray, &mut s).is_some(), "solid {k}: kd-tree leaked at {target}");
                    assert!(tree.occluded(&ray, &mut s), "solid {k}: occlusion leaked at {target}");
                }
            }
            assert!(aimed >= 72, "{aimed} rays aimed");
        }
    }
}
