#!/usr/bin/env bash
# The test command: installs the Debian packages Saltus needs (if missing), configures, builds
# and runs every GoogleTest suite with ctest. Usage: bash tests/run.sh [build-dir] [extra cmake args...]
#   SALTUS_JOBS=N      parallel build and test jobs (default: nproc)
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${1:-"$here/build"}
shift || true
bash "$here/.ci/install-deps.sh"  # apt-get update + apt-get install of the missing packages
jobs=${SALTUS_JOBS:-$(nproc)}
# Benchmarks are built and run by the main job (examples/demo.sh), not here: they add minutes of
# compile time to every CI run and test nothing the suites do not.
bash "$here/.ci/configure.sh" "$here" "$build" -DCMAKE_BUILD_TYPE=Release -DSALTUS_BUILD_BENCH=OFF "$@"
cmake --build "$build" -j "$jobs"
ctest --test-dir "$build" --output-on-failure -j "$jobs"
