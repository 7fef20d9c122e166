#!/usr/bin/env bash
# Regenerates the viewer section of docs/BENCHMARKS.md: frames per second of the `raylab` viewer in a real
# window (under Xvfb when no display is set) on the shared Sponza view, primary rays + hard shadows, with the
# cost of uploading each frame and of the UI. Run it on a committed tree; it needs xvfb-run and a Vulkan driver
# (apt-get install xvfb xauth mesa-vulkan-drivers libvulkan1).
#
#   scripts/viewer-fps.sh               # 60 traced frames per configuration
#   FRAMES=30 scripts/viewer-fps.sh
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
# shellcheck source=lib/splice.sh
source "$root/scripts/lib/splice.sh"
# shellcheck source=lib/cpu.sh
source "$root/scripts/lib/cpu.sh"
frames=${FRAMES:-60}
cargo build --release -p raylab-viewer -p raylab-bench --manifest-path "$root/Cargo.toml"
cd "$root"
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-$(mktemp -d)}
run=()
if [ -z "${DISPLAY:-}" ]; then run=(xvfb-run -a -s "-screen 0 1920x1080x24"); fi

sponza=(--scene ../shared/scenes/sponza/sponza.obj --eye -12.5,2.5,0 --target 10,5.5,0 --up 0,1,0 --fov 65 --light 0,11,0)
work=$(mktemp -d)
table="$work/table.md"
commit=$(git describe --always --dirty --abbrev=12)
cpu=$(cpu_name)
{
  echo "Machine and build: commit $commit, $(rustc --version), CPU $cpu ($(nproc) logical CPUs)."
  echo "Command: \`scripts/viewer-fps.sh\` (FRAMES=$frames): for each row, \`${run[*]} target/release/raylab ${sponza[*]} --width W --height H --method M --tile T --shadows hard --frames $frames --json-stats FILE\`; the panel is shown. Headless FPS: the same frame without a window, \`target/release/raylab-bench render ${sponza[*]} --width W --height H --method M --tile T --shadows hard --frames $frames\` (median frame), run right after the viewer."
  echo
  echo "| view | window | method | tile | FPS (median frame) | frame ms (median) | Mrays/s | N | I | upload CPU ms, mean (wall) | UI CPU ms, mean (wall) | upload + UI CPU ms, median (mean) | UI frames/s | UI frames / egui draws | headless FPS (median frame) |"
  echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
} > "$table"
for size in 1280x720 512x512; do
  for cfg in mft:8 mft:16 mft:32 frustum:16 packet:16 mono:16; do
    method=${cfg%%:*}; tile=${cfg##*:}
    w=${size%%x*}; h=${size##*x}
    stats="$work/$method-$tile-$size.json"
    "${run[@]}" target/release/raylab "${sponza[@]}" --width "$w" --height "$h" --method "$method" --tile "$tile" \
      --shadows hard --frames "$frames" --json-stats "$stats" >/dev/null
    headless=$(target/release/raylab-bench render "${sponza[@]}" --width "$w" --height "$h" --method "$method" \
      --tile "$tile" --shadows hard --frames "$frames" --out "$work/headless.png" \
      | sed -n 's/^[0-9]* frames: median [0-9.]* ms (\([0-9.]*\) FPS).*/\1/p')
    python3 - "$stats" "$size" "$method" "$tile" "$frames" "$headless" >> "$table" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
r = s["readouts"]
draws = s["ui_layer_draws"]
ui_s = r["frame_ms_mean"] * r["frames"] / 1e3
print(f"| Sponza | {sys.argv[2]} | {sys.argv[3]} | {sys.argv[4]} | {r['fps_median']:.1f} | {r['frame_ms_median']:.1f} "
      f"| {r['mrays_per_s']:.2f} | {r['n']:.2f} | {r['i']:.2f} "
      f"| {r['upload_ms_mean']:.2f} ({r['upload_wall_ms_mean']:.2f}) | {r['ui_ms_mean']:.2f} ({r['ui_wall_ms_mean']:.2f}) "
      f"| {r['upload_and_ui_ms_median']:.2f} ({r['upload_ms_mean'] + r['ui_ms_mean']:.2f}) "
      f"| {r['ui_frames'] / ui_s:.0f} | {r['ui_frames']} / {draws} | {sys.argv[6]} |")
PY
  done
done
{
  echo
  echo 'UI responsiveness while tracing (`--redraw-always`: the UI redraws as often as it can, up to 60 FPS, instead of only on input and new frames; lavapipe draws each UI frame on the same two cores):'
  echo
  echo "| view | window | method | tile | UI FPS while tracing | UI CPU ms, median / mean (mean wall) | UI frames / egui draws | traced FPS meanwhile |"
  echo "|---|---|---|---|---|---|---|---|"
} >> "$table"
stats="$work/ui.json"
"${run[@]}" target/release/raylab "${sponza[@]}" --width 1280 --height 720 --method mft --tile 16 --shadows hard \
  --frames 20 --redraw-always --json-stats "$stats" >/dev/null
python3 - "$stats" >> "$table" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
r = s["readouts"]
ui_s = r["frame_ms_mean"] * r["frames"] / 1e3
print(f"| Sponza | 1280x720 | mft | 16 | {r['ui_frames'] / ui_s:.0f} | {r['ui_ms_median']:.2f} / {r['ui_ms_mean']:.2f} ({r['ui_wall_ms_mean']:.2f}) "
      f"| {r['ui_frames']} / {s['ui_layer_draws']} | {r['fps_median']:.1f} |")
PY
echo >> "$table"
echo "GPU: $(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['gpu'])" "$stats")." >> "$table"

splice_section viewer-fps "$table"
python3 scripts/targets.py
rm -rf "$work"
echo "updated docs/BENCHMARKS.md"
