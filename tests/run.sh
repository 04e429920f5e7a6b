#!/usr/bin/env bash
# The test command: installs the Debian packages Saltus needs (if missing), configures, builds
# and runs every GoogleTest suite with ctest. Usage: bash tests/run.sh [build-dir] [extra cmake args...]
#   SALTUS_JOBS=N      parallel build and test jobs (default: nproc)
#   CXX (and CC)       the compiler of a new build directory (default, when CXX is unset: clang++)
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# ccache (when installed): paths relative to the clone and no working directory in the hash, so that
# a fresh clone at another path on the same machine hits the cache of an earlier one.
export CCACHE_BASEDIR="$here" CCACHE_NOHASHDIR=1
build=${1:-"$here/build"}
shift || true
# A new build directory is configured with clang unless CXX is set: on this project's 2-core
# machine clang 14 at -O2 builds the library, scenes, examples and tests in 458 s (a fresh clone)
# against GCC 12's 927 s (the scenes' template instantiations: GCC's front end alone takes 110 s
# on the flagship OCP test, clang's 34 s; docs/build.md). libomp-dev: SUNDIALS'
# CMake package asks for OpenMP, which clang finds only with LLVM's OpenMP runtime installed.
# An existing build directory keeps the compiler it was configured with (examples/demo.sh, which
# shares build/, configures a new one with the system's default compiler); the consumer test
# (tests/consumer) builds with the compiler of the build directory.
if [ -z "${CXX:-}" ] && [ ! -f "$build/CMakeCache.txt" ]; then
  bash "$here/.ci/install-deps.sh" clang libomp-dev  # apt-get update + install of the missing packages
  export CXX=clang++
  if [ -z "${CC:-}" ]; then export CC=clang; fi
else
  bash "$here/.ci/install-deps.sh"
fi
jobs=${SALTUS_JOBS:-$(nproc)}
# Benchmarks are built and run by bash bench/run.sh, not here: they add minutes of
# compile time to every CI run and test nothing the suites do not.
bash "$here/.ci/configure.sh" "$here" "$build" -DCMAKE_BUILD_TYPE=Release -DSALTUS_BUILD_BENCH=OFF "$@"
cmake --build "$build" -j "$jobs"
ctest --test-dir "$build" --output-on-failure -j "$jobs"
