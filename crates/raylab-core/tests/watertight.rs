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

/// A ray through the edge two triangles share meets both at the same distance; every method keeps the
/// lower triangle id, as the brute-force reference does, whichever of the two it tests first.
#[test]
fn a_shared_edge_goes_to_the_lower_triangle_id() {
    use raylab_core::method::{Method, Purpose};
    use raylab_core::structures::{StructureParams, Structures};
    use raylab_core::trace::{TraceOptions, Tracer};
    use raylab_simd::Backend;
    let (a, b, c, d) = (Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0), Vec3::ONE);
    for flip in [false, true] {
        let mut m = MeshBuilder::new();
        // Triangle 0 and 1 share the edge b-c; `flip` swaps which of them comes first.
        let (first, second) =
            if flip { ([b, d.with_z(0.0), c], [a, b, c]) } else { ([a, b, c], [b, d.with_z(0.0), c]) };
        m.triangle(first[0], first[1], first[2]);
        m.triangle(second[0], second[1], second[2]);
        let scene = m.build();
        // Every method, the kd-tree ones on the thesis's tree (both slots take its cost model).
        let params = StructureParams { packet_kd: KdParams::default(), ..StructureParams::default() };
        let structures = Structures::build(&scene, &Method::ALL, Purpose::Frames, &params).unwrap();
        let bf = BruteForce::new(&scene);
        let mut s = TraversalStats::default();
        // Down onto the edge's midpoint and two other points of it, in a 2x2 tile of identical rays.
        for p in [Vec3::new(0.5, 0.5, 0.0), Vec3::new(0.25, 0.75, 0.0), Vec3::new(0.875, 0.125, 0.0)] {
            let ray = Ray::new(p + Vec3::Z, Vec3::NEG_Z);
            assert_eq!(bf.hit_distance(&ray, 0), bf.hit_distance(&ray, 1), "flip {flip}: not a tie at {p}");
            assert_eq!(bf.intersect(&ray, &mut s).map(|h| h.tri), Some(0));
            let rays = [Some(ray); 4];
            for method in Method::ALL.into_iter().filter(|&m| m != Method::Reference) {
                for backend in Backend::available() {
                    let options = TraceOptions { method, backend, ..Default::default() };
                    let tracer = Tracer::new(&structures, options).unwrap();
                    let mut hits = [None; 4];
                    tracer.intersect_tile(&rays, 2, 2, &mut hits, &mut s);
                    for h in hits {
                        assert_eq!(h.map(|h| h.tri), Some(0), "flip {flip}, {method} {backend:?} at {p}");
                    }
                }
            }
        }
    }
}
