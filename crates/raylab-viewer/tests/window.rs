//! The viewer in a real window (under Xvfb when no display is set) and offscreen: for every interactive
//! traversal method and shadow technique, the traced region of a window screenshot must equal the image
//! `raylab-bench render` makes of the same view and settings, texel for pixel, and the panel must be drawn.
//!
//! Needs a Vulkan or GL driver (Mesa's lavapipe will do: `mesa-vulkan-drivers libvulkan1`) and, without a
//! display, `xvfb-run` (`xvfb xauth`). A missing piece fails the test with a message naming it.

use std::path::Path;
use std::process::Command;

use raylab_cli::args::SceneArgs;
use raylab_cli::still::render_still;
use raylab_core::method::{Method, Purpose};
use raylab_core::ray_order::RayOrder;
use raylab_core::render::{FrameView, RenderSettings};
use raylab_core::scene::PointLight;
use raylab_core::shadow::{SampleBound, ShadowKind};
use raylab_core::structures::{StructureParams, Structures};
use raylab_core::trace::TraceOptions;

const W: u32 = 720;
const H: u32 = 400;
const TILE: u32 = 8;
/// Drop shadows of egui popups and panel edges reach this far beyond their rectangles.
const SHADOW_MARGIN: f32 = 24.0;

const METHODS: [Method; 6] =
    [Method::Mono, Method::Packet, Method::Frustum, Method::Mft, Method::Cone, Method::MftCone];

fn has_display() -> bool {
    ["DISPLAY", "WAYLAND_DISPLAY"].iter().any(|v| std::env::var_os(v).is_some_and(|s| !s.is_empty()))
}

/// The viewer, wrapped in `xvfb-run` when there is no display (or always offscreen with `headless`).
fn viewer(headless: bool, runtime: &Path) -> Command {
    let exe = env!("CARGO_BIN_EXE_raylab");
    let mut c = if headless || has_display() {
        Command::new(exe)
    } else {
        let mut c = Command::new("xvfb-run");
        c.args(["-a", "-s", "-screen 0 1024x768x24", exe]);
        c
    };
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        c.env("XDG_RUNTIME_DIR", runtime);
    }
    if headless {
        c.arg("--headless");
    }
    c
}

/// Runs the viewer for two traced frames and returns the window screenshot and the stats file.
fn run_viewer(dir: &Path, name: &str, headless: bool, args: &[&str]) -> (image::RgbaImage, serde_json::Value) {
    let shot = dir.join(format!("{name}.png"));
    let stats = dir.join(format!("{name}.json"));
    let out = viewer(headless, dir)
        .args(["--scene", "atrium", "--width", &W.to_string(), "--height", &H.to_string()])
        .args(["--tile", &TILE.to_string(), "--threads", "2", "--frames", "2"])
        .args(args)
        .arg("--screenshot")
        .arg(&shot)
        .arg("--json-stats")
        .arg(&stats)
        .output()
        .unwrap_or_else(|e| {
            panic!("cannot start the viewer ({e}); without a display it needs xvfb-run: apt-get install xvfb xauth")
        });
    assert!(
        out.status.success(),
        "{name}: the viewer failed ({}):\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    let img = image::open(&shot).unwrap_or_else(|e| panic!("{name}: no screenshot: {e}")).to_rgba8();
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(&stats).unwrap()).unwrap();
    (img, json)
}

/// The `raylab-bench render` image of the same view, on the kd-tree that `method` walks in both (heat maps
/// of nodes and tests depend on the tree).
fn reference(method: Method, shadows: ShadowKind, show: FrameView) -> image::RgbaImage {
    let settings = |light: &PointLight| RenderSettings {
        width: W,
        height: H,
        tile: TILE,
        order: RayOrder::Scanline,
        shadows: shadows.with(light.radius, false, SampleBound::default()),
        max_depth: RenderSettings::DEFAULT_DEPTH,
        view: show,
        heat_max: None,
    };
    let options = TraceOptions { method, ..TraceOptions::default() };
    render_still(&SceneArgs::named("atrium"), &StructureParams::default(), options, settings, 2, 1)
        .unwrap()
        .image()
        .unwrap()
}

fn rect(v: &serde_json::Value) -> [f32; 4] {
    let a = v.as_array().expect("a rectangle");
    [0, 1, 2, 3].map(|i| a[i].as_f64().unwrap() as f32)
}

/// Checks the screenshot against the reference outside the UI's rectangles and that the panel is drawn.
fn check(name: &str, shot: &image::RgbaImage, stats: &serde_json::Value, want: &image::RgbaImage) {
    assert_eq!(shot.dimensions(), (W, H), "{name}: window size");
    assert_eq!(stats["render"], serde_json::json!([W, H]), "{name}: render resolution");
    assert!(stats["environment"]["cpus"].as_u64().is_some_and(|n| n > 0), "{name}: the machine is named");
    let covered: Vec<[f32; 4]> = stats["ui_rects"].as_array().unwrap().iter().map(rect).collect();
    let inside = |x: u32, y: u32, r: &[f32; 4], m: f32| {
        let (x, y) = (x as f32 + 0.5, y as f32 + 0.5);
        x >= r[0] - m && x < r[2] + m && y >= r[1] - m && y < r[3] + m
    };
    let (mut compared, mut differ) = (0usize, Vec::new());
    for (x, y, p) in shot.enumerate_pixels() {
        if covered.iter().any(|r| inside(x, y, r, SHADOW_MARGIN)) {
            continue;
        }
        compared += 1;
        if p != want.get_pixel(x, y) {
            differ.push((x, y, *p, *want.get_pixel(x, y)));
        }
    }
    assert!(compared > (W * H / 4) as usize, "{name}: only {compared} traced pixels visible");
    assert!(
        differ.is_empty(),
        "{name}: {} of {compared} traced pixels differ, first {:?}",
        differ.len(),
        &differ[..3.min(differ.len())]
    );

    let panel = rect(&stats["panel_rect"]);
    assert!(panel[2] - panel[0] > 100.0, "{name}: the panel is too narrow: {panel:?}");
    let (mut in_panel, mut changed) = (0usize, 0usize);
    for (x, y, p) in shot.enumerate_pixels() {
        if inside(x, y, &panel, 0.0) {
            in_panel += 1;
            changed += usize::from(p != want.get_pixel(x, y));
        }
    }
    assert!(changed * 10 > in_panel * 9, "{name}: the panel area looks like the traced image ({changed}/{in_panel})");
}

#[test]
fn window_shows_the_traced_frame_unchanged_for_every_method_and_shadow_technique() {
    let dir = tempfile::tempdir().unwrap();
    for method in METHODS {
        for flag in ["none", "hard"] {
            let name = format!("{method}-{flag}");
            let (shot, stats) = run_viewer(dir.path(), &name, false, &["--method", method.name(), "--shadows", flag]);
            check(&name, &shot, &stats, &reference(method, flag.parse().unwrap(), FrameView::Shaded));
        }
    }
    // The soft techniques, each with one method (the method changes no pixels; tests/shadows.rs in
    // raylab-scene proves that for every pair).
    // The MBVH methods, which the viewer builds an MBVH for, and DACRT, which it prepares a triangle copy for,
    // ride along here.
    for (method, flag) in [
        (Method::Packet, "cached"),
        (Method::Mft, "edge"),
        (Method::Mono, "ms4"),
        (Method::Mbvh, "hard"),
        (Method::MbvhRs, "hard"),
        (Method::Dacrt, "cached"),
    ] {
        let name = format!("{method}-{flag}");
        let (shot, stats) = run_viewer(dir.path(), &name, false, &["--method", method.name(), "--shadows", flag]);
        check(&name, &shot, &stats, &reference(method, flag.parse().unwrap(), FrameView::Shaded));
    }
}

#[test]
fn heat_maps_and_offscreen_runs_match_the_cli() {
    let dir = tempfile::tempdir().unwrap();
    for (method, show) in
        [(Method::Mft, FrameView::Nodes), (Method::Mono, FrameView::Isects), (Method::Cone, FrameView::Depth)]
    {
        let name = format!("headless-{method}-{show}");
        let (shot, stats) = run_viewer(dir.path(), &name, true, &["--method", method.name(), "--show", show.name()]);
        check(&name, &shot, &stats, &reference(method, ShadowKind::Hard, show));
    }
    let (shot, stats) = run_viewer(dir.path(), "window-normals", false, &["--method", "packet", "--show", "normals"]);
    check("window-normals", &shot, &stats, &reference(Method::Packet, ShadowKind::Hard, FrameView::Normals));
}

/// Distribution mode refines one image over frames: the window shows exactly the mean of the passes the core
/// tracer makes for that view, as many as the stats file says were accumulated.
#[test]
fn distribution_mode_shows_the_accumulated_passes() {
    use raylab_core::distribution::{Accumulator, DistributionSettings, render_pass};
    use raylab_core::trace::Tracer;

    let dir = tempfile::tempdir().unwrap();
    let args = ["--mode", "distribution", "--bounces", "1", "--paths-per-pass", "2"];
    let (shot, stats) = run_viewer(dir.path(), "distribution", true, &args);
    let paths = stats["paths"].as_u64().expect("paths in the stats file") as u32;
    assert!(paths >= 2 && paths.is_multiple_of(2), "{paths}");
    let scene_args = SceneArgs::named("atrium");
    let scene = raylab_scene::load(&scene_args.source()).unwrap().scene;
    let (camera, light) = scene_args.camera_and_light(&scene).unwrap();
    let structures = Structures::build(&scene, &[Method::Mono], Purpose::Rays, &StructureParams::default()).unwrap();
    let tracer = Tracer::for_rays(&structures, TraceOptions::default()).unwrap();
    let settings = DistributionSettings {
        width: W,
        height: H,
        tile: TILE,
        spp: 2,
        bounces: 1,
        glossy_exponent: 64.0,
        all_glossy: false,
    };
    let mut acc = Accumulator::new(W, H);
    for pass in 0..paths / 2 {
        render_pass(&scene, &tracer, &camera, light, &settings, pass, &mut acc);
    }
    let want = image::RgbaImage::from_raw(W, H, acc.rgba().as_flattened().to_vec()).unwrap();
    check("distribution", &shot, &stats, &want);
}

/// The animation switch: objects move between frames, and each method updates only its own structure (the
/// kd-tree methods rebuild, the MBVH methods refit, DACRT copies triangles), in both render modes.
#[test]
fn animation_moves_objects_and_updates_the_structure_each_method_needs() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&str, &[&str], [bool; 3]); 4] = [
        ("anim-mono", &["--method", "mono"], [true, false, false]),
        ("anim-mbvh", &["--method", "mbvh", "--shadows", "cached"], [false, true, false]),
        ("anim-dacrt", &["--method", "dacrt"], [false, false, true]),
        ("anim-dist-dacrt", &["--method", "dacrt", "--mode", "distribution"], [false, false, true]),
    ];
    for (name, args, [kd, refit, dacrt]) in cases {
        let mut all = vec!["--animate"];
        all.extend_from_slice(args);
        let (shot, stats) = run_viewer(dir.path(), name, true, &all);
        let a = &stats["animation"];
        assert!(a["moving_triangles"].as_u64().unwrap() > 100, "{name}: {a}");
        assert!(a["time_s"].as_f64().unwrap() > 0.0, "{name}: {a}");
        assert_eq!(a["kd_rebuild_ms"].is_number(), kd, "{name}: {a}");
        assert_eq!(a["mbvh_refit_ms"].is_number(), refit, "{name}: {a}");
        assert_eq!(a["dacrt_setup_ms"].is_number(), dacrt, "{name}: {a}");
        assert_eq!(stats["settings"]["animate"], true);
        assert!(shot.pixels().any(|p| p.0[0] > 40), "{name}: the frame is not black");
    }
    // Without the switch there is nothing to report.
    let (_, stats) = run_viewer(dir.path(), "still", true, &["--method", "dacrt"]);
    assert!(stats["animation"].is_null());
}

/// The hybrid mode end to end, offscreen under the GPU driver (lavapipe in CI): the R-buffer the viewer
/// shows (its traced frame) holds the CPU Whitted renderer's first reflections, within 35 dB over the
/// reflective pixels, with synchronous and asynchronous readback and with the animation on (the scene posed at
/// the frame's time); interlacing traces a share of the rows; the composite is drawn.
/// PSNR of the R-buffer screenshot at `path` (display values, gamma 2.2) against the CPU renderer's
/// reflections `want` (linear, `None` where a pixel reflects nothing).
fn rbuffer_psnr(path: &Path, want: &[Option<glam::Vec3>]) -> f64 {
    let r = image::open(path).unwrap().to_rgba8();
    assert_eq!(r.dimensions(), (W, H));
    let to_lin = |v: u8| (v as f32 / 255.0).powf(2.2);
    let pairs = r
        .pixels()
        .zip(want)
        .filter_map(|(p, w)| w.map(|w| (glam::Vec3::new(to_lin(p.0[0]), to_lin(p.0[1]), to_lin(p.0[2])), w)));
    raylab_core::render::hybrid::psnr(pairs).unwrap()
}

#[test]
fn hybrid_mode_reflections_match_the_cpu_renderer() {
    use raylab_core::render::hybrid::reference_reflections;
    use raylab_core::trace::Tracer;
    let dir = tempfile::tempdir().unwrap();
    let args = SceneArgs::named("atrium");
    let (scene, _) = raylab_cli::prepare::load_scene(&args.source()).unwrap();
    let (camera, light) = args.camera_and_light(&scene).unwrap();
    let structures = Structures::build(&scene, &[Method::Mono], Purpose::Frames, &StructureParams::default()).unwrap();
    let tracer = Tracer::new(&structures, TraceOptions::default()).unwrap();
    let settings = RenderSettings { width: W, height: H, tile: TILE, ..RenderSettings::default() };
    let want = reference_reflections(&scene, &tracer, &camera, light, &settings);
    let reflective = want.iter().filter(|c| c.is_some()).count();
    assert!(reflective > 500, "{reflective} reflective pixels in the view");
    for (name, extra) in [("hybrid-sync", &["--sync-readback"][..]), ("hybrid-async", &[][..])] {
        let traced = dir.path().join(format!("{name}-rbuffer.png"));
        let mut all =
            vec!["--mode", "hybrid", "--gbuffer-percent", "100", "--traced-screenshot", traced.to_str().unwrap()];
        all.extend_from_slice(extra);
        let (shot, stats) = run_viewer(dir.path(), name, true, &all);
        let h = &stats["hybrid"];
        assert_eq!(h["gbuffer"], serde_json::json!([W, H]), "{name}: {h}");
        let (rays, flagged) = (h["rays"].as_u64().unwrap(), h["reflective_pixels"].as_u64().unwrap());
        assert_eq!(rays, flagged, "{name}: every reflective pixel traced without interlacing");
        assert!(
            (flagged as f64 - reflective as f64).abs() <= 0.05 * reflective as f64,
            "{name}: {flagged} vs {reflective}"
        );
        for k in ["raster_ms", "readback_ms", "trace_ms", "upload_ms", "composite_ms"] {
            assert!(h[k].as_f64().is_some_and(|v| v >= 0.0), "{name}: {k} in {h}");
        }
        let db = rbuffer_psnr(&traced, &want);
        assert!(db >= 35.0, "{name}: R-buffer {db:.1} dB from the CPU renderer's reflections");
        assert!(shot.pixels().filter(|p| p.0[0] > 40).count() > (W * H / 8) as usize, "{name}: composite drawn");
    }
    // With the animation on, the G-buffer and the reflections show the scene posed at the same time.
    let traced = dir.path().join("hybrid-animated-rbuffer.png");
    let (_, stats) = run_viewer(
        dir.path(),
        "hybrid-animated",
        true,
        &["--mode", "hybrid", "--animate", "--gbuffer-percent", "100", "--traced-screenshot", traced.to_str().unwrap()],
    );
    let t = stats["animation"]["time_s"].as_f64().expect("animation times in the stats");
    assert!(stats["animation"]["dacrt_setup_ms"].is_number(), "{}", stats["animation"]);
    let (mut moved, anim) = raylab_scene::animation::Animation::add_movers(&scene);
    anim.apply(&mut moved, t as f32).unwrap();
    let structures = Structures::build(&moved, &[Method::Mono], Purpose::Frames, &StructureParams::default()).unwrap();
    let tracer = Tracer::new(&structures, TraceOptions::default()).unwrap();
    let want = reference_reflections(&moved, &tracer, &camera, light, &settings);
    let db = rbuffer_psnr(&traced, &want);
    assert!(db >= 35.0, "animated: R-buffer {db:.1} dB from the CPU renderer's reflections at t = {t}");

    // Interlacing: half the rows a frame.
    let (_, stats) = run_viewer(dir.path(), "hybrid-interlaced", true, &["--mode", "hybrid", "--interlace", "2"]);
    let h = &stats["hybrid"];
    let (rays, flagged) = (h["rays"].as_u64().unwrap(), h["reflective_pixels"].as_u64().unwrap());
    assert!(rays * 3 < flagged * 2 && rays * 3 > flagged, "interlaced: {rays} rays for {flagged} reflective pixels");
}
