#!/usr/bin/env bash
# Compares two raylab-bench binaries on a noisy host by running them at the same time, one on each of the
# first two CPUs, and swapping the CPUs every round: a slow spell of the host then falls on both alike, and
# only their ratio is read. Each run must be single-threaded (`--threads 1`) and print raylab-bench's
# "Mrays/s median" line (`trace`).
#
#   scripts/ab-concurrent.sh OLD_BINARY NEW_BINARY ROUNDS trace --scene ... --threads 1 --reps 7
#
# Prints each round's two medians and their ratio (new / old), then the mean ratio.
set -euo pipefail
if [ $# -lt 4 ]; then
  echo "usage: $0 OLD_BINARY NEW_BINARY ROUNDS raylab-bench-arguments..." >&2
  exit 2
fi
old=$1 new=$2 rounds=$3
shift 3
# shellcheck source=lib/ab.sh
source "$(dirname "$0")/lib/ab.sh"
ab_check_args "$old" "$new" "$rounds"
[ "$(nproc)" -ge 2 ] || { echo "needs at least two CPUs" >&2; exit 2; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for i in $(seq 1 "$rounds"); do
  if [ $((i % 2)) -eq 1 ]; then c_old=0 c_new=1; else c_old=1 c_new=0; fi
  taskset -c "$c_old" "$old" "$@" > "$work/old" 2>&1 &
  p_old=$!
  taskset -c "$c_new" "$new" "$@" > "$work/new" 2>&1 &
  p_new=$!
  wait "$p_old" || { echo "old binary failed:" >&2; cat "$work/old" >&2; exit 1; }
  wait "$p_new" || { echo "new binary failed:" >&2; cat "$work/new" >&2; exit 1; }
  a=$(ab_median < "$work/old") || { echo "no Mrays/s line from the old binary" >&2; exit 1; }
  b=$(ab_median < "$work/new") || { echo "no Mrays/s line from the new binary" >&2; exit 1; }
  ab_report "$i" "$a" "$b"
done
ab_summary "$rounds"
