//! The command line as a user meets it: outputs, and clear errors with a non-zero exit on bad input.

use std::process::{Command, Output};

fn bench(args: &[&str], dir: &std::path::Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_raylab-bench")).args(args).current_dir(dir).output().expect("runs")
}

/// Runs `compare` on a 16x16 view of the arena, one thread, one run and one build, against the shell
/// script `harness` standing in for the Embree harness, with `extra` flags.
#[cfg(unix)]
fn compare_with_fake_harness(dir: &std::path::Path, harness: &str, extra: &[&str]) -> Output {
    use std::os::unix::fs::PermissionsExt;
    let path = dir.join("embree_bench");
    std::fs::write(&path, harness).unwrap();
    std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755)).unwrap();
    let common = "--scene arena --width 16 --height 16 --threads 1 --reps 1 --builds 1";
    let args: Vec<&str> = ["compare", "--embree", path.to_str().unwrap()]
        .into_iter()
        .chain(common.split(' '))
        .chain(extra.iter().copied())
        .collect();
    bench(&args, dir)
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn render_writes_a_png() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("a.png");
    let o = bench(
        &["render", "--scene", "arena", "--width", "64", "--height", "48", "--out", out.to_str().unwrap()],
        dir.path(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let img = image::open(&out).expect("a PNG").to_rgba8();
    assert_eq!(img.dimensions(), (64, 48));
    assert!(img.pixels().any(|p| p.0[0] > 40), "the image is not black");
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("wrote") && stdout.contains("counters: "), "{stdout}");
}

#[test]
fn repeated_frames_report_their_times_and_keep_the_image() {
    let dir = tempfile::tempdir().unwrap();
    let render = |frames: &str, name: &str| {
        let out = dir.path().join(name);
        let args = ["render", "--scene", "atrium", "--width", "40", "--height", "30", "--threads", "2", "--frames"];
        let o = bench(&[&args[..], &[frames, "--out", out.to_str().unwrap()]].concat(), dir.path());
        assert!(o.status.success(), "{}", stderr(&o));
        (String::from_utf8_lossy(&o.stdout).into_owned(), image::open(&out).expect("a PNG").to_rgba8())
    };
    let (once, first) = render("1", "one.png");
    let (many, last) = render("5", "five.png");
    assert!(!once.contains("frames: median"), "{once}");
    let line = many.lines().find(|l| l.starts_with("5 frames: median")).unwrap_or_else(|| panic!("{many}"));
    let ms: Vec<f64> = line
        .split_whitespace()
        .zip(line.split_whitespace().skip(1))
        .filter(|(_, unit)| unit.trim_matches(|c| c == ',' || c == ')') == "ms")
        .map(|(v, _)| v.trim_start_matches('(').parse().unwrap())
        .collect();
    let [median, min, max] = ms[..] else { panic!("median, min and max in ms: {line}") };
    assert!(min > 0.0 && min <= median && median <= max, "{line}");
    assert!(many.contains("stages (median frame, summed over threads)"), "{many}");
    assert_eq!(first, last, "every frame is the same image");
}

#[test]
fn render_json_is_one_object_with_frame_times_stages_and_counters() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("j.png");
    let args = ["render", "--scene", "arena", "--width", "40", "--height", "30", "--method", "mft", "--tile", "8"];
    let rest = ["--shadows", "cached", "--depth", "1", "--frames", "3", "--threads", "2", "--json", "--out"];
    let o = bench(&[&args[..], &rest, &[out.to_str().unwrap()]].concat(), dir.path());
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("stdout is exactly one JSON object");
    let f = |path: &str| v.pointer(path).and_then(serde_json::Value::as_f64).unwrap_or_else(|| panic!("{path}: {v}"));
    assert_eq!(image::open(&out).expect("the PNG is still written").to_rgba8().dimensions(), (40, 30));
    assert_eq!(v["out"].as_str().map(std::path::PathBuf::from), Some(out.canonicalize().unwrap()));
    assert_eq!((v["frames"].as_u64(), v["frame_seconds"]["each"].as_array().map(Vec::len)), (Some(3), Some(3)));
    let (median, min, max) = (f("/frame_seconds/median"), f("/frame_seconds/min"), f("/frame_seconds/max"));
    assert!(0.0 < min && min <= median && median <= max, "{v}");
    assert!((f("/fps") * median - 1.0).abs() < 1e-9, "FPS from the median frame: {v}");
    assert!(f("/stages_seconds/primary") > 0.0 && f("/stages_seconds/shadow") > 0.0, "{v}");
    assert_eq!(v["settings"]["shadows"]["technique"], "cached");
    assert_eq!((v["settings"]["width"].as_u64(), v["settings"]["max_depth"].as_u64()), (Some(40), Some(1)));
    assert_eq!(v["options"]["method"], "mft");
    assert!(["avx512", "avx2", "sse2", "scalar"].contains(&v["options"]["backend"].as_str().unwrap()), "{v}");
    // Primary rays, shadow rays and reflections: more rays than pixels, and the derived figures agree with the
    // raw counters.
    let rays = f("/counters/rays");
    assert!(rays > 1200.0, "{v}");
    // (JSON's decimal floats come back within an ulp or so.)
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs();
    assert!(close(f("/mrays_per_second"), rays / median / 1e6), "{v}");
    assert!(close(f("/nodes_per_packet"), f("/counters/nodes") / f("/counters/packets")), "{v}");
    assert!(close(f("/isects_per_packet"), f("/counters/isect_tests") / f("/counters/packets")), "{v}");
    let visits = f("/counters/packets_culled") + f("/counters/packets_tested");
    assert!(visits > 0.0 && close(f("/culled_percent"), 100.0 * f("/counters/packets_culled") / visits), "{v}");
    assert!(f("/counters/cache_lookups") > 0.0 && (0.0..=1.0).contains(&f("/cache_hit_rate")), "{v}");
}

#[test]
fn trace_json_is_one_object_with_checksums() {
    let dir = tempfile::tempdir().unwrap();
    for kind in ["primary", "shadow", "diffuse"] {
        let o = bench(
            &["trace", "--scene", "arena", "--width", "32", "--height", "32", "--kind", kind, "--reps", "2", "--json"],
            dir.path(),
        );
        assert!(o.status.success(), "{}", stderr(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("stdout is exactly one JSON object");
        let r = &v["result"];
        assert!(r["rays"].as_u64().unwrap() > 0 && r["mrays_median"].as_f64().unwrap() > 0.0, "{v}");
        assert!(r["hits"].as_u64().unwrap() > 0, "{kind}: {v}");
        assert!(v["validated_rays"].as_u64().unwrap() > 0);
        assert_eq!(v["result"]["kind"], kind);
    }
}

#[test]
fn info_reports_tree_statistics() {
    let dir = tempfile::tempdir().unwrap();
    let o = bench(&["info", "--scene", "arena", "--json"], dir.path());
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v["triangles"].as_u64().unwrap() > 10_000);
    assert!(v["kdtree"]["leaves"].as_u64().unwrap() > 1 && v["kdtree"]["sah_cost"].as_f64().unwrap() > 0.0);
    // The packet methods' tree has its own cost model, and fewer, fuller leaves.
    let o = bench(&["info", "--scene", "arena", "--method", "mft", "--json"], dir.path());
    assert!(o.status.success(), "{}", stderr(&o));
    let w: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!((v["kd_params"]["c_trav"].as_f64(), w["kd_params"]["c_trav"].as_f64()), (Some(1.0), Some(12.0)));
    assert!(w["kdtree"]["leaves"].as_u64().unwrap() < v["kdtree"]["leaves"].as_u64().unwrap(), "{w}");
}

#[test]
fn bad_input_is_refused_with_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("broken.obj"), "v 0 0 0\nv 1 oops 0\n").unwrap();
    std::fs::write(dir.path().join("empty.obj"), "# nothing\n").unwrap();
    let cases: &[(&[&str], &str)] = &[
        (&["info", "--scene", "sponzaa"], "atrium, arena, kitchen, forest"),
        (&["info", "--scene", "missing.obj"], "missing.obj"),
        (&["info", "--scene", "broken.obj"], "broken.obj:2"),
        (&["info", "--scene", "empty.obj"], "no usable triangles"),
        (&["info", "--scene", "model.fbx"], "unsupported scene format"),
        (&["render", "--scene", "arena", "--width", "0"], "1..=16384"),
        (&["render", "--scene", "arena", "--width", "99999999999"], "1..=16384"),
        (&["render", "--scene", "arena", "--eye", "1,2"], "X,Y,Z"),
        (&["render", "--scene", "arena", "--eye", "nan,0,0"], "not finite"),
        (&["render", "--scene", "arena", "--fov", "180"], "field of view"),
        (&["render", "--scene", "arena", "--eye", "1,1,1", "--target", "1,1,1"], "eye and target"),
        (&["render", "--scene", "arena", "--view", "nowhere"], "overview"),
        (
            &["render", "--scene", "arena", "--out", "/nonexistent-dir/x.png", "--width", "8", "--height", "8"],
            "cannot write",
        ),
        (&["render", "--scene", "arena", "--shadows", "soft"], "unknown shadow technique 'soft'"),
        (&["render", "--scene", "arena", "--shadows", "ms0"], "between 1 and 4096"),
        (&["render", "--scene", "arena", "--edge-radius", "-1"], ">= 0"),
        (&["render", "--scene", "arena", "--light-radius", "nan"], ">= 0"),
        (&["render", "--scene", "arena", "--depth", "99"], "0..=16"),
        (&["render", "--scene", "arena", "--frames", "0"], "1..=100000"),
        (&["render", "--scene", "arena", "--ms-bound", "box"], "packets, fitted, pyramid or cone"),
        (&["trace", "--scene", "arena", "--kind", "glossy"], "primary, shadow, diffuse"),
        (&["trace", "--scene", "arena", "--method", "warp"], "mono"),
        (&["trace", "--scene", "arena", "--threads", "0"], "1..=1024"),
        (&["trace", "--scene", "arena", "--kd-cisect", "-1"], "c_isect"),
        (&["trace", "--scene", "arena", "--kd-empty-bonus", "1"], "empty_bonus"),
        (&["trace", "--scene", "arena", "--method", "mbvh-rs", "--group", "100"], "power of two from 16 to 4096"),
        (&["trace", "--scene", "arena", "--method", "mbvh-rs", "--group", "8192"], "power of two from 16 to 4096"),
        (&["trace", "--scene", "arena", "--method", "mbvh", "--group", "64"], "--method mbvh-rs"),
    ];
    for (args, needle) in cases {
        let o = bench(args, dir.path());
        assert!(!o.status.success(), "{args:?} should fail");
        let e = stderr(&o);
        assert!(e.contains(needle), "{args:?}: error should mention '{needle}', got: {e}");
        assert!(!e.contains("panicked"), "{args:?} panicked: {e}");
    }
}

#[test]
fn tables_print_the_thesis_tables() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("tables.md");
    let o = bench(
        &[
            "tables",
            "--builtins",
            "arena",
            "--shading-builtins",
            "arena",
            "--scene",
            "arena",
            "--width",
            "32",
            "--height",
            "32",
            "--reps",
            "1",
            "--threads",
            "1",
            "--quality-size",
            "16",
            "--images",
            "img",
            "--markdown",
            out.to_str().unwrap(),
            "--json",
            "tables.json",
        ],
        dir.path(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let md = std::fs::read_to_string(&out).unwrap();
    for t in [
        "Table 4.1",
        "Table 4.2",
        "Table 4.3",
        "Table 4.4",
        "Table 4.5",
        "Table 5.1",
        "Table 4.6",
        "Table 3.1",
        "Image quality",
        "| arena |",
    ] {
        assert!(md.contains(t), "missing {t} in:\n{md}");
    }
    for technique in ["hard", "edge", "ms4", "ms32", "ms1024"] {
        assert!(dir.path().join(format!("img/arena-{technique}.png")).is_file(), "no {technique} image");
    }

    // The same tables as flat JSON records, one per measured cell.
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.path().join("tables.json")).unwrap()).unwrap();
    let records = v["records"].as_array().unwrap_or_else(|| panic!("{v}"));
    assert!(v["environment"]["cpus"].as_u64().is_some_and(|n| n > 0), "the machine is named: {v}");
    assert_eq!(v["command"][1], "tables", "the command line is quoted: {v}");
    let of = |table: &str| records.iter().filter(|r| r["table"] == table).collect::<Vec<_>>();
    let counts = ["4.1", "4.2", "4.3", "4.5", "5.1", "4.6", "3.1", "quality"].map(|t| of(t).len());
    assert_eq!(counts, [5, 1, 4, 6, 6, 8, 1, 6], "{v}");
    assert!(records.iter().all(|r| r["scene"] == "arena"), "{v}");
    let packet = of("4.1")[0];
    assert_eq!((&packet["method"], packet["cull"].as_bool()), (&"packet".into(), Some(true)));
    assert_eq!((&of("4.2")[0]["method"], of("4.2")[0]["cull"].as_bool()), (&"frustum".into(), Some(false)));
    // Named as in the render and trace reports.
    assert!(of("4.1")[1]["culled_percent"].as_f64().is_some_and(|c| c > 0.0), "{v}");
    // The markdown's Table 4.1 row starts with the packets' FPS, N and I, as the record holds them.
    let row = md.lines().find(|l| l.starts_with("| arena | ")).unwrap();
    let cell = |k: &str, digits: usize| format!("{:.*}", digits, packet[k].as_f64().unwrap());
    assert!(row.starts_with(&format!("| arena | {} | {} | {} |", cell("fps", 1), cell("n", 2), cell("i", 2))), "{row}");
    let radii: Vec<f64> = of("4.6").iter().map(|r| r["light_radius"].as_f64().unwrap()).collect();
    assert_eq!(radii, [1.0, 1.0, 1.0, 1.0, 2.0, 2.0, 2.0, 2.0]);
    assert_eq!(of("4.6")[0]["shadows"]["bound"], "cone");
    assert_eq!(of("3.1")[0]["split_seconds"].as_object().map(|m| m.len()), Some(7), "{v}");
    assert!(of("quality").iter().all(|r| r["rmse"].as_f64().is_some_and(|e| e >= 0.0)), "{v}");
}

#[test]
fn render_is_the_same_for_every_method_and_backend() {
    let dir = tempfile::tempdir().unwrap();
    let mut images = Vec::new();
    for extra in [
        &["--method", "mono", "--order", "hilbert"][..],
        &["--method", "packet"][..],
        &["--method", "mft", "--tile", "8"][..],
        &["--method", "mft-cone", "--tile", "16", "--backend", "scalar"][..],
        &["--method", "frustum", "--tile", "4", "--no-cull"][..],
    ] {
        let out = dir.path().join(format!("{}.png", images.len()));
        let mut args =
            vec!["render", "--scene", "arena", "--width", "48", "--height", "40", "--out", out.to_str().unwrap()];
        args.extend_from_slice(extra);
        let o = bench(&args, dir.path());
        assert!(o.status.success(), "{extra:?}: {}", stderr(&o));
        images.push(image::open(&out).unwrap().to_rgba8());
    }
    for (k, img) in images.iter().enumerate().skip(1) {
        assert_eq!(img.as_raw(), images[0].as_raw(), "render {k} differs from mono");
    }
}

#[test]
fn every_shadow_technique_renders_the_same_with_every_method() {
    let dir = tempfile::tempdir().unwrap();
    for shadows in [&["--shadows", "edge", "--leak-fix"][..], &["--shadows", "ms8", "--ms-bound", "pyramid"][..]] {
        let mut images = Vec::new();
        for method in ["mono", "mft", "cone"] {
            let out = dir.path().join(format!("{method}.png"));
            let mut args = vec![
                "render",
                "--scene",
                "atrium",
                "--width",
                "40",
                "--height",
                "32",
                "--method",
                method,
                "--out",
                out.to_str().unwrap(),
            ];
            args.extend_from_slice(shadows);
            let o = bench(&args, dir.path());
            assert!(o.status.success(), "{shadows:?}: {}", stderr(&o));
            images.push(image::open(&out).unwrap().to_rgba8());
        }
        assert!(images.iter().all(|i| i.as_raw() == images[0].as_raw()), "{shadows:?}: methods differ");
    }
}

#[test]
fn trace_reports_the_same_checksum_on_every_backend() {
    let dir = tempfile::tempdir().unwrap();
    let mut sums = Vec::new();
    for backend in ["sse2", "scalar"] {
        let o = bench(
            &[
                "trace",
                "--scene",
                "kitchen",
                "--width",
                "40",
                "--height",
                "40",
                "--method",
                "mft",
                "--tile",
                "8",
                "--reps",
                "1",
                "--backend",
                backend,
                "--json",
            ],
            dir.path(),
        );
        assert!(o.status.success(), "{backend}: {}", stderr(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        sums.push((v["result"]["hits"].as_u64().unwrap(), v["result"]["sum_t"].as_f64().unwrap()));
    }
    assert_eq!(sums[0], sums[1]);
}

#[test]
fn info_lists_materials_textures_and_warnings() {
    let dir = tempfile::tempdir().unwrap();
    image::RgbImage::from_pixel(6, 3, image::Rgb([200, 10, 10])).save(dir.path().join("red.png")).unwrap();
    std::fs::write(dir.path().join("m.mtl"), "newmtl brick\nKd 1 1 1\nmap_Kd red.png\nnewmtl lost\nmap_Kd lost.png\n")
        .unwrap();
    std::fs::write(
        dir.path().join("m.obj"),
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nusemtl brick\nf 1 2 3\nusemtl lost\nf 2 4 3\n",
    )
    .unwrap();
    let o = bench(&["info", "--scene", "m.obj"], dir.path());
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    for want in ["brick (Diffuse", "red.png (6x3)", "lost.png (8x8)", "warnings         1", "cannot read texture"] {
        assert!(out.contains(want), "missing '{want}' in:\n{out}");
    }
    let o = bench(&["info", "--scene", "m.obj", "--json"], dir.path());
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["textures"][0]["width"], 6);
    assert_eq!(v["warnings"].as_array().unwrap().len(), 1);
}

#[test]
fn distribution_prints_per_bounce_speeds_for_each_method() {
    let dir = tempfile::tempdir().unwrap();
    let o = bench(
        &[
            "distribution",
            "--scene",
            "arena",
            "--width",
            "16",
            "--height",
            "16",
            "--spp",
            "4",
            "--bounces",
            "2",
            "--groups",
            "2,4",
            "--out",
            "d.png",
            "--json",
            "d.json",
        ],
        dir.path(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    for want in ["| mono |", "| packet |", "| mbvh |", "| mbvh-rs | 64 |", "| mbvh-rs | 16 |", "bounce 2"] {
        assert!(out.contains(want), "missing '{want}' in:\n{out}");
    }
    // The paper's figures, each its own table: counters per bounce for reflection and shadow rays apart, and
    // the leaf SIMD use against the group size (the sweep's groups and the default one, in order).
    for want in ["**Figure 4**", "**Figure 5**", "**Figure 6**", "**Figures 7-8**", "| mbvh | - | shadow |"] {
        assert!(out.contains(want), "missing '{want}' in:\n{out}");
    }
    let sweep = out.split("**Figures 7-8**").nth(1).unwrap();
    let groups: Vec<&str> = sweep.lines().filter_map(|l| l.strip_prefix("| ")?.split(' ').next()).collect();
    assert_eq!(groups[1..], ["16", "64"], "{sweep}");
    assert!(dir.path().join("d.png").is_file());
    // The JSON holds every run: the four methods, then the sweep's MBVH RS groups, each with its three bounces.
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.path().join("d.json")).unwrap()).unwrap();
    let runs = v["runs"].as_array().unwrap_or_else(|| panic!("{v}"));
    let names: Vec<_> = runs.iter().map(|r| (r["method"].as_str().unwrap(), r["group"].as_u64())).collect();
    assert_eq!(names[3..], [("mbvh-rs", Some(64)), ("mbvh-rs", Some(16)), ("mbvh-rs", Some(64))], "{v}");
    assert_eq!(names[..3], [("mono", None), ("packet", None), ("mbvh", None)]);
    for r in runs {
        let bounces = r["bounces"].as_array().unwrap();
        assert_eq!(bounces.len(), 3, "{r}");
        // Every camera ray of the 16x16 image's 4 paths per pixel.
        assert_eq!(bounces[0]["work"]["rays"].as_u64(), Some(16 * 16 * 4), "{r}");
        assert!(bounces[0]["mrays_per_second"].as_f64().unwrap() > 0.0, "{r}");
    }
    let o = bench(&["distribution", "--scene", "arena", "--bounces", "9"], dir.path());
    assert!(!o.status.success() && stderr(&o).contains("1..=7"));
}

#[test]
fn mbvh_rs_groups_cut_from_tiles_give_the_same_hits() {
    let dir = tempfile::tempdir().unwrap();
    for kind in ["diffuse", "shadow"] {
        let sum = |extra: &[&str]| {
            let mut args = vec!["trace", "--scene", "kitchen", "--width", "40", "--height", "40", "--kind", kind];
            args.extend_from_slice(extra);
            args.extend_from_slice(&["--reps", "1", "--json"]);
            let o = bench(&args, dir.path());
            assert!(o.status.success(), "{extra:?}: {}", stderr(&o));
            let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
            (v["result"]["hits"].as_u64().unwrap(), v["result"]["sum_t"].as_f64().unwrap(), v)
        };
        let (hits, sum_t, _) = sum(&["--method", "mono"]);
        assert!(hits > 0, "{kind}");
        for group in ["16", "32", "256", "2048"] {
            let (h, t, v) = sum(&["--method", "mbvh-rs", "--group", group]);
            assert_eq!((h, t), (hits, sum_t), "{kind}, group {group}");
            assert_eq!(v["group"].as_u64().unwrap().to_string(), group);
            assert!(v["tile"].as_u64().unwrap().pow(2) >= v["group"].as_u64().unwrap(), "{v}");
        }
    }
}

#[test]
fn dacrt_traces_and_animate_reports_every_update_strategy() {
    let dir = tempfile::tempdir().unwrap();
    let o = bench(
        &["trace", "--scene", "kitchen", "--width", "48", "--height", "48", "--kind", "diffuse", "--method", "dacrt"],
        dir.path(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("validated"));
    let md = dir.path().join("animate.md");
    let o = bench(
        &[
            "animate",
            "--scene",
            "atrium",
            "--width",
            "40",
            "--height",
            "30",
            "--frames",
            "2",
            "--markdown",
            md.to_str().unwrap(),
            "--json",
            "animate.json",
        ],
        dir.path(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let table = std::fs::read_to_string(&md).unwrap();
    for row in ["| mono | kd-tree rebuilt |", "| mbvh | MBVH refitted |", "| dacrt | triangles copied, top divided |"] {
        assert!(table.contains(row), "{row} missing from:\n{table}");
    }
    let v: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("animate.json")).unwrap()).unwrap();
    let methods = v["methods"].as_array().unwrap_or_else(|| panic!("{v}"));
    assert_eq!(methods.iter().map(|m| m["method"].as_str().unwrap()).collect::<Vec<_>>(), ["mono", "mbvh", "dacrt"]);
    assert!(v["moving_triangles"].as_u64().unwrap() > 0 && v["rays_per_frame"].as_u64() == Some(1200), "{v}");
    for m in methods {
        let frames = m["frames"]["total_ms"].as_array().unwrap();
        assert_eq!(frames.len(), 2, "every frame's time: {m}");
        let most = frames.iter().map(|t| t.as_f64().unwrap()).fold(0.0, f64::max);
        assert!(m["median_total_ms"].as_f64().unwrap() <= most && most > 0.0, "{m}");
    }
    let o = bench(&["animate", "--frames", "0"], dir.path());
    assert!(!o.status.success() && stderr(&o).contains("--frames"), "{}", stderr(&o));
    let o = bench(&["trace", "--method", "dacrt", "--dacrt-split", "middle"], dir.path());
    assert!(!o.status.success() && stderr(&o).contains("sah, median"), "{}", stderr(&o));
}

/// A stand-in for the Embree harness: logs the `--kinds` it is asked for and prints, in the real harness's
/// format, fixed figures for them.
const FAKE_HARNESS: &str = r###"#!/bin/sh
kinds=all
while [ $# -gt 0 ]; do
  if [ "$1" = "--kinds" ]; then kinds="$2"; fi
  shift
done
echo "$kinds" >> "$0.log"
echo "build HIGH       1 thread(s): median 0.123 s (min 0.100, max 0.200, 1 builds)"
echo "## 16x16  (256 primary rays, 200 hit, checksum sum_t 1.0, mean_t 0.1)"
case "$kinds" in
  primary) echo "CSV,16x16,primary_1,1,256,1.500,1.400,1.600,0.000,1"
           echo "CSV,16x16,primary_8_4x2,1,256,3.000,2.900,3.100,0.000,1" ;;
  shadow) echo "CSV,16x16,shadow_1,1,200,2.500,2.400,2.600,0.000,1"
          echo "CSV,16x16,shadow_8_4x2,1,200,4.000,3.900,4.100,0.000,1" ;;
  diffuse) echo "CSV,16x16,diffuse_1,1,200,0.750,0.700,0.800,0.000,1"
           echo "CSV,16x16,diffuse_1M,1,200,0.800,0.700,0.900,0.000,1" ;;
esac
"###;

#[cfg(unix)]
#[test]
fn compare_takes_turns_with_the_harness_and_reports_its_figures() {
    let dir = tempfile::tempdir().unwrap();
    let extra =
        ["--methods", "mft", "--tiles", "4", "--incoherent", "mbvh-rs", "--rs-groups", "16", "--json", "compare.json"];
    let o = compare_with_fake_harness(dir.path(), FAKE_HARNESS, &extra);
    assert!(o.status.success(), "{}", stderr(&o));
    // Builds first, then one turn per ray kind, in the order raylab measures them.
    let log = std::fs::read_to_string(dir.path().join("embree_bench.log")).unwrap();
    assert_eq!(log, "none\nprimary\nshadow\ndiffuse\n");
    let md = String::from_utf8_lossy(&o.stdout);
    let row = |start: &str| md.lines().find(|l| l.starts_with(start)).unwrap_or_else(|| panic!("no row {start}: {md}"));
    assert!(row("| primary | 1 |").contains("| rtcIntersect1 | 1.50 (1.40-1.60) |"), "{md}");
    assert!(row("| shadow | 1 |").contains("| rtcOccluded1 | 2.50 (2.40-2.60) |"), "{md}");
    assert!(row("| diffuse | 1 |").contains("| rtcIntersect1 | 0.75 (0.70-0.80) |"), "{md}");
    assert!(row("| median of 1 | 1 |").ends_with("| 0.123 |"), "{md}");
    assert!(row("| primary | 1 | mft | 4 |").contains("| primary_8_4x2 | 3.00 |"), "{md}");
    assert!(row("| shadow | 1 | mft | 4 |").contains("| shadow_8_4x2 | 4.00 |"), "{md}");
    assert!(
        row("| mbvh-rs (16) | 1 |").contains("| 0.75 |") && row("| mbvh-rs (16) | 1 |").contains("| 0.80 |"),
        "{md}"
    );
    // Each invocation repeats the primary check; the table lists it once.
    assert_eq!(md.matches("256 primary rays").count(), 1, "{md}");

    // The same comparison as JSON: each configuration beside the Embree row it is compared with.
    let json = std::fs::read(dir.path().join("compare.json")).expect("--json writes its file");
    let v: serde_json::Value = serde_json::from_slice(&json).unwrap();
    let entries = |key: &str| v[key].as_array().unwrap_or_else(|| panic!("{key}: {v}")).clone();
    let kind_of = |e: &serde_json::Value| e["report"]["kind"].as_str().unwrap().to_string();
    assert_eq!(v["embree"]["rows"].as_array().map(Vec::len), Some(6), "{v}");
    assert_eq!(v["embree"]["builds"][0]["seconds"], 0.123);
    let mono = entries("mono");
    assert_eq!(mono.iter().map(kind_of).collect::<Vec<_>>(), ["primary", "shadow", "diffuse"]);
    for e in &mono {
        let ours = e["report"]["mrays_median"].as_f64().unwrap();
        let expected = ours / e["embree"]["median"].as_f64().unwrap();
        assert!((e["ratio"].as_f64().unwrap() - expected).abs() < 1e-9 * expected, "{e}");
    }
    assert_eq!((&mono[1]["embree_api"], &mono[1]["embree"]["kind"]), (&"rtcOccluded1".into(), &"shadow_1".into()));
    let coherent = entries("coherent");
    assert_eq!(coherent.iter().map(kind_of).collect::<Vec<_>>(), ["primary", "shadow"]);
    assert_eq!((&coherent[0]["method"], coherent[0]["tile"].as_u64()), (&"mft".into(), Some(4)));
    assert_eq!(coherent[0]["embree_best"]["kind"], "primary_8_4x2");
    assert_eq!(coherent[1]["embree_best"]["median"], 4.0);
    assert!(coherent[1]["report"]["stats"]["packets"].as_u64().unwrap() > 0, "counters come with each report");
    let incoherent = entries("incoherent");
    assert_eq!((incoherent.len(), &incoherent[0]["method"]), (1, &"mbvh-rs (16)".into()));
    assert_eq!(incoherent[0]["embree_intersect1m"]["median"], 0.8);
}

/// A harness whose primary single-ray figures change from one invocation to the next: medians 1.0, 3.0, then
/// 2.0 Mrays/s, each with a spread of 0.1.
#[cfg(unix)]
const FAKE_DRIFTING_HARNESS: &str = r###"#!/bin/sh
kinds=all
while [ $# -gt 0 ]; do
  if [ "$1" = "--kinds" ]; then kinds="$2"; fi
  shift
done
echo "$kinds" >> "$0.log"
n=$(grep -c primary "$0.log")
echo "build HIGH       1 thread(s): median 0.123 s (min 0.100, max 0.200, 1 builds)"
case "$kinds" in
  primary) case "$n" in
             1) echo "CSV,16x16,primary_1,1,256,1.000,0.900,1.100,0.000,1" ;;
             2) echo "CSV,16x16,primary_1,1,256,3.000,2.900,3.100,0.000,1" ;;
             *) echo "CSV,16x16,primary_1,1,256,2.000,1.900,2.100,0.000,1" ;;
           esac ;;
  shadow) echo "CSV,16x16,shadow_1,1,200,2.500,2.400,2.600,0.000,1" ;;
  diffuse) echo "CSV,16x16,diffuse_1,1,200,0.750,0.700,0.800,0.000,1" ;;
esac
"###;

#[cfg(unix)]
#[test]
fn compare_rounds_repeat_the_turns_and_report_the_median_round() {
    let dir = tempfile::tempdir().unwrap();
    let extra = ["--methods", "frustum", "--tiles", "8", "--incoherent", "mbvh", "--rounds", "3"];
    let o = compare_with_fake_harness(dir.path(), FAKE_DRIFTING_HARNESS, &extra);
    assert!(o.status.success(), "{}", stderr(&o));
    let log = std::fs::read_to_string(dir.path().join("embree_bench.log")).unwrap();
    assert_eq!(log, format!("none\n{}", "primary\nshadow\ndiffuse\n".repeat(3)));
    let md = String::from_utf8_lossy(&o.stdout);
    let rows = |start: &str| md.lines().filter(|l| l.starts_with(start)).collect::<Vec<_>>();
    // The median of the rounds' medians, between the lowest minimum and the highest maximum of all rounds.
    let primary = rows("| primary | 1 | ");
    let mono: Vec<_> = primary.iter().filter(|l| l.contains("rtcIntersect1")).collect();
    assert_eq!(mono.len(), 1, "{md}");
    assert!(mono[0].contains("| rtcIntersect1 | 2.00 (0.90-3.10) |"), "{md}");
    // One row per configuration, however many rounds.
    assert_eq!(rows("| primary | 1 | frustum | 8 |").len(), 1, "{md}");
    assert_eq!(rows("| mbvh | 1 |").len(), 1, "{md}");
}
