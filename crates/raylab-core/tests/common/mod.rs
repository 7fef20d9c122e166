//! Shared test helpers: adversarial ray sets and the comparison of a method against brute force.

#![allow(dead_code)]

use glam::{Affine3A, Vec3};
use raylab_core::dacrt::{Dacrt, DacrtParams};
use raylab_core::intersector::Intersector;
use raylab_core::kdtree::KdTree;
use raylab_core::mbvh::Mbvh;
use raylab_core::method::{Method, Purpose};
use raylab_core::ray::{Hit, Ray};
use raylab_core::reference::BruteForce;
use raylab_core::scene::Scene;
use raylab_core::stats::TraversalStats;
use raylab_core::structures::{StructureParams, Structures};
use raylab_scene::MeshBuilder;
use raylab_scene::mesh::Jitter;
use raylab_simd::Backend;

/// A structure's own single-ray queries, in the lanes of one SIMD backend.
pub struct Lanes<'a, S>(pub &'a S, pub Backend);

impl Intersector for Lanes<'_, Mbvh> {
    fn intersect(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<Hit> {
        self.0.intersect(ray, self.1, stats)
    }
    fn occluded(&self, ray: &Ray, stats: &mut TraversalStats) -> bool {
        self.0.occluded(ray, self.1, stats)
    }
}

/// One ray as a set of one, with the default parameters.
impl Intersector for Lanes<'_, Dacrt> {
    fn intersect(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<Hit> {
        let mut out = [None];
        self.0.intersect(&DacrtParams::default(), self.1, &[Some(*ray)], &mut out, stats);
        out[0]
    }
    fn occluded(&self, ray: &Ray, stats: &mut TraversalStats) -> bool {
        let mut out = [false];
        self.0.occluded(&DacrtParams::default(), self.1, &[Some(*ray)], &mut out, stats);
        out[0]
    }
}

/// The structures `methods` need for frames, with the default parameters.
/// The six axis directions, both signs: rays with two zero direction components.
pub const AXES: [Vec3; 6] = [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z];

pub fn structures(scene: &Scene, methods: &[Method]) -> Structures {
    Structures::build(scene, methods, Purpose::Frames, &StructureParams::default()).unwrap()
}

/// Asserts that `method` returns the same closest hit (triangle and t, bit for bit) and the same occlusion
/// as brute force for every ray. Where two triangles are hit at the same distance (a shared edge, coincident
/// faces) the lower id must win, as in the reference.
pub fn check_hits(scene: &Scene, method: &dyn Intersector, rays: &[Ray], what: &str) {
    let reference = BruteForce::new(scene);
    let mut s = TraversalStats::default();
    for (i, ray) in rays.iter().enumerate() {
        let want = reference.intersect(ray, &mut s);
        let got = method.intersect(ray, &mut s);
        match (got, want) {
            (None, None) => {}
            (Some(g), Some(w)) => {
                assert!(g.tri == w.tri && g.t == w.t, "{what}: ray {i} {ray:?}: got {g:?}, reference {w:?}");
            }
            _ => panic!("{what}: ray {i} {ray:?}: got {got:?}, reference {want:?}"),
        }
        let occ_want = reference.occluded(ray, &mut s);
        let occ_got = method.occluded(ray, &mut s);
        assert_eq!(occ_got, occ_want, "{what}: occlusion of ray {i} {ray:?}");
    }
}

/// A mixed set of adversarial rays for `scene`: random origins and directions; directions with one and two
/// zero components (of both signs); rays aimed exactly at vertices and edge midpoints; rays running inside
/// split planes of `tree`; rays grazing along triangle planes; segments with tmin > 0 and finite tmax.
pub fn adversarial_rays(scene: &Scene, tree: &KdTree, n: usize, seed: u32) -> Vec<Ray> {
    let mut rng = Jitter::new(seed);
    let b = scene.bounds();
    let pad = b.extent() * 0.2;
    let (lo, hi) = (b.min - pad, b.max + pad);
    let point = |rng: &mut Jitter| Vec3::new(rng.range(lo.x, hi.x), rng.range(lo.y, hi.y), rng.range(lo.z, hi.z));
    let mut rays = Vec::new();
    let signed_zeros = [
        Vec3::new(1.0, -0.0, 0.0),
        Vec3::new(-0.0, 0.0, -1.0),
        Vec3::new(0.0, 0.7, -0.7),
        Vec3::new(-0.6, 0.0, 0.8),
        Vec3::new(0.5, -0.5, -0.0),
    ];
    let axis_dirs: Vec<Vec3> = AXES.into_iter().chain(signed_zeros).collect();
    for k in 0..n {
        let o = point(&mut rng);
        let random_dir = Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
        rays.push(Ray::new(o, random_dir));
        rays.push(Ray::new(o, axis_dirs[k % axis_dirs.len()]));
        if scene.triangle_count() > 0 {
            let t = (rng.unit() * scene.triangle_count() as f32) as usize % scene.triangle_count();
            let [a, bb, c] = scene.vertices(t);
            let targets = [a, bb, c, (a + bb) * 0.5, (bb + c) * 0.5, (a + c) / 3.0 + bb / 3.0 + c / 3.0];
            let target = targets[k % targets.len()];
            rays.push(Ray::new(o, target - o));
            // Grazing: start on the triangle's plane and run along it toward an edge and past a vertex.
            rays.push(Ray::new(a, bb - a));
            rays.push(Ray::new((a + c) * 0.5 - (bb - a), bb - a));
            // A segment with tmin > 0 and a finite tmax around the target.
            let d = target - o;
            rays.push(Ray::segment(o, d, 0.5, 1.0));
            rays.push(Ray::segment(o, d, 0.999, 1.001));
        }
    }
    // Rays inside split planes with a zero direction component on the split axis.
    let mut splits = Vec::new();
    tree.visit(|_, _, node| {
        if !node.is_leaf() && splits.len() < n {
            splits.push((node.axis(), node.split()));
        }
    });
    for (k, (axis, split)) in splits.into_iter().enumerate() {
        let mut o = point(&mut rng);
        o[axis] = split;
        let mut d = Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
        d[axis] = if k % 2 == 0 { 0.0 } else { -0.0 };
        rays.push(Ray::new(o, d));
    }
    rays
}

/// Random incoherent segments: origins anywhere in (and around) the scene, random directions, some with
/// tmin > 0 and a finite tmax.
pub fn incoherent(scene: &Scene, n: usize, seed: u32) -> Vec<Ray> {
    let mut rng = Jitter::new(seed);
    let b = scene.bounds();
    let pad = b.extent() * 0.1;
    let (lo, hi) = (b.min - pad, b.max + pad);
    (0..n)
        .map(|k| {
            let o = Vec3::new(rng.range(lo.x, hi.x), rng.range(lo.y, hi.y), rng.range(lo.z, hi.z));
            let d = Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
            match k % 3 {
                0 => Ray::new(o, d),
                1 => Ray::segment(o, d, rng.range(0.0, 0.5), rng.range(0.5, 8.0)),
                _ => Ray::segment(o, d, 0.0, b.diagonal() * rng.unit()),
            }
        })
        .collect()
}

/// A box beside a sphere at extreme scales and offsets (10^4 and 10^-4 units, 10^5 from the origin, tiny
/// and off-centre), each named by its scale.
pub fn scaled_scenes() -> Vec<(String, Scene)> {
    [(1e4f32, Vec3::ZERO), (1e-4, Vec3::ZERO), (1.0, Vec3::splat(1e5)), (1e-3, Vec3::splat(-50.0))]
        .into_iter()
        .map(|(scale, offset)| {
            let mut mb = MeshBuilder::new();
            mb.set_transform(Affine3A::from_translation(offset) * Affine3A::from_scale(Vec3::splat(scale)));
            mb.cuboid(Vec3::splat(-1.0), Vec3::ONE);
            mb.sphere(Vec3::new(3.0, 0.0, 0.0), 1.0, 8, 12);
            (format!("scale {scale}"), mb.build())
        })
        .collect()
}
