#!/usr/bin/env bash
# Lists the functions of the release benchmark binary that call an AVX intrinsic out of line. Vector code must be
# inlined into raylab-simd's AVX2 entry point: a generic function the compiler keeps out of line is built for the
# x86-64 baseline and calls every `_mm256_*` intrinsic as a function, which makes a kernel several times slower
# without changing its answers. Exits non-zero when there is any.
#
#   scripts/check-avx-inlining.sh
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cargo build --release --locked -p raylab-bench --manifest-path "$root/Cargo.toml"
found=$(objdump -d --no-show-raw-insn -C "$root/target/release/raylab-bench" |
  awk '/^[0-9a-f]+ <.*>:$/ { fn = $0 } /call.*core_arch::x86::avx/ { print fn }' | sort | uniq -c)
if [ -n "$found" ]; then
  echo "functions calling AVX intrinsics out of line (calls, function):"
  echo "$found"
  exit 1
fi
echo "no out-of-line AVX intrinsic calls"
