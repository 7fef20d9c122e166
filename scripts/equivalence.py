#!/usr/bin/env python3
"""Record what raylab traces, so that a refactoring can show it changed nothing.

`run` renders every method on every built-in scene (each of its named views) and on the shared Sponza view, then,
on the atrium, every shadow technique and bound, every heat map and debug view, every SIMD backend, every ray order
and the method options; it also runs `trace --json` for every method, ray kind and scene. The manifest it writes
holds, per case, the PNG's SHA-256 and every count of the JSON report (counters, hits, checksums), with the
timings, machine and paths left out.

`compare` diffs two manifests and exits non-zero on any difference.

    scripts/equivalence.py run --bench /tmp/before/raylab-bench --out /tmp/before.json
    scripts/equivalence.py run --bench target/release/raylab-bench --out /tmp/after.json
    scripts/equivalence.py compare /tmp/before.json /tmp/after.json
"""

import argparse
import concurrent.futures
import hashlib
import json
import os
import subprocess
import sys
import tempfile

METHODS = ["mono", "packet", "frustum", "mft", "cone", "mft-cone", "mbvh", "mbvh-rs", "dacrt", "reference"]
BUILTIN = ["atrium", "arena", "kitchen", "forest"]
SHADOWS = ["none", "hard", "cached", "edge", "ms4", "ms8", "ms16", "ms32"]
MS_BOUNDS = ["packets", "fitted", "pyramid", "cone"]
SHOWS = ["shaded", "nodes", "isects", "normals", "depth"]
BACKENDS = ["avx512", "avx2", "sse2", "scalar"]
ORDERS = ["scanline", "morton", "hilbert"]
KINDS = ["primary", "shadow", "diffuse"]

SPONZA = "../shared/scenes/sponza/sponza.obj"
SPONZA_VIEW = ["--eye", "-12.5,2.5,0", "--target", "10,5.5,0", "--up", "0,1,0", "--fov", "65", "--light", "0,11,0"]

# Report fields that are timings, rates of timings, the machine or a path: they differ from run to run.
VOLATILE = {"fps", "frame_seconds", "kd_build_seconds", "load_seconds", "build_seconds", "mrays_per_second",
            "mrays_max", "mrays_median", "mrays_min", "environment", "out"}


def stable(value):
    """The JSON report without its volatile fields (of the stage timings, only the test counts stay)."""
    if isinstance(value, dict):
        kept = {}
        for k, v in value.items():
            if k in VOLATILE or (k.endswith("seconds") and not isinstance(v, dict)):
                continue
            if k == "stages_seconds":
                v = {stage: n for stage, n in v.items() if stage.endswith("_tests")}
            kept[k] = stable(v)
        return kept
    if isinstance(value, list):
        return [stable(v) for v in value]
    return value


def named_views(bench, scene):
    info = subprocess.run([bench, "info", "--scene", scene], capture_output=True, text=True, check=True).stdout
    for line in info.splitlines():
        if line.startswith("views"):
            return line.split(None, 1)[1].replace(" ", "").split(",")
    return [None]


def scene_args(scene, view):
    if scene == "sponza":
        return ["--scene", SPONZA, *SPONZA_VIEW]
    return ["--scene", scene] + (["--view", view] if view else [])


def cases(bench, size):
    """(key, command arguments) for every case."""
    geometry = ["--width", str(size), "--height", str(size)]
    scenes = [(s, v) for s in BUILTIN for v in named_views(bench, s)] + [("sponza", None)]
    out = []
    for scene, view in scenes:
        for method in METHODS:
            key = f"render/{scene}/{view}/{method}"
            out.append((key, ["render", *scene_args(scene, view), *geometry, "--method", method]))
    atrium = scene_args("atrium", None)
    for method in METHODS:
        base = ["render", *atrium, *geometry, "--method", method]
        for shadows in SHADOWS:
            out.append((f"render/atrium/shadows={shadows}/{method}", [*base, "--shadows", shadows]))
        for bound in MS_BOUNDS:
            out.append((f"render/atrium/ms8-bound={bound}/{method}", [*base, "--shadows", "ms8", "--ms-bound", bound]))
        out.append((f"render/atrium/edge-leak-fix/{method}", [*base, "--shadows", "edge", "--leak-fix"]))
        for show in SHOWS:
            out.append((f"render/atrium/show={show}/{method}", [*base, "--show", show]))
        for backend in BACKENDS:
            out.append((f"render/atrium/backend={backend}/{method}", [*base, "--backend", backend]))
        for order in ORDERS:
            out.append((f"render/atrium/order={order}/{method}", [*base, "--order", order]))
        for tile in ["8", "32"]:
            out.append((f"render/atrium/tile={tile}/{method}", [*base, "--tile", tile]))
        out.append((f"render/atrium/no-cull/{method}", [*base, "--no-cull"]))
        out.append((f"render/atrium/depth=0/{method}", [*base, "--depth", "0"]))
    extra = {
        "mbvh-rs": [["--no-stream-order"], ["--stream-leaves", "packets"]],
        "dacrt": [["--dacrt-split", "median"], ["--dacrt-leaf-rays", "4", "--dacrt-leaf-tris", "16"]],
    }
    for method, variants in extra.items():
        for variant in variants:
            name = "".join(variant).replace("--", "+")
            out.append((f"render/atrium/{name}/{method}", ["render", *atrium, *geometry, "--method", method, *variant]))
    trace_scenes = [(s, None) for s in BUILTIN] + [("sponza", None)]
    for scene, view in trace_scenes:
        for kind in KINDS:
            for method in METHODS:
                args = ["trace", *scene_args(scene, view), *geometry, "--kind", kind, "--method", method]
                args += ["--validate", "0", "--reps", "1", "--warmup", "0"]
                out.append((f"trace/{scene}/{kind}/{method}", args))
                if method == "mbvh-rs":
                    out.append((f"trace/{scene}/{kind}/{method}/group=16", [*args, "--group", "16"]))
        for backend in BACKENDS:
            for method in METHODS:
                args = ["trace", *scene_args(scene, view), *geometry, "--kind", "shadow", "--method", method]
                args += ["--validate", "0", "--reps", "1", "--warmup", "0", "--backend", backend]
                out.append((f"trace/{scene}/shadow/{method}/backend={backend}", args))
    return out


def run_case(bench, key, args, workdir):
    png = os.path.join(workdir, hashlib.sha1(key.encode()).hexdigest() + ".png")
    command = [bench, *args, "--threads", "1", "--json"]
    if args[0] == "render":
        command += ["--out", png]
    proc = subprocess.run(command, capture_output=True, text=True)
    if proc.returncode != 0:
        return key, {"error": proc.stderr.strip()}
    record = {"report": stable(json.loads(proc.stdout))}
    if args[0] == "render":
        with open(png, "rb") as f:
            record["png_sha256"] = hashlib.sha256(f.read()).hexdigest()
        os.remove(png)
    return key, record


def run(options):
    bench = os.path.abspath(options.bench)
    todo = cases(bench, options.size)
    manifest = {}
    with tempfile.TemporaryDirectory() as workdir, concurrent.futures.ThreadPoolExecutor(options.jobs) as pool:
        futures = [pool.submit(run_case, bench, key, args, workdir) for key, args in todo]
        for i, future in enumerate(concurrent.futures.as_completed(futures), 1):
            key, record = future.result()
            manifest[key] = record
            if i % 50 == 0 or i == len(todo):
                print(f"{i}/{len(todo)}", file=sys.stderr)
    with open(options.out, "w") as f:
        json.dump(dict(sorted(manifest.items())), f, indent=1)
    errors = sum("error" in r for r in manifest.values())
    print(f"{len(manifest)} cases ({errors} refused by the CLI) -> {options.out}")


def flatten(value, prefix=""):
    if isinstance(value, dict):
        for k, v in value.items():
            yield from flatten(v, f"{prefix}.{k}" if prefix else k)
    elif isinstance(value, list):
        for i, v in enumerate(value):
            yield from flatten(v, f"{prefix}[{i}]")
    else:
        yield prefix, value


def compare(options):
    with open(options.before) as f:
        before = json.load(f)
    with open(options.after) as f:
        after = json.load(f)
    ignore = set(options.ignore or [])
    differences = 0
    for key in sorted(set(before) | set(after)):
        if key not in before or key not in after:
            print(f"{key}: only in {'after' if key not in before else 'before'}")
            differences += 1
            continue
        a = dict(flatten(before[key]))
        b = dict(flatten(after[key]))
        for field in sorted(set(a) | set(b)):
            if any(part.split("[")[0] in ignore for part in field.split(".")):
                continue
            if a.get(field) != b.get(field):
                print(f"{key}: {field}: {a.get(field)!r} -> {b.get(field)!r}")
                differences += 1
    print(f"{len(before)} cases before, {len(after)} after, {differences} differences")
    return 1 if differences else 0


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run", help="render and trace every case, write a manifest")
    r.add_argument("--bench", default="target/release/raylab-bench")
    r.add_argument("--out", required=True)
    r.add_argument("--size", type=int, default=48, help="image edge in pixels")
    r.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    c = sub.add_parser("compare", help="diff two manifests")
    c.add_argument("before")
    c.add_argument("after")
    c.add_argument("--ignore", action="append", help="a report field left out of the comparison, with all below it")
    options = parser.parse_args()
    if options.command == "run":
        run(options)
        return 0
    return compare(options)


if __name__ == "__main__":
    sys.exit(main())
