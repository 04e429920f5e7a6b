#!/usr/bin/env bash
# The main job: installs the Debian packages (if missing), builds Saltus, runs every example scene
# and the contact/simulation benchmarks, prints the results and writes the report files to
# report/ (trajectories as JSON and CSV, benchmark figures as JSON).
#   SALTUS_JOBS=N   parallel build jobs (default: nproc)
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build="$here/build"
bash "$here/.ci/install-deps.sh"
bash "$here/.ci/configure.sh" "$here" "$build" -DCMAKE_BUILD_TYPE=Release -DSALTUS_BUILD_BENCH=ON
cmake --build "$build" -j "${SALTUS_JOBS:-$(nproc)}"
export SALTUS_REPORT_DIR="$here/report"
mkdir -p "$SALTUS_REPORT_DIR"
for example in bouncing_ball guiding_example plank_box hopper spatial_box; do
  echo
  "$build/examples/$example"
done
for bench in contact_properties simulation_accuracy jump_gains simultaneous_impact; do
  if [ -x "$build/bench/$bench" ]; then
    echo
    echo "== $bench =="
    "$build/bench/$bench"
    "$build/bench/$bench" --json > "$SALTUS_REPORT_DIR/$bench.json"
    echo "wrote $SALTUS_REPORT_DIR/$bench.json"
  fi
done
# The guiding example's time-freezing OCP (a few seconds): JSON on stdout, progress on stderr.
echo
echo "== guiding_example --json (time-freezing OCP) =="
OPENBLAS_NUM_THREADS=1 "$build/examples/guiding_example" --json | tee "$SALTUS_REPORT_DIR/guiding_example_ocp.json"
# Time-freezing + FESD against closed forms (about 5 minutes): run once; its progress lines (one per
# configuration, on stderr) are the printed results, the table is in the JSON.
if [ -x "$build/bench/fesd_accuracy" ]; then
  echo
  echo "== fesd_accuracy =="
  OPENBLAS_NUM_THREADS=1 "$build/bench/fesd_accuracy" --json > "$SALTUS_REPORT_DIR/fesd_accuracy.json"
  echo "wrote $SALTUS_REPORT_DIR/fesd_accuracy.json"
fi
