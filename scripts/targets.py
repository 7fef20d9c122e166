#!/usr/bin/env python3
"""Writes the "targets" section of docs/BENCHMARKS.md: each benchmark target of the issues beside the figure
measured for it, read from the tables the benchmark scripts wrote (never typed), with the commit of the
table it comes from.

    python3 scripts/targets.py           # rewrites the section in place
    python3 scripts/targets.py --check   # exits 1 when the section differs from what the tables give

The benchmark scripts run it after splicing their own table, so the summary follows every new table; CI runs
it with --check, so the summary cannot be edited by hand.
"""

import re
import sys
from pathlib import Path

DOC = Path(__file__).resolve().parent.parent / "docs" / "BENCHMARKS.md"


def section(text, name):
    """The lines between <!-- name:begin --> and <!-- name:end -->."""
    m = re.search(rf"<!-- {name}:begin -->\n(.*?)<!-- {name}:end -->", text, re.S)
    if not m:
        sys.exit(f"docs/BENCHMARKS.md: no section '{name}'")
    return m.group(1).split("\n")


def commit(lines):
    """The commit named by a section's "Machine and build" line."""
    for line in lines:
        m = re.match(r"Machine and build: commit (\S+?),", line)
        if m:
            return m.group(1)[:7]
    sys.exit("docs/BENCHMARKS.md: a table section names no commit")


def tables(lines):
    """Every markdown table in `lines`, as (header cells, [row cells])."""
    out, cur = [], None
    for line in lines:
        if line.startswith("|"):
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            if cur is None:
                cur = (cells, [])
            elif not all(re.fullmatch(r":?-+:?", c) for c in cells):
                cur[1].append(cells)
        elif cur is not None:
            out.append(cur)
            cur = None
    if cur is not None:
        out.append(cur)
    return out


def table_with(lines, first_cells):
    """The rows, as dicts by header, of the table whose header starts with `first_cells`."""
    for head, rows in tables(lines):
        if head[: len(first_cells)] == first_cells:
            return [dict(zip(head, r)) for r in rows]
    sys.exit(f"docs/BENCHMARKS.md: no table with columns {first_cells}")


def num(cell):
    """The first number of a cell ("22.47 (21.91-22.85)", "1.05x", "71.9%")."""
    m = re.match(r"-?[0-9.]+", cell)
    if not m:
        sys.exit(f"docs/BENCHMARKS.md: '{cell}' is not a number")
    return float(m.group(0))


def best(rows, **match):
    """The row with the highest Mrays/s among `rows` whose cells equal `match`."""
    rows = [r for r in rows if all(r[k] == v for k, v in match.items())]
    if not rows:
        sys.exit(f"docs/BENCHMARKS.md: no row with {match}")
    return max(rows, key=lambda r: num(r["Mrays/s (min-max)"]))


def verdict(value, goal, at_least):
    return "met" if (value >= goal if at_least else value <= goal) else "**not met**"


def threads_label(threads):
    return "1 thread" if threads == "1" else f"{threads} threads"


def embree_rows(text):
    lines = section(text, "mono-vs-embree")
    c = commit(lines)
    rows = table_with(lines, ["rays", "threads", "method", "tile"])
    out = []
    # Against Embree: the best ratio among the methods named, each at its best tile.
    for rays, methods, what in (
        ("primary", ("mft",), "primary rays, MFT at its best tile against Embree's best coherent API"),
        ("shadow", ("frustum", "mft"),
         "hard-shadow rays, the better of frustum and MFT at its best tile against Embree's best occlusion API"),
    ):
        for threads in ("1", "2"):
            s = max((best(rows, rays=rays, threads=threads, method=m) for m in methods),
                    key=lambda x: num(x["raylab / Embree"]))
            r = num(s["raylab / Embree"])
            out.append((
                "4",
                f"{what}, {threads_label(threads)}",
                ">= 1.5x",
                f"{r:.2f}x ({s['method']} {s['tile']}: {num(s['Mrays/s (min-max)']):.2f} against "
                f"{s['Embree best']} {num(s['Embree Mrays/s']):.2f} Mrays/s)",
                f"Embree table, {c}",
                verdict(r, 1.5, True),
            ))
    for threads in ("1", "2"):
        m = best(rows, rays="primary", threads=threads, method="mft")
        f = best(rows, rays="primary", threads=threads, method="frustum")
        r = num(m["Mrays/s (min-max)"]) / num(f["Mrays/s (min-max)"])
        out.append((
            "4",
            f"primary rays, MFT against the single frustum, each at its best tile, {threads_label(threads)}",
            ">= 1.1x",
            f"{r:.2f}x (mft {m['tile']} {num(m['Mrays/s (min-max)']):.2f}, frustum {f['tile']} "
            f"{num(f['Mrays/s (min-max)']):.2f} Mrays/s)",
            f"Embree table, {c}",
            verdict(r, 1.1, True),
        ))
    return out


def thesis_rows(text):
    lines = section(text, "thesis-tables")
    c = commit(lines)
    t41 = {r["scene"]: r for r in table_with(lines, ["scene", "packet 2x2 FPS"])}
    t44 = {r["scene"]: r for r in table_with(lines, ["scene", "MFT FPS", "MFT tile"])}
    if "sponza" not in t41 or "sponza" not in t44:
        sys.exit("docs/BENCHMARKS.md: the thesis tables have no Sponza row")
    s41, s44 = t41["sponza"], t44["sponza"]
    mft = num(s44["MFT FPS"])
    frustums = {k.split()[1]: num(v) for k, v in s41.items() if k.startswith("frustum ") and k.endswith(" FPS")}
    tile, frustum = max(frustums.items(), key=lambda kv: kv[1])
    packets = num(s41["packet 2x2 FPS"])
    return [
        (
            "4",
            "Sponza, MFT against the single frustum, each at its best tile (thesis Tables 4.1 and 4.4)",
            ">= 1.1x",
            f"{mft / frustum:.2f}x (mft {s44['MFT tile']} {mft:.1f} FPS, frustum {tile} {frustum:.1f})",
            f"thesis tables, {c}",
            verdict(mft / frustum, 1.1, True),
        ),
        (
            "4",
            "Sponza, MFT at its best tile against 2x2 packets (thesis Tables 4.1 and 4.4)",
            ">= 1.8x",
            f"{mft / packets:.2f}x (mft {s44['MFT tile']} {mft:.1f} FPS, 2x2 packets {packets:.1f})",
            f"thesis tables, {c}",
            verdict(mft / packets, 1.8, True),
        ),
    ]


def shading_rows(text):
    lines = section(text, "shading-tables")
    c = commit(lines)
    out = []
    for r in table_with(lines, ["scene", "none", "hard"]):
        v = num(r["edge / hard time"])
        out.append((
            "5",
            f"{r['scene']}, edge-width frame time against the hard-shadow frame (Table 5.1)",
            "<= 1.3x",
            f"{v:.2f}x ({r['edge width']} against {r['hard']} FPS)",
            f"shading tables, {c}",
            verdict(v, 1.3, False),
        ))
    rows = table_with(lines, ["scene", "light radius", "bound"])
    for r in rows:
        if r["bound"] != "pyramid":
            continue
        cone = next((x for x in rows if x["scene"] == r["scene"] and x["light radius"] == r["light radius"]
                     and x["bound"] == "cone"), None)
        if cone is None:
            sys.exit(f"docs/BENCHMARKS.md: Table 4.6 has no cone row for {r['scene']} at radius {r['light radius']}")
        v = num(r["cone speed-up"])
        out.append((
            "5",
            f"{r['scene']}, light radius {r['light radius']}: 16 samples bounded by the cone against the "
            "pyramid (Table 4.6)",
            ">= 1.3x",
            f"{v:.2f}x ({cone['FPS']} against {r['FPS']} FPS)",
            f"shading tables, {c}",
            verdict(v, 1.3, True),
        ))
    return out


def viewer_rows(text):
    lines = section(text, "viewer-fps")
    c = commit(lines)
    rows = table_with(lines, ["view", "window", "method", "tile", "FPS (median frame)"])
    out = []
    for window, goal in (("1280x720", 30.0), ("512x512", 100.0)):
        m = max((r for r in rows if r["window"] == window and r["method"] == "mft"),
                key=lambda r: num(r["FPS (median frame)"]))
        v = num(m["FPS (median frame)"])
        out.append((
            "7",
            f"viewer, Sponza at {window}, primary rays and hard shadows, MFT at its best tile",
            f">= {goal:.0f} FPS",
            f"{v:.1f} FPS (mft {m['tile']}; headless {m['headless FPS (median frame)']})",
            f"viewer table, {c}",
            verdict(v, goal, True),
        ))
    big = [r for r in rows if r["window"] == "1280x720"]
    worst = max(big, key=lambda r: num(r["upload + UI CPU ms, median (mean)"]))
    v = num(worst["upload + UI CPU ms, median (mean)"])
    out.append((
        "7",
        "viewer, upload and UI CPU time per frame at 1280x720 (median frame, the costliest row)",
        "<= 2 ms",
        f"{v:.2f} ms ({worst['method']} {worst['tile']})",
        f"viewer table, {c}",
        verdict(v, 2.0, False),
    ))
    ui = table_with(lines, ["view", "window", "method", "tile", "UI FPS while tracing"])
    v = min(num(r["UI FPS while tracing"]) for r in ui)
    out.append((
        "7",
        "viewer, UI frames per second while tracing",
        ">= 30",
        f"{v:.0f}",
        f"viewer table, {c}",
        verdict(v, 30.0, True),
    ))
    return out


def summary(text):
    rows = embree_rows(text) + thesis_rows(text) + shading_rows(text) + viewer_rows(text)
    out = [
        "Written by `scripts/targets.py` from the tables below (each row names the table and its commit).",
        "",
        "| issue | target | goal | measured | from | |",
        "|---|---|---|---|---|---|",
    ]
    out += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(out) + "\n"


def main():
    check = sys.argv[1:] == ["--check"]
    if sys.argv[1:] not in ([], ["--check"]):
        sys.exit("usage: scripts/targets.py [--check]")
    text = DOC.read_text()
    new_block = summary(text)
    m = re.search(r"(<!-- targets:begin -->\n)(.*?)(<!-- targets:end -->)", text, re.S)
    if not m:
        sys.exit("docs/BENCHMARKS.md: no section 'targets'")
    if check:
        if m.group(2) != new_block:
            sys.exit("docs/BENCHMARKS.md: the targets section differs from the tables; run scripts/targets.py")
        return
    DOC.write_text(text[: m.start(2)] + new_block + text[m.end(2):])


if __name__ == "__main__":
    main()
