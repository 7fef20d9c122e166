#!/usr/bin/env bash
# Builds the Embree harness from ../shared/tools/embree-bench (needs g++ and libembree-dev) and regenerates the
# single-ray table of docs/BENCHMARKS.md with `raylab-bench compare`, which runs Embree and raylab on the same
# OBJ, view, light and rays in one invocation. Run it on a committed tree: the table records the commit. The
# same figures, counters included, go to target/bench/compare.json for scripts and plots.
#
#   scripts/bench-vs-embree.sh            # 512x512, threads 1 and 2, 7 rounds of 5 timed runs each
#   REPS=3 ROUNDS=5 scripts/bench-vs-embree.sh
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
# shellcheck source=lib/splice.sh
source "$root/scripts/lib/splice.sh"
shared=${SHARED:-$root/../shared}
reps=${REPS:-5}
rounds=${ROUNDS:-7}
harness=$root/target/embree-bench
mkdir -p "$harness"
cp "$shared/tools/embree-bench/embree_bench.cpp" "$shared/tools/embree-bench/Makefile" "$harness/"
make -s -C "$harness" embree_bench
cargo build --release -p raylab-bench --manifest-path "$root/Cargo.toml"

cd "$root"
mkdir -p target/bench
table=$(mktemp)
target/release/raylab-bench compare --embree target/embree-bench/embree_bench \
  --scene ../shared/scenes/sponza/sponza.obj --eye -12.5,2.5,0 --target 10,5.5,0 --up 0,1,0 --fov 65 \
  --light 0,11,0 --width 512 --height 512 --threads 1,2 --reps "$reps" --rounds "$rounds" --warmup 1 --builds 3 --markdown "$table" \
  --json target/bench/compare.json

# Replace the text between the markers in docs/BENCHMARKS.md with the fresh table.
splice_section mono-vs-embree "$table"
python3 scripts/targets.py
rm -f "$table"
echo "updated docs/BENCHMARKS.md"
