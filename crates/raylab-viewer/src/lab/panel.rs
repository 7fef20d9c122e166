//! The side panel: every switch of the tracer, grouped as a user reaches for them (scene, camera, rendering,
//! view), with the readouts below.

use raylab_core::dacrt::{DacrtParams, SplitRule};
use raylab_core::mbvh::StreamLeaves;
use raylab_core::method::{Method, Walk};
use raylab_core::ray_order::RayOrder;
use raylab_core::render::FrameView;
use raylab_simd::Backend;

use super::{Lab, Shot};
use crate::animated::UpdateTimes;
use crate::camera::paths::CameraPath;
use crate::cli::value_name;
use raylab_core::render::RenderSettings;
use raylab_core::shadow::{SampleBound, ShadowKind, Shadows};

use crate::settings::{HybridControls, RenderMode, ViewerSettings};
use crate::tracer::jobs::HybridFrame;

/// Draws the panel.
pub fn show(lab: &mut Lab, ui: &mut egui::Ui) {
    ui.heading("raylab");
    scene_section(lab, ui);
    camera_section(lab, ui);
    render_section(lab, ui);
    view_section(lab, ui);
    egui::CollapsingHeader::new("Readouts").default_open(true).show(ui, |ui| lab.readouts.panel(ui));
    ui.separator();
    ui.horizontal(|ui| {
        if ui.button("Compare methods").on_hover_text("Trace this view with every method and tile size").clicked() {
            lab.start_compare();
        }
        if ui.button("Save frame").on_hover_text("The traced frame as PNG").clicked() {
            lab.request_shot(Shot::Traced(super::timestamped("raylab-frame")));
        }
        if ui.button("Save window").on_hover_text("The whole window as PNG (F12)").clicked() {
            lab.request_shot(Shot::Window(super::timestamped("raylab-window")));
        }
    });
    ui.small(format!("GPU: {}", lab.gpu_name));
    ui.small("Tab hides this panel");
}

fn scene_section(lab: &mut Lab, ui: &mut egui::Ui) {
    egui::CollapsingHeader::new("Scene").default_open(true).show(ui, |ui| {
        let current = lab.scene.name.clone();
        egui::ComboBox::from_label("built-in").selected_text(&current).show_ui(ui, |ui| {
            for name in raylab_scene::builtin::names() {
                if ui.selectable_label(current == name, name).clicked() && current != name {
                    lab.open(name);
                }
            }
        });
        ui.horizontal(|ui| {
            if ui.button("Open...").clicked() {
                lab.open_dialog();
            }
            ui.add(
                egui::TextEdit::singleline(&mut lab.open_path)
                    .hint_text("path/to/scene.obj, .gltf or .glb")
                    .desired_width(170.0),
            );
            if ui.button("Load").clicked() {
                let p = lab.open_path.clone();
                lab.open(&p);
            }
        });
        ui.small("or drop an .obj, .gltf or .glb file on the window");
        let s = &lab.scene;
        let method = lab.settings.frame_method();
        let built = method.entry().frame_kd.and_then(|k| s.structures.built(k));
        if let Some((built, stats)) = built.and_then(|b| Some((b, b.kd?))) {
            ui.label(format!(
                "{} triangles; the method's kd-tree: {} nodes (depth {}, C_trav {}), built in {:.2} s",
                s.scene.triangle_count(),
                stats.nodes,
                stats.max_depth,
                s.structures.params().kd_for(method).c_trav,
                built.seconds
            ));
        }
        let dropped = s.scene.dropped.total();
        if dropped > 0 {
            ui.colored_label(ui.visuals().warn_fg_color, format!("{dropped} bad triangles dropped at load"));
        }
    });
}

fn camera_section(lab: &mut Lab, ui: &mut egui::Ui) {
    egui::CollapsingHeader::new("Camera").default_open(false).show(ui, |ui| {
        ui.small("WASD move, Q/E down/up, right drag look, wheel speed, Shift fast, F frame scene");
        ui.horizontal(|ui| {
            ui.label("speed");
            let step = lab.fly.speed * 0.01;
            ui.add(egui::DragValue::new(&mut lab.fly.speed).speed(step).range(1e-4..=1e7));
            if ui.button("Frame scene").clicked() {
                lab.frame_scene();
            }
        });
        ui.label("Bookmarks");
        let mut go = None;
        for v in &lab.scene.scene.views {
            if ui.button(format!("view: {}", v.name)).clicked() {
                go = Some(v.camera);
            }
        }
        let mut remove = None;
        for (i, b) in lab.bookmarks.for_scene(&lab.scene.name).iter().enumerate() {
            ui.horizontal(|ui| {
                if ui.button(&b.name).clicked() {
                    go = Some(b.camera);
                }
                if ui.small_button("x").on_hover_text("Delete this bookmark").clicked() {
                    remove = Some(i);
                }
            });
        }
        if let Some(c) = go {
            lab.fly.camera = c;
            lab.dirty = true;
        }
        if let Some(i) = remove {
            let r = lab.bookmarks.remove(&lab.scene.name, i);
            lab.report(r);
        }
        ui.horizontal(|ui| {
            ui.add(egui::TextEdit::singleline(&mut lab.new_bookmark).hint_text("name").desired_width(120.0));
            if ui.button("Save view").clicked() {
                let name = if lab.new_bookmark.trim().is_empty() {
                    format!("view {}", lab.bookmarks.for_scene(&lab.scene.name).len() + 1)
                } else {
                    lab.new_bookmark.trim().to_string()
                };
                let r = lab.bookmarks.add(&lab.scene.name, name, lab.fly.camera);
                lab.report(r);
                lab.new_bookmark.clear();
            }
        });
        ui.label("Camera path");
        ui.add(egui::TextEdit::singleline(&mut lab.path_file).desired_width(200.0));
        ui.horizontal(|ui| {
            if let Some(rec) = &lab.recorder {
                if ui.button(format!("Stop ({} keys) and save", rec.len())).clicked() {
                    lab.stop_recording();
                }
            } else if ui.add_enabled(lab.player.is_none(), egui::Button::new("Record")).clicked() {
                lab.recorder = Some(crate::camera::paths::Recorder::start(&lab.scene.name, lab.fly.camera));
            }
            if let Some(p) = &lab.player {
                let (i, n) = p.progress();
                if ui.button(format!("Stop playback ({i}/{n})")).clicked() {
                    lab.player = None;
                    lab.dirty = true;
                }
            } else if ui.add_enabled(lab.recorder.is_none(), egui::Button::new("Play")).clicked() {
                match CameraPath::load(std::path::Path::new(&lab.path_file)) {
                    Ok(p) => lab.play(p, false),
                    Err(e) => lab.message(e, true),
                }
            }
        });
    });
}

fn render_section(lab: &mut Lab, ui: &mut egui::Ui) {
    let before = lab.settings;
    let light_radius = lab.light.radius;
    let paths = lab.latest().and_then(|r| r.paths);
    let animation = lab.latest().and_then(|r| r.animation);
    let hybrid = lab.latest().and_then(|r| r.hybrid.clone());
    let gpu_ms = lab.hybrid_gpu_ms;
    let traced_scale = lab.latest().map(|r| r.settings.scale);
    let s = &mut lab.settings;
    egui::CollapsingHeader::new("Rendering").default_open(true).show(ui, |ui| {
        egui::ComboBox::from_label("mode").selected_text(value_name(&s.mode)).show_ui(ui, |ui| {
            ui.selectable_value(&mut s.mode, RenderMode::Whitted, "whitted");
            ui.selectable_value(&mut s.mode, RenderMode::Distribution, "distribution");
            ui.selectable_value(&mut s.mode, RenderMode::Hybrid, "hybrid (G-buffer)");
        });
        if s.mode == RenderMode::Hybrid {
            hybrid_controls(ui, s, hybrid.as_deref(), gpu_ms);
        }
        if s.mode == RenderMode::Distribution {
            let d = &mut s.distribution;
            ui.add(egui::Slider::new(&mut d.bounces, 1..=7).text("bounces"));
            ui.add(egui::Slider::new(&mut d.paths_per_pass, 1..=64).text("paths per frame"));
            ui.add(egui::Slider::new(&mut d.glossy_exponent, 1.0..=1000.0).logarithmic(true).text("glossy exponent"));
            ui.checkbox(&mut d.all_glossy, "every surface glossy").on_hover_text("the MBVH RS paper's benchmark");
            ui.add(egui::Slider::new(&mut d.aperture, 0.0..=1.0).text("lens radius"));
            if let Some(paths) = paths {
                ui.small(format!("{paths} paths per pixel so far"));
            }
        }
        egui::ComboBox::from_label("method").selected_text(s.trace.method.name()).show_ui(ui, |ui| {
            for m in Method::ALL {
                let e = m.entry();
                let r = ui
                    .add_enabled(e.not_live.is_none(), egui::Button::selectable(s.trace.method == m, m.name()))
                    .on_hover_text(format!("{} ({})", e.summary, e.source));
                if r.clicked() {
                    s.trace.method = m;
                }
                if let Some(why) = e.not_live {
                    r.on_disabled_hover_text(why);
                }
            }
        });
        egui::ComboBox::from_label("tile").selected_text(format!("{0}x{0}", s.tile)).show_ui(ui, |ui| {
            for t in ViewerSettings::TILES {
                ui.selectable_value(&mut s.tile, t, format!("{t}x{t}"));
            }
        });
        let frustums = s.trace.method.entry().tile_matters();
        ui.add_enabled(frustums, egui::Checkbox::new(&mut s.trace.cull, "packet/leaf culling"))
            .on_disabled_hover_text("only the frustum methods cull packets at leaves");
        ui.add_enabled(
            s.trace.method.entry().walk == Walk::MbvhStream,
            egui::Checkbox::new(&mut s.trace.stream_order, "stream ordering"),
        )
        .on_hover_text("walk MBVH RS children by accumulated hit length (the paper's heuristic)")
        .on_disabled_hover_text("only mbvh-rs orders its child tasks");
        ui.add_enabled_ui(s.trace.method.entry().walk == Walk::MbvhStream, |ui| {
            egui::ComboBox::from_label("stream leaves").selected_text(s.trace.stream_leaves.name()).show_ui(ui, |ui| {
                for l in StreamLeaves::ALL {
                    ui.selectable_value(&mut s.trace.stream_leaves, l, l.name());
                }
            });
        })
        .response
        .on_hover_text("MBVH RS leaf test: ray pairs against four-triangle blocks, or the paper's four-ray packets")
        .on_disabled_hover_text("only mbvh-rs streams rays through leaves");
        if s.trace.method.entry().walk == Walk::DacrtSet {
            dacrt_controls(ui, s);
        }
        egui::ComboBox::from_label("SIMD").selected_text(s.trace.backend.name()).show_ui(ui, |ui| {
            for b in Backend::available() {
                ui.selectable_value(&mut s.trace.backend, b, b.name());
            }
        });
        shadow_controls(ui, s, light_radius);
        ui.add_enabled(
            frustums && s.shadows == Shadows::Hard,
            egui::Slider::new(&mut s.trace.shadow_spread_limit, 0.0..=0.5).text("shadow spread limit"),
        )
        .on_hover_text("widest shadow bundle traced as a frustum; wider ones go as 2x2 packets");
        let single = !s.trace.method.entry().packets();
        ui.add_enabled_ui(single, |ui| {
            egui::ComboBox::from_label("ray order").selected_text(s.order.name()).show_ui(ui, |ui| {
                for o in RayOrder::ALL {
                    ui.selectable_value(&mut s.order, o, o.name());
                }
            });
        })
        .response
        .on_disabled_hover_text("packet methods trace tiles row by row");
        let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
        ui.add(egui::Slider::new(&mut s.threads, 1..=(2 * cpus).max(2)).text("threads"));
        ui.add(egui::Slider::new(&mut s.scale, 25..=100).text("render scale %"));
        ui.horizontal(|ui| {
            ui.checkbox(&mut s.fly_scale, "lower while flying").on_hover_text(
                "while the camera moves, trace at the scale that takes about 1/30 s a frame; \
                 the chosen scale returns once it stops",
            );
            if let Some(t) = traced_scale.filter(|&t| t < s.scale) {
                ui.label(format!("(now {t}%)"));
            }
        });
        ui.checkbox(&mut s.continuous, "trace continuously").on_hover_text("keep tracing a still view for steady FPS");
        ui.add_enabled(
            s.mode != RenderMode::Hybrid,
            egui::Checkbox::new(&mut s.animate, "animate (spinning mirror, bouncing ball)"),
        )
        .on_hover_text(
            "move objects every frame: the kd-tree is rebuilt, the MBVH refitted, DACRT set up again (milliseconds)",
        )
        .on_disabled_hover_text("the hybrid mode rasterises the loaded scene, which does not move yet");
        if let Some(u) = animation.filter(|_| s.animate) {
            animation_readout(ui, &u);
        }
    });
    if lab.settings != before {
        lab.dirty = true;
    }
}

/// The shadow technique, its parameters, and the reflection depth.
fn shadow_controls(ui: &mut egui::Ui, s: &mut ViewerSettings, light_radius: f32) {
    // Parameters carry over when switching technique: the edge radius and leak fix, the sample bound.
    let (radius, leak_fix, bound) = match s.shadows {
        Shadows::EdgeWidth { radius, leak_fix } => (radius, leak_fix, SampleBound::default()),
        Shadows::MultiSample { bound, .. } => (light_radius, false, bound),
        _ => (light_radius, false, SampleBound::default()),
    };
    let kinds = [
        (ShadowKind::None, "none"),
        (ShadowKind::Hard, "hard"),
        (ShadowKind::Cached, "hard, shadow cache"),
        (ShadowKind::Edge, "edge width (soft)"),
        (ShadowKind::Samples(4), "4 samples"),
        (ShadowKind::Samples(8), "8 samples"),
        (ShadowKind::Samples(16), "16 samples"),
        (ShadowKind::Samples(32), "32 samples"),
    ];
    let current = s.shadows.name();
    let label = kinds.iter().find(|(k, _)| k.with(radius, leak_fix, bound).name() == current).map_or("?", |k| k.1);
    egui::ComboBox::from_label("shadows").selected_text(label).show_ui(ui, |ui| {
        for (kind, name) in kinds {
            let option = kind.with(radius, leak_fix, bound);
            if ui.selectable_label(option.name() == current, name).clicked() && option.name() != current {
                s.shadows = option;
            }
        }
    });
    match &mut s.shadows {
        Shadows::EdgeWidth { radius, leak_fix } => {
            let top = (light_radius * 8.0).max(1.0);
            ui.add(egui::Slider::new(radius, 0.0..=top).text("edge radius R"))
                .on_hover_text("edge width at which a point is fully shadowed; wider R, wider penumbra");
            ui.checkbox(leak_fix, "light-leak fix")
                .on_hover_text("pair only entry and exit triangles that share a vertex");
        }
        Shadows::MultiSample { bound, .. } => {
            egui::ComboBox::from_label("sample bound").selected_text(bound.name()).show_ui(ui, |ui| {
                for b in SampleBound::ALL {
                    ui.selectable_value(bound, b, b.name()).on_hover_text(b.summary());
                }
            });
            ui.small(format!("light radius {light_radius}"));
        }
        _ => {}
    }
    ui.add(egui::Slider::new(&mut s.depth, 0..=RenderSettings::MAX_DEPTH.min(8)).text("reflection depth"))
        .on_hover_text("reflection and refraction bounces after the primary hit");
}

fn view_section(lab: &mut Lab, ui: &mut egui::Ui) {
    let before = lab.settings;
    let s = &mut lab.settings;
    egui::CollapsingHeader::new("View").default_open(true).show(ui, |ui| {
        ui.horizontal_wrapped(|ui| {
            for v in FrameView::ALL {
                ui.selectable_value(&mut s.show, v, v.name());
            }
        });
        if s.show.is_heat_map() {
            let mut fixed = s.heat_max.is_some();
            ui.horizontal(|ui| {
                ui.checkbox(&mut fixed, "fixed scale");
                if fixed {
                    let mut m = s.heat_max.unwrap_or(64.0);
                    ui.add(egui::DragValue::new(&mut m).range(0.01..=1e6).speed(0.5));
                    s.heat_max = Some(m);
                } else {
                    s.heat_max = None;
                }
            });
        }
    });
    if lab.settings != before {
        lab.dirty = true;
    }
}

/// DACRT's leaf thresholds and split rule, and the tile it really traces.
fn dacrt_controls(ui: &mut egui::Ui, s: &mut ViewerSettings) {
    let d = &mut s.trace.dacrt;
    let max = DacrtParams::MAX_LEAF.min(256);
    ui.add(egui::Slider::new(&mut d.leaf_rays, 1..=max).logarithmic(true).text("leaf rays"))
        .on_hover_text("a node with at most this many rays is tested naively (below the division made at setup)");
    ui.add(egui::Slider::new(&mut d.leaf_tris, 1..=max).logarithmic(true).text("leaf triangles"))
        .on_hover_text("a node with at most this many triangles is tested naively");
    egui::ComboBox::from_label("split").selected_text(d.split.name()).show_ui(ui, |ui| {
        for r in SplitRule::ALL {
            ui.selectable_value(&mut d.split, r, r.name());
        }
    });
    let edge = Method::Dacrt.entry().tile_edge(s.tile, 1);
    if edge != s.tile {
        ui.small(format!("DACRT traces {edge}x{edge} tiles: smaller ray sets repeat the division of every triangle"));
    }
}

/// What the last frame's structure updates cost.
fn animation_readout(ui: &mut egui::Ui, u: &UpdateTimes) {
    let part = |name: &str, ms: Option<f64>| ms.map(|ms| format!("{name} {ms:.1} ms"));
    let parts: Vec<String> = [
        part("kd-tree rebuild", u.kd_rebuild_ms),
        part("MBVH refit", u.mbvh_refit_ms),
        part("DACRT setup", u.dacrt_setup_ms),
    ]
    .into_iter()
    .flatten()
    .collect();
    ui.small(format!("t = {:.1} s, {} moving triangles: {}", u.time_s, u.moving_triangles, parts.join(", ")));
}

/// The hybrid mode's G-buffer resolution, interlacing, readback and reflection method, and what its last
/// frame cost.
fn hybrid_controls(ui: &mut egui::Ui, s: &mut ViewerSettings, last: Option<&HybridFrame>, gpu_ms: Option<(f64, f64)>) {
    let h = &mut s.hybrid;
    egui::ComboBox::from_label("G-buffer").selected_text(format!("{}%", h.gbuffer_percent)).show_ui(ui, |ui| {
        for p in HybridControls::PERCENTS {
            ui.selectable_value(&mut h.gbuffer_percent, p, format!("{p}%"));
        }
    });
    egui::ComboBox::from_label("interlacing").selected_text(format!("1/{}", h.interlace)).show_ui(ui, |ui| {
        for k in HybridControls::INTERLACE {
            ui.selectable_value(&mut h.interlace, k, format!("1/{k} of the rows a frame"));
        }
    });
    ui.checkbox(&mut h.async_readback, "asynchronous readback")
        .on_hover_text("read the G-buffer a frame late through double-buffered staging buffers instead of waiting");
    egui::ComboBox::from_label("reflection method").selected_text(h.method.name()).show_ui(ui, |ui| {
        for m in Method::ALL.into_iter().filter(|&m| m != Method::Reference) {
            ui.selectable_value(&mut h.method, m, m.name());
        }
    });
    if let Some(f) = last {
        ui.small(format!(
            "{}x{} G-buffer: {} reflective pixels, {} rays traced",
            f.size.0, f.size.1, f.reflective, f.rays
        ));
        let (upload, composite) = gpu_ms.unwrap_or((0.0, 0.0));
        ui.small(format!(
            "ms: raster {:.1}, readback {:.1}, trace {:.1}, upload {:.1}, composite {:.1}",
            f.raster_ms, f.readback_ms, f.trace_ms, upload, composite
        ));
    }
}
