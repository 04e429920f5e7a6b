#!/usr/bin/env bash
# The test command: installs the Debian packages Saltus needs (if missing), configures, builds
# and runs every GoogleTest suite with ctest. Usage: bash tests/run.sh [build-dir] [extra cmake args...]
#   SALTUS_JOBS=N      parallel build and test jobs (default: nproc)
#   CC, CXX            the compilers of a new build directory (default: clang, clang++)
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${1:-"$here/build"}
shift || true
# A new build directory is configured with clang unless CC or CXX is set: on this project's 2-core
# machine clang 14 at -O2 builds the library, scenes, examples and tests in 507 s against GCC 12's
# 927 s (the scenes' template instantiations: GCC's front end alone takes 110 s on the flagship
# OCP test, clang's 34 s; README, "Build and test times"). An existing build directory keeps the
# compiler it was configured with (examples/demo.sh, which shares build/, configures a new one with
# the system's default compiler).
if [ -z "${CC:-}" ] && [ -z "${CXX:-}" ]; then
  bash "$here/.ci/install-deps.sh" clang  # apt-get update + apt-get install of the missing packages
  export CC=clang CXX=clang++
else
  bash "$here/.ci/install-deps.sh"
fi
jobs=${SALTUS_JOBS:-$(nproc)}
# Benchmarks are built and run by the main job (examples/demo.sh), not here: they add minutes of
# compile time to every CI run and test nothing the suites do not.
bash "$here/.ci/configure.sh" "$here" "$build" -DCMAKE_BUILD_TYPE=Release -DSALTUS_BUILD_BENCH=OFF "$@"
cmake --build "$build" -j "$jobs"
ctest --test-dir "$build" --output-on-failure -j "$jobs"
