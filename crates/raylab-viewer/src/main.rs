//! `raylab`: the interactive viewer. The CPU tracer of `raylab-core` renders frames on a background pool;
//! the latest is uploaded to the GPU and drawn under egui panels that switch every technique live.
//!
//! With `--frames N` it renders N traced frames, writes the requested screenshots and readouts, and exits;
//! `--headless` does the same offscreen when there is no window system.

mod animated;
mod app;
mod camera;
mod cli;
mod cpu_clock;
mod frontend;
mod gpu;
mod headless;
mod lab;
mod loader;
mod settings;
mod tracer;

use std::process::ExitCode;
use std::sync::Arc;

use clap::Parser;
use raylab_cli::prepare::with_spinner;

use crate::camera::paths::CameraPath;
use crate::cli::Cli;
use crate::frontend::Automation;
use crate::lab::Lab;
use crate::settings::ViewerSettings;

fn main() -> ExitCode {
    match run(&Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(msg) => {
            eprintln!("error: {msg}");
            ExitCode::from(1)
        }
    }
}

fn run(cli: &Cli) -> Result<(), String> {
    cli.validate()?;
    // Two kd-trees when their cost models differ (`StructureParams`): each method walks its own.
    let kd = cli.kd.structure_params()?;
    let scene =
        with_spinner("loading scene and building its structures", || loader::load_now(&cli.scene, &kd, &|_| {}))?;
    let settings = ViewerSettings {
        mode: cli.mode,
        trace: cli.method.options(),
        tile: cli.method.tile as u32,
        shadows: cli.shade.shadows(&scene.light),
        depth: cli.shade.depth as u32,
        distribution: crate::settings::DistributionControls {
            bounces: cli.bounces as u32,
            paths_per_pass: cli.paths_per_pass as u32,
            aperture: cli.aperture,
            ..Default::default()
        },
        hybrid: crate::settings::HybridControls {
            gbuffer_percent: cli.gbuffer_percent as u32,
            interlace: cli.interlace as u32,
            async_readback: !cli.sync_readback,
            method: cli.hybrid_method,
        },
        order: cli.order,
        show: cli.show,
        heat_max: cli.heat_max,
        scale: cli.scale as u32,
        fly_scale: !cli.no_fly_scale,
        threads: cli.thread_count(),
        continuous: true,
        animate: cli.animate,
    };
    if let Some(why) = settings.trace.method.entry().not_live {
        return Err(format!("--method {}: {why}", settings.trace.method));
    }
    settings.shadows.validate().map_err(|e| format!("--shadows: {e}"))?;
    let path = cli.play.as_deref().map(CameraPath::load).transpose()?;
    let no_panel = cli.no_panel;
    let make_lab = move |wake: Arc<dyn Fn() + Send + Sync>| {
        let mut lab = Lab::new(scene, kd, settings, wake);
        lab.panel_visible = !no_panel;
        if let Some(p) = path {
            lab.play(p, false);
        }
        lab
    };
    let size = (cli.width as u32, cli.height as u32);
    let automation = cli.frames.map(|frames| Automation {
        frames,
        screenshot: cli.screenshot.clone(),
        traced_screenshot: cli.traced_screenshot.clone(),
        json_stats: cli.json_stats.clone(),
    });
    if cli.headless {
        let a = automation.ok_or("--headless needs --frames N")?;
        headless::run(make_lab, size, a)
    } else {
        app::run(make_lab, size, automation, cli.redraw_always)
    }
}
