//! What `raylab-bench` and the viewer (`raylab`) share, so that their flags mean the same: the scene, camera,
//! kd-tree, method and shading flags (`args`), loading a scene and building its structures (`prepare`), the
//! description of the machine a measurement ran on (`env`), and rendering one still frame (`still`).

pub mod args;
pub mod env;
pub mod prepare;
pub mod still;
