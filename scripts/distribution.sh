#!/usr/bin/env bash
# Regenerates the distribution section of docs/BENCHMARKS.md: the MBVH RS paper's workload (16 glossy paths per
# pixel) on the shared Sponza view, Mrays/s per bounce for kd-tree mono, 2x2 packets, MBVH single rays and MBVH
# RS, the MBVH counters, and an MBVH RS group-size sweep, with `raylab-bench distribution`. Run it on a committed
# tree.
#
#   scripts/distribution.sh             # 256x256, 3 bounces, 1 thread
#   SIZE=512 BOUNCES=7 scripts/distribution.sh
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
# shellcheck source=lib/splice.sh
source "$root/scripts/lib/splice.sh"
size=${SIZE:-256}
bounces=${BOUNCES:-3}
cargo build --release -p raylab-bench --manifest-path "$root/Cargo.toml"

cd "$root"
table=$(mktemp)
target/release/raylab-bench distribution --scene ../shared/scenes/sponza/sponza.obj --eye -12.5,2.5,0 \
  --target 10,5.5,0 --up 0,1,0 --fov 65 --light 0,11,0 --width "$size" --height "$size" --bounces "$bounces" \
  --threads 1 --groups 1,2,8,16 --markdown "$table"

splice_section distribution "$table"
rm -f "$table"
echo "updated docs/BENCHMARKS.md"
