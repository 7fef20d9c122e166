//! Scene sources for raylab: the built-in procedural scenes (no files needed) and file loaders.
//!
//! Every source produces a [`raylab_core::scene::Scene`] with at least one view and one light.

pub mod animation;
pub mod builtin;
mod error;
pub mod gltf_model;
pub mod mesh;
pub mod normals;
pub mod obj;
pub mod obj_positions;
pub mod paths;
pub mod sidecar;
mod source;
pub mod texture;

pub use error::SceneError;
pub use mesh::MeshBuilder;
pub use source::{SceneSource, load, load_with_progress};

/// A loaded scene and what the loader had to work around (missing textures, unreadable material libraries,
/// dropped triangles), each warning naming the file.
#[derive(Clone, Debug, Default)]
pub struct Loaded {
    /// The scene.
    pub scene: raylab_core::scene::Scene,
    /// Warnings, for the terminal or the viewer.
    pub warnings: Vec<String>,
}
