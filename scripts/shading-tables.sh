#!/usr/bin/env bash
# Regenerates the shading-tables section of docs/BENCHMARKS.md: thesis Tables 5.1 (FPS per shadow technique),
# 4.6 (16 samples bounded by cones, pyramids or packets), 3.1 (stage shares) and the soft-shadow image-quality
# table, for the atrium and the shared Sponza view, with `raylab-bench tables --part shading`; the images go
# to docs/images/shadows/. Run it on a committed tree.
#
#   scripts/shading-tables.sh            # 512x512, 2 threads, median of 5 frames, quality at 256x256
#   REPS=3 scripts/shading-tables.sh
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
# shellcheck source=lib/splice.sh
source "$root/scripts/lib/splice.sh"
reps=${REPS:-5}
cargo build --release -p raylab-bench --manifest-path "$root/Cargo.toml"

cd "$root"
mkdir -p target/bench
table=$(mktemp)
target/release/raylab-bench tables --part shading --scene ../shared/scenes/sponza/sponza.obj --eye -12.5,2.5,0 \
  --target 10,5.5,0 --up 0,1,0 --fov 65 --light 0,11,0 --threads 2 --reps "$reps" \
  --images docs/images/shadows --markdown "$table" --json target/bench/shading-tables.json

splice_section shading-tables "$table"
python3 scripts/targets.py
rm -f "$table"
echo "updated docs/BENCHMARKS.md"
