//! The shading half of `raylab-bench tables`: thesis Table 5.1 (frame rate per shadow technique), Table 4.6
//! (16-sample soft shadows bounded by cones or pyramids, light radius 1 and 2), Table 3.1 (where a frame's
//! time goes, stage by stage), and an image-quality table: each soft technique's RMSE against a 1024-sample
//! reference, with the images written as PNG.

use std::fmt::Write as _;
use std::path::Path;

use raylab_core::kdtree::KdTree;
use raylab_core::method::Method;
use raylab_core::render::{Frame, RenderSettings, StageTimes, render};
use raylab_core::scene::{Camera, PointLight, Scene};
use raylab_core::shadow::{SampleBound, Shadows};
use raylab_core::structures::Structures;
use raylab_core::trace::{TraceOptions, Tracer};

use serde_json::{Value, json};

use super::frame_cells::{Cell, measure, measure_interleaved, record};

/// Samples per point of the image-quality table's reference.
const REFERENCE_SAMPLES: u32 = 1024;

/// What the shading tables need besides the scenes.
pub struct ShadingRun<'a> {
    /// Frame width and height for the timed tables.
    pub size: (u32, u32),
    /// Frame width and height of the image-quality renders (the 1024-sample reference is slow).
    pub quality_size: (u32, u32),
    /// Timed frames per configuration.
    pub reps: u64,
    /// The pool to render on.
    pub pool: &'a rayon::ThreadPool,
    /// Where the image-quality PNGs go, if anywhere.
    pub images: Option<&'a Path>,
    /// Tile edge of the primary rays (MFT).
    pub tile: u32,
}

/// One scene with its tree, camera and light.
pub struct Subject<'a> {
    /// Name for the tables.
    pub name: &'a str,
    /// The scene.
    pub scene: &'a Scene,
    /// Its structures (MFT's kd-tree).
    pub structures: &'a Structures,
    /// The camera.
    pub camera: Camera,
    /// The light (its radius is replaced where a table fixes one).
    pub light: PointLight,
}

impl Subject<'_> {
    fn kd_tree(&self) -> &KdTree {
        self.structures.kd_for(Method::Mft).expect("the shading tables build MFT's structures for frames")
    }
}

impl ShadingRun<'_> {
    fn settings(&self, shadows: Shadows, max_depth: u32, size: (u32, u32)) -> RenderSettings {
        RenderSettings { width: size.0, height: size.1, tile: self.tile, shadows, max_depth, ..Default::default() }
    }

    fn timed(&self, s: &Subject, tracer: &Tracer, light: PointLight, shadows: Shadows, depth: u32) -> Cell {
        measure(s.scene, tracer, &s.camera, light, &self.settings(shadows, depth, self.size), self.pool, self.reps)
    }

    /// Primary-ray frames (no reflections) under each of `techniques`, measured round by round.
    fn timed_together(&self, s: &Subject, tracer: &Tracer, light: PointLight, techniques: &[Shadows]) -> Vec<Cell> {
        let configs: Vec<_> = techniques.iter().map(|&t| (tracer, self.settings(t, 0, self.size))).collect();
        measure_interleaved(s.scene, &s.camera, light, &configs, self.pool, self.reps)
    }

    /// Writes Tables 5.1, 4.6 and 3.1 and the image-quality table for `subjects` into `md`.
    pub fn write(&self, subjects: &[Subject], md: &mut String, records: &mut Vec<Value>) -> Result<(), String> {
        let (w, h) = self.size;
        let _ = writeln!(
            md,
            "\n{w}x{h}; primary rays by MFT {t}x{t}; FPS from the median of {} frames, the techniques of a table \
             row rendered in turn, round by round. Soft techniques use the light's radius (1 where the scene's \
             light is a point), and the edge radius R equals it.",
            self.reps,
            t = self.tile
        );
        self.table_5_1(subjects, md, records);
        self.table_4_6(subjects, md, records);
        self.table_3_1(subjects, md, records);
        self.quality(subjects, md, records)
    }

    /// A JSON record of a shading-table cell: what was measured (table, scene, shadow technique, light radius,
    /// reflection depth, MFT at the run's tile) and the cell.
    fn record(&self, table: &str, s: &Subject, shadows: &Shadows, light_radius: f32, depth: u32, c: &Cell) -> Value {
        let head = json!({ "table": table, "scene": s.name, "method": Method::Mft, "tile": self.tile, "cull": true,
            "shadows": shadows, "light_radius": light_radius, "depth": depth });
        record(head, c)
    }

    fn tracer<'t>(s: &'t Subject) -> Tracer<'t> {
        let options = TraceOptions { method: Method::Mft, ..TraceOptions::default() };
        Tracer::new(s.structures, options).expect("the shading tables build MFT's structures for frames")
    }

    fn table_5_1(&self, subjects: &[Subject], md: &mut String, records: &mut Vec<Value>) {
        let _ = writeln!(
            md,
            "\n**Table 5.1**: shadow techniques, primary rays only (no reflections), FPS (and frame time against \
             hard shadows); samples bounded by {} (the fastest bound, Table 4.6).\n",
            SampleBound::default().name()
        );
        let _ = writeln!(
            md,
            "| scene | none | hard | hard + cache (hit rate) | edge width | edge / hard time | 4 samples | 32 \
             samples |"
        );
        let _ = writeln!(md, "|---|---:|---:|---:|---:|---:|---:|---:|");
        for s in subjects {
            let tracer = Self::tracer(s);
            let light = s.light.soft();
            let r = light.radius;
            let techniques = [
                Shadows::None,
                Shadows::Hard,
                Shadows::Cached,
                Shadows::EdgeWidth { radius: r, leak_fix: false },
                Shadows::MultiSample { samples: 4, bound: SampleBound::default() },
                Shadows::MultiSample { samples: 32, bound: SampleBound::default() },
            ];
            let cells = self.timed_together(s, &tracer, light, &techniques);
            records.extend(techniques.iter().zip(&cells).map(|(t, c)| self.record("5.1", s, t, r, 0, c)));
            let [none, hard, cached, edge, ms4, ms32] = cells[..] else { unreachable!("six techniques") };
            let _ = writeln!(
                md,
                "| {} | {:.1} | {:.1} | {:.1} ({:.0}%) | {:.1} | {:.2}x | {:.2} | {:.2} |",
                s.name,
                none.fps,
                hard.fps,
                cached.fps,
                100.0 * cached.cache_hit_rate,
                edge.fps,
                hard.fps / edge.fps,
                ms4.fps,
                ms32.fps
            );
        }
    }

    fn table_4_6(&self, subjects: &[Subject], md: &mut String, records: &mut Vec<Value>) {
        let _ = writeln!(
            md,
            "\n**Table 4.6**: 16 samples per point, bounded by the cone or the square pyramid around the light \
             (proxies built from the light alone, as in the thesis), by a pyramid fitted to the samples, or by \
             nothing (plain packets).\n"
        );
        let _ = writeln!(md, "| scene | light radius | bound | FPS | N | I | cone speed-up |");
        let _ = writeln!(md, "|---|---:|---|---:|---:|---:|---:|");
        for s in subjects {
            let tracer = Self::tracer(s);
            for radius in [1.0f32, 2.0] {
                let light = PointLight { radius, ..s.light };
                let bounds = [SampleBound::Cone, SampleBound::Pyramid, SampleBound::Fitted, SampleBound::Packets];
                let techniques = bounds.map(|bound| Shadows::MultiSample { samples: 16, bound });
                let cells: Vec<(SampleBound, Cell)> =
                    bounds.into_iter().zip(self.timed_together(s, &tracer, light, &techniques)).collect();
                records.extend(techniques.iter().zip(&cells).map(|(t, (_, c))| self.record("4.6", s, t, radius, 0, c)));
                let cone = cells[0].1.fps;
                for (bound, c) in &cells {
                    let speedup =
                        if *bound == SampleBound::Cone { String::new() } else { format!("{:.2}x", cone / c.fps) };
                    let _ = writeln!(
                        md,
                        "| {} | {radius} | {} | {:.2} | {:.2} | {:.2} | {speedup} |",
                        s.name,
                        bound.name(),
                        c.fps,
                        c.n,
                        c.i
                    );
                }
            }
        }
    }

    fn table_3_1(&self, subjects: &[Subject], md: &mut String, records: &mut Vec<Value>) {
        let _ = writeln!(
            md,
            "\n**Table 3.1**: share of the frame per stage, hard shadows, reflections and refractions to depth {} \
             (thread-summed times). Traversal and intersection run interleaved inside one kernel call: each trace \
             stage's triangle tests are counted and charged the cost of one test measured alone on the same \
             scene (the view's primary packets against the triangles of the leaves they end in, warm \
             caches: a lower bound on intersection), and the rest of the stage is traversal.\n",
            RenderSettings::DEFAULT_DEPTH
        );
        let names = StageTimes::SPLIT_NAMES;
        let _ = write!(md, "| scene | FPS | ns per test |");
        for name in names {
            let _ = write!(md, " {name} |");
        }
        let _ = writeln!(md, "\n|---|---:|---:|{}", "---:|".repeat(names.len()));
        for s in subjects {
            let tracer = Self::tracer(s);
            let c = self.timed(s, &tracer, s.light, Shadows::Hard, RenderSettings::DEFAULT_DEPTH);
            let (w, h, backend) = (self.size.0, self.size.1, tracer.options.backend);
            let per_test =
                crate::isect_cost::seconds_per_packet_test(s.kd_tree(), &s.camera, w, h, backend).unwrap_or(0.0);
            let split = c.stages.split(per_test);
            let total: f64 = split.iter().sum();
            let mut v = self.record("3.1", s, &Shadows::Hard, s.light.radius, RenderSettings::DEFAULT_DEPTH, &c);
            v["seconds_per_test"] = json!(per_test);
            v["split_seconds"] = json!(
                names.iter().zip(split).map(|(n, t)| (n.to_string(), json!(t))).collect::<serde_json::Map<_, _>>()
            );
            records.push(v);
            let _ = write!(md, "| {} | {:.1} | {:.1} |", s.name, c.fps, per_test * 1e9);
            for t in split {
                let _ = write!(md, " {:.1}% |", if total > 0.0 { 100.0 * t / total } else { 0.0 });
            }
            let _ = writeln!(md);
        }
    }

    fn quality(&self, subjects: &[Subject], md: &mut String, records: &mut Vec<Value>) -> Result<(), String> {
        let (w, h) = self.quality_size;
        let _ = writeln!(
            md,
            "\n**Image quality**: RMSE (8-bit display values, all channels) against {REFERENCE_SAMPLES} stratified samples per \
             point, {w}x{h}, primary rays only.\n"
        );
        let _ =
            writeln!(md, "| scene | hard | edge width | edge width, leak fix | 4 samples | 16 samples | 32 samples |");
        let _ = writeln!(md, "|---|---:|---:|---:|---:|---:|---:|");
        for s in subjects {
            let tracer = Self::tracer(s);
            let light = s.light.soft();
            let r = light.radius;
            let shot = |shadows: Shadows| -> Frame {
                self.pool.install(|| render(s.scene, &tracer, &s.camera, light, &self.settings(shadows, 0, (w, h))))
            };
            let reference = shot(Shadows::MultiSample { samples: REFERENCE_SAMPLES, bound: SampleBound::default() });
            let techniques = [
                ("hard", Shadows::Hard),
                ("edge", Shadows::EdgeWidth { radius: r, leak_fix: false }),
                ("edge-leakfix", Shadows::EdgeWidth { radius: r, leak_fix: true }),
                ("ms4", Shadows::MultiSample { samples: 4, bound: SampleBound::default() }),
                ("ms16", Shadows::MultiSample { samples: 16, bound: SampleBound::default() }),
                ("ms32", Shadows::MultiSample { samples: 32, bound: SampleBound::default() }),
            ];
            let _ = write!(md, "| {} |", s.name);
            for (label, shadows) in techniques {
                let f = shot(shadows);
                let error = rmse(&f, &reference);
                let _ = write!(md, " {error:.2} |");
                records.push(json!({ "table": "quality", "scene": s.name, "technique": label, "shadows": shadows,
                    "light_radius": r, "width": w, "height": h, "reference_samples": REFERENCE_SAMPLES, "rmse": error }));
                if let Some(dir) = self.images {
                    save(&f, &dir.join(format!("{}-{label}.png", s.name)))?;
                }
            }
            let _ = writeln!(md);
            if let Some(dir) = self.images {
                save(&reference, &dir.join(format!("{}-ms{REFERENCE_SAMPLES}.png", s.name)))?;
            }
        }
        if let Some(dir) = self.images {
            let _ = writeln!(md, "\nImages: `{}/<scene>-<technique>.png`.", dir.display());
        }
        Ok(())
    }
}

/// Root-mean-square difference of two frames' RGB display values.
fn rmse(a: &Frame, b: &Frame) -> f64 {
    let sum: f64 =
        a.rgba.iter().zip(&b.rgba).flat_map(|(p, q)| (0..3).map(move |k| (p[k] as f64 - q[k] as f64).powi(2))).sum();
    (sum / (3 * a.rgba.len().max(1)) as f64).sqrt()
}

fn save(f: &Frame, path: &Path) -> Result<(), String> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(|e| format!("--images: cannot create {}: {e}", dir.display()))?;
    }
    image::RgbaImage::from_raw(f.width, f.height, f.rgba.as_flattened().to_vec())
        .ok_or("frame buffer size mismatch")?
        .save(path)
        .map_err(|e| format!("--images: cannot write {}: {e}", path.display()))
}
