#!/usr/bin/env bash
# Builds the two libFuzzer targets with clang (libFuzzer + ASan + UBSan) and runs each for a
# while. Usage: bash bench/fuzz/run.sh [seconds per target, default 300] [jobs, default 1]
# Findings (crash-*, leak-*, timeout-* inputs) are written to bench/fuzz/out/<target>/; the corpus
# grows in bench/fuzz/out/<target>/corpus. Needs clang (Debian: clang, libclang-rt-dev).
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)
seconds=${1:-300}
jobs=${2:-1}
out="$here/out"
mkdir -p "$out"
flags=(-std=c++20 -O1 -g1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined
       -I"$root/hybrid/include" -I"$root/examples" -isystem /usr/include/eigen3)
status=0
for target in fuzz_impact_solver fuzz_reference_csv; do
  if [[ ! -x "$out/$target" || "$here/$target.cpp" -nt "$out/$target" ]]; then
    echo "building $target (clang++, a minute or two)"
    clang++ "${flags[@]}" "$here/$target.cpp" -o "$out/$target"
  fi
  mkdir -p "$out/$target.d/corpus"
  echo "running $target for $seconds s (log: $out/$target.log)"
  parallel=()
  if (( jobs > 1 )); then parallel=(-jobs="$jobs" -workers="$jobs"); fi  # then logs in fuzz-<n>.log
  if (cd "$out/$target.d" && "$out/$target" -max_total_time="$seconds" "${parallel[@]}" \
        -print_final_stats=1 -rss_limit_mb=4096 corpus > "$out/$target.log" 2>&1); then
    echo "  no finding"
  else
    echo "  FINDING (inputs in $out/$target.d/):"
    grep -E "^finding:|^scene |ERROR|SUMMARY|Test unit written" "$out/$target.log" | head -10
    status=1
  fi
  grep -E "stat::number_of_executed_units|stat::average_exec_per_sec|cov: .*ft:" "$out/$target.log" | tail -3
done
exit $status
