#!/usr/bin/env bash
# The benchmarks: installs the Debian packages (if missing), builds the benchmark programs in
# build/ (SALTUS_BUILD_BENCH=ON) and runs the speed-against-error benchmarks, each printing its
# table and writing its JSON to report/bench/. bench/README.md says what each one measures.
#   SALTUS_JOBS=N      parallel build jobs (default: nproc)
#   SALTUS_BENCH_FESD=1  also runs fesd_accuracy (time-freezing + FESD against closed forms,
#                        about 10 minutes)
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build="$here/build"
bash "$here/.ci/install-deps.sh"
bash "$here/.ci/configure.sh" "$here" "$build" -DCMAKE_BUILD_TYPE=Release -DSALTUS_BUILD_BENCH=ON
benches=(contact_properties simulation_accuracy jump_gains simultaneous_impact)
if [ "${SALTUS_BENCH_FESD:-0}" = 1 ]; then benches+=(fesd_accuracy); fi
cmake --build "$build" -j "${SALTUS_JOBS:-$(nproc)}" --target "${benches[@]}"
out="$here/report/bench"
mkdir -p "$out"
for bench in "${benches[@]}"; do
  echo
  echo "== $bench =="
  if [ "$bench" = fesd_accuracy ]; then
    OPENBLAS_NUM_THREADS=1 "$build/bench/$bench" --json > "$out/$bench.json"
  else
    OPENBLAS_NUM_THREADS=1 "$build/bench/$bench"
    OPENBLAS_NUM_THREADS=1 "$build/bench/$bench" --json > "$out/$bench.json"
  fi
  echo "wrote $out/$bench.json"
done
