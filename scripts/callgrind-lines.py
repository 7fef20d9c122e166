#!/usr/bin/env python3
"""Attributes a callgrind profile's self cost to raylab's own source lines, following each instruction's chain
of inlined frames: a cost lands on the innermost frame that lies in one of the given path fragments. The
kernels are inlined into one SIMD entry point, so callgrind's own per-function view puts nearly all of their
cost in `run_avx2` and in the intrinsics' source files; this says which raylab line the instructions serve.

    valgrind --tool=callgrind --dump-instr=yes --callgrind-out-file=cg.out --toggle-collect='*run_avx2*' \
        target/release/raylab-bench trace <Sponza flags> --kind primary --method mft --tile 16 --threads 1 \
        --reps 1 --warmup 0 --validate 0
    scripts/callgrind-lines.py cg.out target/release/raylab-bench [FRAGMENT ...]

FRAGMENT defaults to `crates/raylab-core/`. Prints the share of the profile's cost per function (with its
file) for every function with a thousandth of it or more, then for the 40 costliest source lines. Needs
`addr2line` (binutils) and a binary with line tables (the release profile keeps them)."""
import collections
import re
import signal
import subprocess
import sys


def self_costs(path):
    """Self cost per instruction address (the first event), skipping the inclusive costs of call lines."""
    costs = collections.Counter()
    addr = 0
    after_call = False
    with open(path) as f:
        for line in f:
            if line.startswith("calls="):
                after_call = True
                continue
            m = re.match(r"^(0x[0-9a-fA-F]+|[+-](?:0x[0-9a-fA-F]+|\d+)|\*)\s+\S+\s+(\d+)", line)
            if not m:
                continue
            pos = m.group(1)
            if pos.startswith("0x"):
                addr = int(pos, 16)
            elif pos != "*":
                # Relative positions are decimal (or hex with `0x`), signed.
                step = int(pos[1:], 0)
                addr += step if pos[0] == "+" else -step
            if after_call:
                after_call = False
                continue
            costs[addr] += int(m.group(2))
    return costs


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    profile, binary = sys.argv[1], sys.argv[2]
    fragments = sys.argv[3:] or ["crates/raylab-core/"]
    costs = self_costs(profile)
    total = sum(costs.values())
    addrs = sorted(costs)
    out = subprocess.run(
        ["addr2line", "-i", "-f", "-C", "-a", "-e", binary],
        input="\n".join(hex(a) for a in addrs),
        capture_output=True,
        text=True,
        check=True,
    ).stdout.splitlines()
    frames, cur = {}, None
    for row in out:
        if re.match(r"^0x[0-9a-f]+$", row):
            cur = int(row, 16)
            frames[cur] = []
        else:
            frames[cur].append(row)
    by_func, by_line = collections.Counter(), collections.Counter()
    for a in addrs:
        pairs = list(zip(frames.get(a, [])[0::2], frames.get(a, [])[1::2]))
        pick = next(((f, l) for f, l in pairs if any(x in l for x in fragments)), pairs[0] if pairs else ("?", "?"))
        func, loc = pick
        loc = re.sub(r" \(discriminator.*", "", loc)
        for x in fragments:
            if x in loc:
                loc = x + loc.split(x, 1)[1]
        name = re.sub(r"<.*", "", func).split("::")[-1] or func
        by_func[f"{name} ({loc.split(':')[0]})"] += costs[a]
        by_line[loc] += costs[a]
    print(f"total {total:,}")
    # Every function down to a thousandth of the profile, so that sums over a group of them miss little.
    for k, v in by_func.most_common():
        if v * 1000 < total:
            break
        print(f"{100 * v / total:5.1f}% {v:>13,}  {k}")
    print("--- lines")
    for k, v in by_line.most_common(40):
        print(f"{100 * v / total:5.1f}% {v:>13,}  {k}")


signal.signal(signal.SIGPIPE, signal.SIG_DFL)  # quiet when piped into `head`
main()
