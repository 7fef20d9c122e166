//! The subcommands.

pub mod compare;
pub mod info;
pub mod render;
pub mod tables;
pub mod trace;
