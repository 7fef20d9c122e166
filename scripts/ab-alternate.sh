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
case $rounds in '' | *[!0-9]*) echo "ROUNDS must be a positive integer, got '$rounds'" >&2; exit 2 ;; esac
for b in "$old" "$new"; do
  [ -x "$b" ] || { echo "not an executable: $b" >&2; exit 2; }
done
median() { awk '/Mrays\/s/ { print $3; found = 1 } END { if (!found) exit 1 }'; }
sum=0
for i in $(seq 1 "$rounds"); do
  a=$(taskset -c 0 "$old" "$@" 2>&1 | median) || { echo "round $i: the old binary printed no Mrays/s line" >&2; exit 1; }
  b=$(taskset -c 0 "$new" "$@" 2>&1 | median) || { echo "round $i: the new binary printed no Mrays/s line" >&2; exit 1; }
  ratio=$(awk -v a="$a" -v b="$b" 'BEGIN { printf "%.3f", b / a }')
  sum=$(awk -v s="$sum" -v r="$ratio" 'BEGIN { print s + r }')
  echo "round $i: old $a, new $b Mrays/s, new/old $ratio"
done
awk -v s="$sum" -v n="$rounds" 'BEGIN { printf "mean new/old %.3f over %d rounds\n", s / n, n }'
