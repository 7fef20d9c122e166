//! `raylab-bench`: raylab's headless command line.
//!
//! With no subcommand it renders the default built-in scene to `raylab.png`.

mod commands;
mod isect_cost;
mod output;
mod timing;

use raylab_cli::{args, env, prepare};

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(name = "raylab-bench", version, about = "raylab's headless renderer and benchmark")]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Render one frame to PNG.
    Render(commands::render::RenderArgs),
    /// Trace the Embree harness's rays with one method and report Mrays/s, checksums and counters.
    Trace(commands::trace::TraceArgs),
    /// Move objects every frame: kd-tree rebuild, MBVH refit and DACRT (no structure), update + trace times.
    Animate(commands::animate::AnimateArgs),
    /// Print a scene's contents and kd-tree statistics.
    Info(commands::info::InfoArgs),
    /// Run the Embree harness and raylab on the same view in one go, and print the comparison table.
    Compare(commands::compare::CompareArgs),
    /// Trace the MBVH RS paper's distribution workload with several methods: Mrays/s per bounce and counters.
    Distribution(commands::distribution::DistributionArgs),
    /// Regenerate the thesis's Tables 4.1-4.5 (FPS, N, I per method and tile) for the built-in scenes.
    Tables(commands::tables::TablesArgs),
}

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        None => commands::render::run(&commands::render::RenderArgs::default_scene()),
        Some(Command::Render(a)) => commands::render::run(a),
        Some(Command::Trace(a)) => commands::trace::run(a),
        Some(Command::Animate(a)) => commands::animate::run(a),
        Some(Command::Info(a)) => commands::info::run(a),
        Some(Command::Compare(a)) => commands::compare::run(a),
        Some(Command::Tables(a)) => commands::tables::run(a),
        Some(Command::Distribution(a)) => commands::distribution::run(a),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(msg) => {
            eprintln!("error: {msg}");
            std::process::ExitCode::from(1)
        }
    }
}
