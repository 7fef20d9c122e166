//! The viewer's command line: the scene, camera and method flags of `raylab-bench`, the window, and the
//! automation flags that render a fixed number of frames, save a screenshot and exit.

use std::path::PathBuf;

use clap::{Parser, ValueEnum};
use raylab_cli::args::{KdArgs, MethodArgs, SceneArgs, ShadeArgs, in_range, parse_non_negative, parse_positive};
use raylab_core::ray_order::RayOrder;
use raylab_core::render::FrameView;

use crate::settings::RenderMode;

/// raylab: fly through a scene traced on the CPU, switch traversal methods live and read what they cost.
#[derive(Parser, Debug)]
///
/// The viewer starts with MFT, the fastest method on the built-in views, where `raylab-bench` defaults to mono,
/// the baseline the thesis measures every other method against.
#[command(name = "raylab", version, about)]
#[command(mut_arg("method", |a| a.default_value("mft")))]
pub struct Cli {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub kd: KdArgs,
    #[command(flatten)]
    pub method: MethodArgs,
    #[command(flatten)]
    pub shade: ShadeArgs,
    /// Render mode: whitted, distribution (glossy paths, soft shadows, depth of field, refined over frames), or
    /// hybrid (GPU G-buffer, CPU-traced reflections, GPU composite).
    #[arg(long, value_enum, default_value_t = RenderMode::Whitted)]
    pub mode: RenderMode,
    /// Distribution mode: bounces after the primary hit.
    #[arg(long, default_value_t = 3, value_parser = in_range(1, 7))]
    pub bounces: u64,
    /// Distribution mode: paths per pixel added each frame.
    #[arg(long, default_value_t = 4, value_parser = in_range(1, 256))]
    pub paths_per_pass: u64,
    /// Hybrid mode: G-buffer resolution in percent of the render resolution (25, 50 or 100).
    #[arg(long, default_value_t = 50, value_parser = one_of(&[25, 50, 100]))]
    pub gbuffer_percent: u64,
    /// Hybrid mode: trace every row of reflections each frame (1), or every second (2) or fourth (4) in turn.
    #[arg(long, default_value_t = 1, value_parser = one_of(&[1, 2, 4]))]
    pub interlace: u64,
    /// Hybrid mode: wait for each frame's G-buffer instead of reading it back asynchronously.
    #[arg(long)]
    pub sync_readback: bool,
    /// Hybrid mode: the method that traces the reflection rays.
    #[arg(long, default_value = "dacrt")]
    pub hybrid_method: raylab_core::method::Method,
    /// Move a spinning mirror and a bouncing ball every frame (the kd-tree is rebuilt, the MBVH refitted,
    /// DACRT set up again; the panel shows what each update costs).
    #[arg(long)]
    pub animate: bool,
    /// Distribution mode: lens radius of the camera (0: pinhole).
    #[arg(long, default_value_t = 0.0, value_parser = parse_non_negative, allow_hyphen_values = true)]
    pub aperture: f32,
    /// Pixel order inside a tile (single-ray methods): scanline, morton or hilbert.
    #[arg(long, default_value = "scanline")]
    pub order: RayOrder,
    /// What the traced image shows: shaded, nodes, isects, normals or depth.
    #[arg(long, default_value = "shaded")]
    pub show: FrameView,
    /// Count at the hot end of the heat maps (default: each frame's maximum).
    #[arg(long, value_parser = parse_positive)]
    pub heat_max: Option<f32>,
    /// Render resolution in percent of the window, 25 to 100.
    #[arg(long, default_value_t = 100, value_parser = in_range(25, 100))]
    pub scale: u64,
    /// Keep the render scale while the camera flies (by default frames traced while flying drop to the scale
    /// that takes about 1/30 s, and the chosen scale returns once the camera is still).
    #[arg(long)]
    pub no_fly_scale: bool,
    /// Tracer threads (default: all CPUs).
    #[arg(long, value_parser = in_range(1, 1024))]
    pub threads: Option<u64>,
    /// Window (or offscreen image) width in pixels.
    #[arg(long, default_value_t = 1280, value_parser = in_range(16, 8192))]
    pub width: u64,
    /// Window (or offscreen image) height in pixels.
    #[arg(long, default_value_t = 720, value_parser = in_range(16, 8192))]
    pub height: u64,
    /// Redraw the UI as often as it can (up to 60 FPS) instead of only on input and new frames: measures how
    /// responsive the UI stays while the tracer runs.
    #[arg(long)]
    pub redraw_always: bool,
    /// Start with the side panel hidden (Tab toggles it).
    #[arg(long)]
    pub no_panel: bool,
    /// Play this camera path (JSON, as saved by the viewer) from the start.
    #[arg(long)]
    pub play: Option<PathBuf>,
    /// Render this many traced frames, then exit (0 when all went well).
    #[arg(long, value_parser = in_range(1, 100_000))]
    pub frames: Option<u64>,
    /// With --frames: save the whole window (panel included) as PNG before exiting.
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// With --frames: save the last traced frame alone as PNG before exiting.
    #[arg(long)]
    pub traced_screenshot: Option<PathBuf>,
    /// With --frames: write the readouts (frame times, counters, stage times, panel rectangle) as JSON.
    #[arg(long)]
    pub json_stats: Option<PathBuf>,
    /// Render offscreen, without a window system (needs --frames).
    #[arg(long)]
    pub headless: bool,
}

impl Cli {
    /// Checks the combinations clap cannot; the error names the flags.
    pub fn validate(&self) -> Result<(), String> {
        if self.frames.is_none() {
            for (given, flag) in [
                (self.screenshot.is_some(), "--screenshot"),
                (self.traced_screenshot.is_some(), "--traced-screenshot"),
                (self.json_stats.is_some(), "--json-stats"),
                (self.headless, "--headless"),
            ] {
                if given {
                    return Err(format!("{flag} needs --frames N (how many traced frames to render first)"));
                }
            }
        }
        if self.hybrid_method == raylab_core::method::Method::Reference {
            return Err("--hybrid-method reference: brute force is for tests, far too slow to fly with".into());
        }
        Ok(())
    }

    /// Tracer threads: the flag or every CPU.
    pub fn thread_count(&self) -> usize {
        self.threads.map_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()), |t| t as usize)
    }
}

/// `ValueEnum` names for the menus and the command line are the same strings.
pub fn value_name<T: ValueEnum>(v: &T) -> String {
    v.to_possible_value().map(|p| p.get_name().to_string()).unwrap_or_default()
}

/// A parser accepting only the listed values; the error lists them.
fn one_of(allowed: &'static [u64]) -> impl Fn(&str) -> Result<u64, String> + Clone {
    move |s| {
        let v: u64 = s.trim().parse().map_err(|_| format!("'{s}' is not a whole number"))?;
        if allowed.contains(&v) {
            Ok(v)
        } else {
            let list: Vec<String> = allowed.iter().map(u64::to_string).collect();
            Err(format!("{v} is not one of {}", list.join(", ")))
        }
    }
}

#[cfg(test)]
mod tests {
    use clap::Parser;
    use raylab_core::method::Method;

    use super::Cli;

    #[test]
    fn the_viewer_starts_with_mft_and_takes_any_method() {
        let parse = |args: &[&str]| Cli::try_parse_from(std::iter::once("raylab").chain(args.iter().copied()));
        assert_eq!(parse(&[]).expect("no flags").method.method, Method::Mft);
        assert_eq!(parse(&["--method", "mono"]).expect("--method mono").method.method, Method::Mono);
    }
}
