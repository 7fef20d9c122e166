//! The camera: the fly camera (`fly`), the render scale while flying (`fly_scale`), and recorded camera
//! paths (`paths`).

pub mod fly;
pub mod fly_scale;
pub mod paths;
