# Shared by scripts/ab-alternate.sh and scripts/ab-concurrent.sh, which compare two raylab-bench binaries.

# ab_check_args OLD NEW ROUNDS: exits 2 with a message naming the bad argument.
ab_check_args() {
  case $3 in '' | *[!0-9]* | 0) echo "ROUNDS must be a positive integer, got '$3'" >&2; exit 2 ;; esac
  local b
  for b in "$1" "$2"; do
    [ -x "$b" ] || { echo "not an executable: $b" >&2; exit 2; }
  done
}

# ab_median: the median Mrays/s that `raylab-bench trace` printed on stdin; fails if there is none.
ab_median() { awk '/Mrays\/s/ { print $3; found = 1 } END { if (!found) exit 1 }'; }

# ab_report ROUND OLD_MEDIAN NEW_MEDIAN: prints the round's line and adds its ratio to AB_SUM.
AB_SUM=0
ab_report() {
  local ratio
  ratio=$(awk -v a="$2" -v b="$3" 'BEGIN { printf "%.3f", b / a }')
  AB_SUM=$(awk -v s="$AB_SUM" -v r="$ratio" 'BEGIN { print s + r }')
  echo "round $1: old $2, new $3 Mrays/s, new/old $ratio"
}

# ab_summary ROUNDS: prints the mean ratio over the rounds.
ab_summary() { awk -v s="$AB_SUM" -v n="$1" 'BEGIN { printf "mean new/old %.3f over %d rounds\n", s / n, n }'; }
