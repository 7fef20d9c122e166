#!/usr/bin/env bash
# Regenerates the hybrid-mode section of docs/BENCHMARKS.md (seed 003, Stokes 2014, Figures 8-10): the viewer
# offscreen in hybrid mode (GPU G-buffer, CPU reflections, GPU composite) at 1280x720, median milliseconds per
# stage over FRAMES frames, (a) against the G-buffer resolution, (b) against the triangle count (the built-in
# scenes and the shared Sponza, each with the animation's moving mirror and ball), (c) with synchronous and asynchronous readback and with interlacing. Run it on
# a committed tree; it needs a Vulkan driver (apt-get install mesa-vulkan-drivers libvulkan1).
#
#   scripts/hybrid.sh                 # 40 frames per row
#   FRAMES=20 scripts/hybrid.sh
#
# On a machine without Rust (a lent GPU machine) with a prebuilt target/release/raylab:
#   SKIP_BUILD=1 COMMIT=abc123 SECTION=hybrid-gpu scripts/hybrid.sh
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
# shellcheck source=lib/splice.sh
source "$root/scripts/lib/splice.sh"
# shellcheck source=lib/cpu.sh
source "$root/scripts/lib/cpu.sh"
frames=${FRAMES:-40}
section=${SECTION:-hybrid}
[ -n "${SKIP_BUILD:-}" ] || cargo build --release -p raylab-viewer --manifest-path "$root/Cargo.toml"
cd "$root"
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-$(mktemp -d)}
work=$(mktemp -d)
table="$work/table.md"
commit=${COMMIT:-$(git describe --always --dirty --abbrev=12)}
toolchain=$(rustc --version 2>/dev/null || echo "binary built elsewhere")
gpus="$work/gpus"
cpu=$(cpu_name)
sponza=(--scene ../shared/scenes/sponza/sponza.obj --eye -12.5,2.5,0 --target 10,5.5,0 --up 0,1,0 --fov 65 --light 0,11,0)
{
  echo "Machine and build: commit $commit, $toolchain, CPU $cpu ($(nproc) logical CPUs), GPU GPU_NAMES."
  echo "Command: \`scripts/hybrid.sh\` (FRAMES=$frames): for each row, \`target/release/raylab --headless --mode hybrid --width 1280 --height 720 --no-panel --frames $frames --json-stats FILE\` with the row's flags; medians over the frames. CPU part = raster (record and submit) + readback + trace."
  echo
  echo "| part | scene | triangles | G-buffer | readback | interlace | reflection method | reflective px | rays | raster ms | readback ms | trace ms | upload ms | composite ms | CPU part ms | frame period ms |"
  echo "|---|---|---:|---|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
} > "$table"
row() {
  local part=$1; shift
  local stats="$work/run.json"
  target/release/raylab --headless --mode hybrid --width 1280 --height 720 --no-panel --frames "$frames" \
    --json-stats "$stats" "$@" > /dev/null
  python3 - "$stats" "$part" "$gpus" >> "$table" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
h, s = d["hybrid"], d["settings"]["hybrid"]
print(d["gpu"], file=open(sys.argv[3], "a"))
m = h["medians"]["stage_ms_median"]
med = h["medians"]
print(f"| {sys.argv[2]} | {d['scene']} | {d['triangles']} | {s['gbuffer_percent']}% ({h['gbuffer'][0]}x{h['gbuffer'][1]}) "
      f"| {'async' if s['async_readback'] else 'sync'} | {s['interlace']} | {s['method']} | {h['reflective_pixels']} | {h['rays']} "
      f"| {m[0]:.2f} | {m[1]:.2f} | {m[2]:.2f} | {m[3]:.2f} | {m[4]:.2f} | {med['cpu_ms_median']:.2f} | {med['period_ms_median']:.2f} |")
PY
}
for pct in 25 50 100; do row "(a) resolution" --scene atrium --gbuffer-percent "$pct"; done
# The animation adds a spinning mirror and a bouncing ball to every scene, so each has reflections in view.
for scene in arena kitchen atrium forest; do row "(b) triangles" --scene "$scene" --animate; done
row "(b) triangles" "${sponza[@]}" --animate
row "(c) readback" --scene atrium --sync-readback
row "(c) readback" --scene atrium
for k in 2 4; do row "(c) interlacing" --scene atrium --interlace "$k"; done
for m in mono mbvh; do row "(c) method" --scene atrium --hybrid-method "$m"; done

# The adapter each run reported (lavapipe is Mesa's software Vulkan, on the same CPU as the tracer).
sed -i "s|GPU_NAMES|$(sort -u "$gpus" | paste -sd ';' | sed 's/[|&]/\\&/g')|" "$table"
splice_section "$section" "$table"
rm -rf "$work"
echo "updated docs/BENCHMARKS.md"
