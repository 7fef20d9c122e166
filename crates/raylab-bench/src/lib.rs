//! The headless pieces that `raylab-bench` and the viewer share: the scene, camera, kd-tree and method flags,
//! the scene preparation (load and tree build), and the description of the machine a measurement ran on.

pub mod args;
pub mod env;
pub mod prepare;
pub mod still;
