//! raylab's CPU tracing core.
//!
//! Data flows one way through the modules: a [`scene::Scene`] is turned into an acceleration structure
//! ([`kdtree::KdTree`]), rays from [`workload`] or the [`render`] tile loop are traced by a traversal kernel
//! ([`kdtree::mono`], or the brute-force [`reference`](mod@reference)), and hits are shaded into a frame buffer. Counters
//! ([`stats::TraversalStats`]) travel with every trace so the CLI and the viewer report the same numbers as the
//! thesis tables (Tsakok 2008, "Fast Ray Tracing Techniques", Tables 4.1-4.6).
//!
//! This crate knows nothing about files, windows or GPUs.

pub mod aabb;
pub mod dacrt;
pub mod distribution;
pub mod edge_width;
pub mod intersector;
pub mod kdtree;
pub mod mbvh;
pub mod method;
pub mod packet;
pub mod ray;
pub mod ray_order;
pub mod reference;
pub mod render;
pub mod scene;
pub mod shadow;
pub mod stats;
pub mod structures;
pub mod trace;
pub mod tri4;
pub mod triangle;
pub mod workload;

pub use glam::Vec3;
