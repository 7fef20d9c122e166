#!/usr/bin/env bash
# Regenerates the thesis-tables section of docs/BENCHMARKS.md: Tables 4.1-4.5 (FPS, N, I per method and tile)
# for the built-in scenes and the shared Sponza view, with `raylab-bench tables`. Run it on a committed tree.
#
#   scripts/thesis-tables.sh            # 512x512, 2 threads, median of 5 frames
#   REPS=3 scripts/thesis-tables.sh
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
# shellcheck source=lib/splice.sh
source "$root/scripts/lib/splice.sh"
reps=${REPS:-5}
cargo build --release -p raylab-bench --manifest-path "$root/Cargo.toml"

cd "$root"
mkdir -p target/bench
table=$(mktemp)
target/release/raylab-bench tables --part primary --scene ../shared/scenes/sponza/sponza.obj --eye -12.5,2.5,0 \
  --target 10,5.5,0 --up 0,1,0 --fov 65 --light 0,11,0 --threads 2 --reps "$reps" --markdown "$table" \
  --json target/bench/thesis-tables.json

splice_section thesis-tables "$table"
python3 scripts/targets.py
rm -f "$table"
echo "updated docs/BENCHMARKS.md"
