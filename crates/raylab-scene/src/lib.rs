//! Scene sources for raylab: the built-in procedural scenes (no files needed) and file loaders.
//!
//! Every source produces a [`raylab_core::scene::Scene`] with at least one view and one light.

pub mod builtin;
mod error;
pub mod mesh;
pub mod obj_positions;
mod source;

pub use error::SceneError;
pub use mesh::MeshBuilder;
pub use source::{SceneSource, load};
