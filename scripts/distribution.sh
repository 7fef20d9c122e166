#!/usr/bin/env bash
# Regenerates the distribution section of docs/BENCHMARKS.md: the MBVH RS paper's workload (16 glossy paths per
# pixel) as its Figures 2-8, with `raylab-bench distribution`: on the shared Sponza view (the paper's Conference
# stand-in) Mrays/s per bounce for kd-tree mono, 2x2 packets, MBVH single rays and MBVH RS, the counters per
# bounce for reflection and shadow rays, and an MBVH RS group-size sweep; then the speeds per bounce of MBVH and
# MBVH RS on each built-in scene (Figure 2's several scenes). Run it on a committed tree.
#
#   scripts/distribution.sh             # Sponza 256x256, 7 bounces; built-in scenes 128x128, 3 bounces; 1 thread
#   SIZE=512 BOUNCES=3 scripts/distribution.sh
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
# shellcheck source=lib/splice.sh
source "$root/scripts/lib/splice.sh"
size=${SIZE:-256}
bounces=${BOUNCES:-7}
scene_size=${SCENE_SIZE:-128}
cargo build --release -p raylab-bench --manifest-path "$root/Cargo.toml"

cd "$root"
mkdir -p target/bench
table=$(mktemp)
target/release/raylab-bench distribution --scene ../shared/scenes/sponza/sponza.obj --eye -12.5,2.5,0 \
  --target 10,5.5,0 --up 0,1,0 --fov 65 --light 0,11,0 --width "$size" --height "$size" --bounces "$bounces" \
  --threads 1 --groups 1,2,8,16 --markdown "$table" --json target/bench/distribution.json
for scene in atrium kitchen arena forest; do
  part=$(mktemp)
  target/release/raylab-bench distribution --scene "$scene" --methods mbvh,mbvh-rs --width "$scene_size" \
    --height "$scene_size" --bounces 3 --threads 1 --speeds-only --markdown "$part"
  { echo; echo "Command: \`$(sed -n 's/^Command: `\(.*\)`$/\1/p' "$part")\`"; echo; sed -n '/^\*\*Figure 2\*\*/,$p' "$part"; } >>"$table"
  rm -f "$part"
done

splice_section distribution "$table"
rm -f "$table"
echo "updated docs/BENCHMARKS.md"
