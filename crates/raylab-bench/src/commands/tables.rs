//! `raylab-bench tables`: the thesis's Tables 4.1-4.5 (Tsakok 2008, chapter 4) regenerated for the built-in
//! scenes (and one OBJ given with `--scene`): frame rate at 512x512 with the simple benchmark shading, N
//! (nodes per 2x2 packet) and I (triangle tests per packet) for 2x2 packets, single frustums, MFT, cones and
//! MFT over cones, the effect of packet/leaf culling, and percentage changes against the single frustum.

use std::fmt::Write as _;
use std::path::PathBuf;

use clap::Args;
use raylab_core::method::{Method, Purpose};
use raylab_core::render::RenderSettings;
use raylab_core::scene::{Camera, PointLight, Scene};
use raylab_core::shadow::Shadows;
use raylab_core::structures::StructureParams;
use raylab_core::trace::{TraceOptions, Tracer};
use raylab_simd::Backend;
use serde_json::json;

use super::frame_cells::{Cell, measure_interleaved, record};
use super::shading_tables::{ShadingRun, Subject};
use crate::args::{KdArgs, SceneArgs, in_range};
use crate::env::Environment;
use crate::output::{markdown_header, print_markdown, write_json};
use crate::prepare::{build_structures, load_scene};

/// Regenerates thesis Tables 4.1-4.5 for the built-in scenes and the scene given with `--scene` (for
/// instance the shared Sponza with its benchmark view).
#[derive(Args, Debug)]
pub struct TablesArgs {
    /// Built-in scenes to measure, each from its default view.
    #[arg(long, value_delimiter = ',', default_value = "arena,kitchen,atrium,forest")]
    builtins: Vec<String>,
    /// One more scene (a built-in name not listed above, or an OBJ path) with the camera and light flags.
    #[command(flatten)]
    view: SceneArgs,
    #[command(flatten)]
    kd: KdArgs,
    /// Image width.
    #[arg(long, default_value_t = 512, value_parser = in_range(16, 4096))]
    width: u64,
    /// Image height.
    #[arg(long, default_value_t = 512, value_parser = in_range(16, 4096))]
    height: u64,
    /// Rendering threads (the thesis used 2 cores).
    #[arg(long, default_value_t = 2, value_parser = in_range(1, 1024))]
    threads: u64,
    /// Timed frames per configuration (the median frame time gives the FPS).
    #[arg(long, default_value_t = 5, value_parser = in_range(1, 1000))]
    reps: u64,
    /// Also write the markdown to this file.
    #[arg(long)]
    markdown: Option<PathBuf>,
    /// Also write the tables as one JSON object to this file: the machine and the run's settings, and one
    /// flat record per measured cell (its table, scene, method, tile and shadow technique beside FPS, N, I,
    /// culled packets and stage times), ready for a data frame.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Which tables: primary (4.1-4.5), shading (5.1, 4.6, 3.1 and image quality) or all.
    #[arg(long, value_enum, default_value_t = Part::All)]
    part: Part,
    /// Built-in scenes of the shading tables (the scene given with --scene is measured too).
    #[arg(long, value_delimiter = ',', default_value = "atrium")]
    shading_builtins: Vec<String>,
    /// Edge of the square image-quality renders (the 1024-sample reference is slow).
    #[arg(long, default_value_t = 256, value_parser = in_range(16, 4096))]
    quality_size: u64,
    /// Write the image-quality renders as PNG into this folder.
    #[arg(long)]
    images: Option<PathBuf>,
    /// SIMD backend of Tables 4.1-4.5 (default: sse2 where there is one, whose 2x2 packets make N and I per
    /// 2x2 packet as in the thesis; avx2 traces 4x2 packets, avx512 4x4).
    #[arg(long, value_parser = crate::args::parse_backend)]
    backend: Option<Backend>,
}

/// A part of the tables.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Part {
    /// Tables 4.1-4.5: primary rays per traversal method and tile.
    Primary,
    /// Tables 5.1, 4.6 and 3.1 and the image-quality table: shadows, reflections and refractions.
    Shading,
    /// Both.
    All,
}

fn pct(a: f64, b: f64) -> String {
    format!("{:+.1}%", 100.0 * (a - b) / b)
}

/// Runs the command.
pub fn run(a: &TablesArgs) -> Result<(), String> {
    let env = Environment::detect();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(a.threads as usize).build().map_err(|e| e.to_string())?;
    // Each scene with whether the primary and the shading tables measure it.
    let mut scenes: Vec<(String, Scene, Camera, PointLight, bool, bool)> = Vec::new();
    let primary = a.part != Part::Shading;
    let shading = a.part != Part::Primary;
    let mut names: Vec<&String> = Vec::new();
    if primary {
        names.extend(&a.builtins);
    }
    if shading {
        names.extend(a.shading_builtins.iter().filter(|n| !names.contains(n)).collect::<Vec<_>>());
    }
    for name in names.iter().copied().filter(|n| **n != a.view.scene) {
        let args = SceneArgs::named(name);
        let (scene, _) = load_scene(&args.source())?;
        let (cam, light) = args.camera_and_light(&scene)?;
        let (p, sh) = (primary && a.builtins.contains(name), shading && a.shading_builtins.contains(name));
        scenes.push((name.clone(), scene, cam, light, p, sh));
    }
    {
        let (scene, _) = load_scene(&a.view.source())?;
        let (cam, light) = a.view.camera_and_light(&scene)?;
        let s = &a.view.scene;
        let name = std::path::Path::new(s).file_stem().map_or(s.clone(), |x| x.to_string_lossy().into_owned());
        scenes.push((name, scene, cam, light, primary, shading));
    }
    let tiles = [4u32, 8, 16, 32];
    let settings = |tile: u32| RenderSettings {
        width: a.width as u32,
        height: a.height as u32,
        tile,
        shadows: Shadows::None,
        max_depth: 0,
        ..Default::default()
    };
    // The thesis's tables: every method walks the thesis's tree (both kd-tree slots take its cost model).
    let params = a.kd.params()?;
    let structure_params = StructureParams { packet_kd: params, ..a.kd.structure_params()? };
    let backend = a.backend.unwrap_or_else(|| {
        let avail = Backend::available();
        avail.iter().copied().find(|&b| b == Backend::Sse).unwrap_or(avail[0])
    });
    // Per scene: packet, frustum[tiles], frustum 8 without culling, mft[tiles], cone[3], mft-cone[3].
    struct Row {
        name: String,
        packet: Cell,
        frustum: Vec<Cell>,
        nocull8: Cell,
        mft: Vec<Cell>,
        cone: Vec<Cell>,
        mft_cone: Vec<Cell>,
    }
    let mut rows = Vec::new();
    for (name, scene, cam, light, ..) in scenes.iter().filter(|s| s.4) {
        let methods = [Method::Packet, Method::Frustum, Method::Mft, Method::Cone, Method::MftCone];
        let structures = build_structures(scene, &methods, Purpose::Frames, &structure_params, a.threads as usize)?;
        let tracer = |method, cull| {
            Tracer::new(&structures, TraceOptions { method, cull, backend, ..Default::default() })
                .map_err(|e| e.to_string())
        };
        eprintln!("measuring {name} ({} triangles)", scene.triangle_count());
        // Every configuration of the scene's row, rendered in turn, round by round (`measure_interleaved`).
        let (packet, unculled) = (tracer(Method::Packet, true)?, tracer(Method::Frustum, false)?);
        let (frustum, mft) = (tracer(Method::Frustum, true)?, tracer(Method::Mft, true)?);
        let (cone, mft_cone) = (tracer(Method::Cone, true)?, tracer(Method::MftCone, true)?);
        let mut configs = vec![(&packet, settings(16)), (&unculled, settings(8))];
        configs.extend(tiles.iter().map(|&t| (&frustum, settings(t))));
        configs.extend(tiles.iter().map(|&t| (&mft, settings(t))));
        configs.extend(tiles[..3].iter().map(|&t| (&cone, settings(t))));
        configs.extend(tiles[..3].iter().map(|&t| (&mft_cone, settings(t))));
        let cells = measure_interleaved(scene, cam, *light, &configs, &pool, a.reps);
        let n = tiles.len();
        rows.push(Row {
            name: name.clone(),
            packet: cells[0],
            nocull8: cells[1],
            frustum: cells[2..2 + n].to_vec(),
            mft: cells[2 + n..2 + 2 * n].to_vec(),
            cone: cells[2 + 2 * n..5 + 2 * n].to_vec(),
            mft_cone: cells[5 + 2 * n..8 + 2 * n].to_vec(),
        });
    }

    let mut records = Vec::new();
    for r in &rows {
        let cell = |table: &str, method: Method, tile: u32, cull: bool, c: &Cell| {
            record(json!({ "table": table, "scene": r.name, "method": method, "tile": tile, "cull": cull }), c)
        };
        records.push(cell("4.1", Method::Packet, 16, true, &r.packet));
        records.extend(r.frustum.iter().zip(tiles).map(|(c, t)| cell("4.1", Method::Frustum, t, true, c)));
        records.push(cell("4.2", Method::Frustum, 8, false, &r.nocull8));
        records.extend(r.mft.iter().zip(tiles).map(|(c, t)| cell("4.3", Method::Mft, t, true, c)));
        records.extend(r.cone.iter().zip(tiles).map(|(c, t)| cell("4.5", Method::Cone, t, true, c)));
        records.extend(r.mft_cone.iter().zip(tiles).map(|(c, t)| cell("4.5", Method::MftCone, t, true, c)));
    }

    let cmd: Vec<String> = std::env::args().collect();
    let mut md = markdown_header(&env, &cmd);
    if primary {
        let _ = writeln!(
            md,
            "\n{}x{}, {} threads, {} backend ({}-ray packets), primary rays with the simple shading (one point \
             light, N.L, attenuation), no shadows, no secondary rays; FPS from the median of {} frames, every \
             configuration of a scene rendered in turn, round by round.",
            a.width,
            a.height,
            a.threads,
            backend.name(),
            backend.lanes(),
            a.reps
        );
        let cells = |c: &Cell| format!("{:.1} | {:.2} | {:.2}", c.fps, c.n, c.i);
        let _ = writeln!(md, "\n**Table 4.1**: 2x2 packets and single frustums (FPS, N, I).\n");
        let _ = write!(md, "| scene | packet 2x2 FPS | N | I |");
        for t in tiles {
            let _ = write!(md, " frustum {t}x{t} FPS | N | I |");
        }
        let _ = writeln!(md, "\n|---|{}", "---:|".repeat(3 + 3 * tiles.len()));
        for r in &rows {
            let _ = write!(md, "| {} | {} |", r.name, cells(&r.packet));
            for c in &r.frustum {
                let _ = write!(md, " {} |", cells(c));
            }
            let _ = writeln!(md);
        }
        let _ = writeln!(md, "\n**Table 4.2**: packet/leaf culling, frustum 8x8.\n");
        let _ =
            writeln!(md, "| scene | FPS with culling | FPS without | frame-rate change | packet/leaf visits culled |");
        let _ = writeln!(md, "|---|---:|---:|---:|---:|");
        for r in &rows {
            let (on, off) = (r.frustum[1], r.nocull8);
            let _ = writeln!(
                md,
                "| {} | {:.1} | {:.1} | {} | {:.1}% |",
                r.name,
                on.fps,
                off.fps,
                pct(on.fps, off.fps),
                on.culled
            );
        }
        let _ =
            writeln!(md, "\n**Table 4.3**: MFT (FPS, N, I and change against the single frustum at the same tile).\n");
        let _ = writeln!(md, "| scene | tile | FPS | N | I | % FPS | % N | % I |");
        let _ = writeln!(md, "|---|---:|---:|---:|---:|---:|---:|---:|");
        for r in &rows {
            for (k, t) in tiles.iter().enumerate() {
                let (m, f) = (r.mft[k], r.frustum[k]);
                let _ = writeln!(
                    md,
                    "| {} | {t}x{t} | {} | {} | {} | {} |",
                    r.name,
                    cells(&m),
                    pct(m.fps, f.fps),
                    pct(m.n, f.n),
                    pct(m.i, f.i)
                );
            }
        }
        let _ = writeln!(md, "\n**Table 4.4**: peak frame rates.\n");
        let _ = writeln!(md, "| scene | MFT FPS | MFT tile | non-MFT FPS | non-MFT method and tile | MFT / non-MFT |");
        let _ = writeln!(md, "|---|---:|---:|---:|---|---:|");
        for r in &rows {
            let (bi, bm) = r.mft.iter().enumerate().max_by(|x, y| x.1.fps.total_cmp(&y.1.fps)).expect("tiles");
            let mut best = (r.packet.fps, "packet 2x2".to_string());
            for (k, f) in r.frustum.iter().enumerate() {
                if f.fps > best.0 {
                    best = (f.fps, format!("frustum {0}x{0}", tiles[k]));
                }
            }
            let _ = writeln!(
                md,
                "| {} | {:.1} | {t}x{t} | {:.1} | {} | {:.2}x |",
                r.name,
                bm.fps,
                best.0,
                best.1,
                bm.fps / best.0,
                t = tiles[bi]
            );
        }
        let _ =
            writeln!(md, "\n**Table 4.5**: cones (single cone and MFT over four cones) against the single frustum.\n");
        let _ = writeln!(md, "| scene | method | tile | FPS | N | I | % FPS | % N | % I |");
        let _ = writeln!(md, "|---|---|---:|---:|---:|---:|---:|---:|---:|");
        for r in &rows {
            for (label, v) in [("cone", &r.cone), ("MFT cone", &r.mft_cone)] {
                for (k, c) in v.iter().enumerate() {
                    let f = r.frustum[k];
                    let t = tiles[k];
                    let _ = writeln!(
                        md,
                        "| {} | {label} | {t}x{t} | {} | {} | {} | {} |",
                        r.name,
                        cells(c),
                        pct(c.fps, f.fps),
                        pct(c.n, f.n),
                        pct(c.i, f.i)
                    );
                }
            }
        }
    }
    if shading {
        let _ = writeln!(md, "\n### Shadows, reflections and refractions (thesis Tables 5.1, 4.6, 3.1)");
        let run = ShadingRun {
            size: (a.width as u32, a.height as u32),
            quality_size: (a.quality_size as u32, a.quality_size as u32),
            reps: a.reps,
            pool: &pool,
            images: a.images.as_deref(),
            tile: 16,
        };
        let mut built = Vec::new();
        for (name, scene, ..) in scenes.iter().filter(|s| s.5) {
            eprintln!("measuring shading on {name} ({} triangles)", scene.triangle_count());
            built.push(build_structures(
                scene,
                &[Method::Mft],
                Purpose::Frames,
                &structure_params,
                a.threads as usize,
            )?);
        }
        let subjects: Vec<Subject> = scenes
            .iter()
            .filter(|s| s.5)
            .zip(&built)
            .map(|((name, scene, camera, light, ..), structures)| Subject {
                name,
                scene,
                structures,
                camera: *camera,
                light: *light,
            })
            .collect();
        run.write(&subjects, &mut md, &mut records)?;
    }
    print_markdown(&md, a.markdown.as_deref())?;
    if let Some(p) = &a.json {
        let v = json!({
            "width": a.width,
            "height": a.height,
            "threads": a.threads,
            "reps": a.reps,
            "backend": backend.name(),
            "kd_params": params,
            "records": records,
        });
        write_json(p, &env, &cmd, v)?;
    }
    Ok(())
}
