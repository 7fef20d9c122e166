#!/usr/bin/env bash
# Regenerates the dynamic-geometry section of docs/BENCHMARKS.md with `raylab-bench animate`: a spinning mirror
# and a bouncing ball move every frame in the shared Sponza view; the kd-tree is rebuilt, the MBVH refitted and
# DACRT needs no structure; update and trace times per frame for primary and diffuse rays, on 1 and 2 threads.
# Run it on a committed tree.
#
#   scripts/animate.sh              # 512x512, 10 frames
#   FRAMES=30 scripts/animate.sh
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
# shellcheck source=lib/splice.sh
source "$root/scripts/lib/splice.sh"
frames=${FRAMES:-10}
cargo build --release -p raylab-bench --manifest-path "$root/Cargo.toml"

cd "$root"
mkdir -p target/bench
table=$(mktemp)
part=$(mktemp)
for kind in primary diffuse; do
  for threads in 1 2; do
    target/release/raylab-bench animate --scene ../shared/scenes/sponza/sponza.obj --eye -12.5,2.5,0 \
      --target 10,5.5,0 --up 0,1,0 --fov 65 --light 0,11,0 --width 512 --height 512 --kind "$kind" \
      --threads "$threads" --frames "$frames" --markdown "$part" \
      --json "target/bench/animate-$kind-$threads.json"
    cat "$part" >> "$table"
    echo >> "$table"
  done
done

splice_section dynamic "$table"
rm -f "$table" "$part"
echo "updated docs/BENCHMARKS.md"
