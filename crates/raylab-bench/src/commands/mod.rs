//! The subcommands.

pub mod animate;
pub mod compare;
pub mod distribution;
mod frame_cells;
pub mod info;
pub mod render;
pub mod shading_tables;
pub mod tables;
pub mod trace;
