#!/usr/bin/env bash
# Compares two raylab-bench binaries by running them one after the other on the first CPU, the other CPU
# idle, alternating for ROUNDS rounds: each run has a core to itself, as a one-thread benchmark does.
# scripts/ab-concurrent.sh runs both at once instead, which cancels slow spells of the host better but
# lets the two runs share what the cores share; a change that shortens a latency-bound chain (mono's walk)
# can then read differently than it runs alone. Each run must be single-threaded and print raylab-bench's
# "Mrays/s median" line (`trace`).
#
#   scripts/ab-alternate.sh OLD_BINARY NEW_BINARY ROUNDS trace --scene ... --threads 1 --reps 5
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
for i in $(seq 1 "$rounds"); do
  a=$(taskset -c 0 "$old" "$@" 2>&1 | ab_median) || { echo "round $i: the old binary printed no Mrays/s line" >&2; exit 1; }
  b=$(taskset -c 0 "$new" "$@" 2>&1 | ab_median) || { echo "round $i: the new binary printed no Mrays/s line" >&2; exit 1; }
  ab_report "$i" "$a" "$b"
done
ab_summary "$rounds"
