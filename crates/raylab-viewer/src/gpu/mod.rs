//! The GPU side: the device (`device`), the compositor that draws the traced frame under egui
//! (`compositor`, with `ui_cover` and `ui_fill` for where egui drew), window captures (`capture`), and the
//! hybrid mode's G-buffer passes (`hybrid`).

pub mod capture;
pub mod compositor;
pub mod device;
pub mod hybrid;
pub mod ui_cover;
pub mod ui_fill;
