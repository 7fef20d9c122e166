# Sourced by the benchmark scripts: splice_section NAME TABLE replaces what lies between the markers
# <!-- NAME:begin --> and <!-- NAME:end --> in docs/BENCHMARKS.md with the contents of the file TABLE.
splice_section() {
  local name=$1 table=$2
  awk -v table="$table" -v begin="<!-- $name:begin -->" -v end="<!-- $name:end -->" '
    $0 == begin { print; while ((getline line < table) > 0) print line; skip = 1; next }
    $0 == end { skip = 0 }
    !skip { print }
  ' docs/BENCHMARKS.md > docs/BENCHMARKS.md.new
  mv docs/BENCHMARKS.md.new docs/BENCHMARKS.md
}
