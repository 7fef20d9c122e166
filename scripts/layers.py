#!/usr/bin/env python3
"""Checks the workspace's import structure; exits non-zero on a violation.

Two rules:

1. raylab-core's modules form layers (LAYERS, bottom first). A file may use its own layer and the layers
   below it, never one above: the structures know nothing of methods, tracing, shadows or rendering.
2. No cycle of files anywhere in the workspace: no two files use each other, directly or through others.
   A use of an item resolves to the file that defines it (following a module's re-exports). A folder's
   mod.rs and the files directly in that folder are one module (the folder's files implement its types),
   so their uses of each other are not counted; uses between those files, and between modules, are.

Uses are the `crate::`, `super::` and `self::` paths of each file in crates/*/src, outside comments, in
`use` declarations and inline. `#[cfg(test)]` modules count too: a test may not reach upwards either.

Usage: scripts/layers.py [--verbose]
"""

import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

# raylab-core's top-level modules, bottom layer first; a module may use its own layer and those before it.
LAYERS = [
    ("model", {"aabb", "ray", "ray_order", "scene", "stats", "triangle", "intersector", "edge_width"}),
    ("packets and leaf tests", {"packet", "tri4"}),
    ("structures", {"kdtree", "mbvh", "dacrt", "reference"}),
    ("method table", {"method"}),
    ("structure set", {"structures"}),
    ("tracing", {"trace", "workload"}),
    ("shadows", {"shadow"}),
    ("rendering", {"render", "distribution"}),
]

ITEM = re.compile(
    r"^\s*(?:pub(?:\([^)]*\))?\s+)?(?:unsafe\s+)?(?:const\s+fn|fn|struct|enum|trait|type|const|static|union)"
    r"\s+([A-Za-z_][A-Za-z0-9_]*)",
    re.M,
)
MACRO = re.compile(r"macro_rules!\s*([A-Za-z_][A-Za-z0-9_]*)")
PATH = re.compile(r"\b(crate|super|self)((?:::[A-Za-z_][A-Za-z0-9_]*)+)")
USE = re.compile(r"\buse\s+([^;]*);", re.S)


def strip_comments(text):
    text = re.sub(r"/\*.*?\*/", " ", text, flags=re.S)
    text = re.sub(r"//[^\n]*", " ", text)
    return re.sub(r'"(?:\\.|[^"\\])*"', '""', text)


def expand(tree):
    """`a::{b, c::{d, e}}` -> ['a::b', 'a::c::d', 'a::c::e'] (with `self` and globs kept as segments)."""
    tree = re.sub(r"\s+", "", tree)
    depth, i = 0, tree.find("{")
    if i < 0:
        return [tree.split(" as ")[0]]
    prefix, inner = tree[:i], tree[i + 1 : tree.rfind("}")]
    parts, start = [], 0
    for j, ch in enumerate(inner):
        depth += ch == "{"
        depth -= ch == "}"
        if ch == "," and depth == 0:
            parts.append(inner[start:j])
            start = j + 1
    parts.append(inner[start:])
    out = []
    for p in filter(None, parts):
        for e in expand(p):
            out.append(prefix.rstrip(":") if e == "self" else prefix + e)
    return out


class Crate:
    def __init__(self, src):
        self.src = src
        self.files = sorted(src.rglob("*.rs"))
        self.text = {f: strip_comments(f.read_text()) for f in self.files}
        self.items = {f: set(ITEM.findall(t)) | set(MACRO.findall(t)) for f, t in self.text.items()}

    def module_of(self, f):
        rel = f.relative_to(self.src).with_suffix("")
        parts = list(rel.parts)
        if parts[-1] in ("mod", "lib", "main"):
            parts = parts[:-1]
        return parts

    def file_of(self, module):
        for candidate in (self.src.joinpath(*module).with_suffix(".rs"), self.src.joinpath(*module, "mod.rs")):
            if module and candidate in self.text:
                return candidate
        if not module:
            for root in ("lib.rs", "main.rs"):
                if self.src / root in self.text:
                    return self.src / root
        return None

    def resolve(self, path, seen=None):
        """The file defining what `path` (absolute segments) names, or None when it is outside the crate."""
        seen = seen or set()
        for n in range(len(path), -1, -1):
            target = self.file_of(path[:n])
            if target is None:
                continue
            rest = path[n:]
            if not rest or rest[0] in self.items[target] or rest[0] == "*":
                return target
            # A re-export: `pub use x::y::Item;` (or `pub use x::*` holding it) in the module file.
            key = (target, rest[0])
            if key in seen:
                return target
            seen.add(key)
            module = self.module_of(target)
            for use in USE.findall(self.text[target]):
                for full in expand(use):
                    segs = full.split("::")
                    if segs[-1] == rest[0] or segs[-1] == "*":
                        base = self.absolute(module, segs[:-1] if segs[-1] == "*" else segs)
                        if base is None:
                            continue
                        hit = self.resolve(base + (rest if segs[-1] == "*" else rest[1:]), seen)
                        if hit is not None and hit != target:
                            return hit
            return target
        return None

    def absolute(self, module, segs):
        if not segs:
            return None
        head, tail = segs[0], segs[1:]
        if head == "crate":
            return tail
        if head == "self":
            return module + tail
        if head == "super":
            base = list(module)
            while True:
                base = base[:-1]
                if tail and tail[0] == "super":
                    tail = tail[1:]
                    continue
                return base + tail
        # A path relative to this module: one of its child modules, when such a file exists.
        child = module + [head]
        if self.file_of(child) is not None:
            return child + tail
        return None

    def uses(self, f):
        text, module = self.text[f], self.module_of(f)
        paths = set()
        for use in USE.findall(text):
            for full in expand(use):
                paths.add(tuple(full.split("::")))
        for m in PATH.finditer(text):
            paths.add(tuple([m.group(1)] + m.group(2).split("::")[1:]))
        targets = set()
        for p in paths:
            segs = [s for s in p if s]
            if segs and segs[-1] == "*":
                segs = segs[:-1]
            absolute = self.absolute(module, segs)
            if absolute is None:
                continue
            t = self.resolve(absolute)
            if t is not None and t != f and t.name not in ("lib.rs", "main.rs"):
                targets.add(t)
        return targets


def one_module(f, t):
    """True when `t` is the mod.rs of the folder `f` lies directly in."""
    return t.name == "mod.rs" and f.parent == t.parent and f != t


def layer_of(module):
    for i, (_, names) in enumerate(LAYERS):
        if module and module[0] in names:
            return i
    return None


def cycles(graph):
    """Strongly connected components with more than one file (Tarjan)."""
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    sys.setrecursionlimit(10000)
    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def main():
    verbose = "--verbose" in sys.argv
    problems = []
    for src in sorted(ROOT.glob("crates/*/src")):
        crate = Crate(src)
        graph = {f: crate.uses(f) for f in crate.files}
        layered = {f: set(t) for f, t in graph.items()}
        for f, targets in graph.items():
            targets -= {t for t in targets if one_module(f, t) or one_module(t, f)}
        if src.parent.name == "raylab-core":
            for f, targets in layered.items():
                mine = layer_of(crate.module_of(f))
                if mine is None and f.name != "lib.rs":
                    problems.append(f"{f.relative_to(ROOT)}: module not in any layer (add it to LAYERS)")
                for t in sorted(targets):
                    theirs = layer_of(crate.module_of(t))
                    if mine is not None and theirs is not None and theirs > mine:
                        problems.append(
                            f"{f.relative_to(ROOT)} ({LAYERS[mine][0]}) uses {t.relative_to(ROOT)} "
                            f"({LAYERS[theirs][0]}), a layer above it"
                        )
        for comp in cycles(graph):
            names = ", ".join(str(c.relative_to(src)) for c in comp)
            detail = "; ".join(
                f"{a.relative_to(src)} -> {b.relative_to(src)}" for a in comp for b in sorted(graph[a]) if b in comp
            )
            problems.append(f"{src.parent.name}: files that use each other: {names} ({detail})")
        if verbose:
            for f in crate.files:
                print(f.relative_to(ROOT), "->", ", ".join(str(t.relative_to(src)) for t in sorted(graph[f])))
    for p in problems:
        print(p)
    if problems:
        print(f"{len(problems)} import problem(s)", file=sys.stderr)
        return 1
    print("imports: layers respected, no cycles")
    return 0


if __name__ == "__main__":
    sys.exit(main())
