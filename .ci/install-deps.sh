#!/usr/bin/env bash
# Installs the Debian packages Saltus builds against, only those missing (no-op when all are
# present). Used by tests/run.sh, examples/demo.sh and .ci/run. Extra package names given as
# arguments are installed too (.ci/run: clang for the sanitizer stage).
set -euo pipefail
# Only what the build uses. ninja-build: the generator (it compiles a target's objects while its
# dependencies still link); ccache: cached rebuilds; coinor-libipopt-dev: Ipopt 3.11 with MUMPS for
# timefreezing/ (found through pkg-config); python3-matplotlib: the main job's figures (examples/plot_report.py).
# The Python bindings (python/, SALTUS_PYTHON) and their tests: python3-dev and pybind11-dev to build
# the module, python3-numpy, python3-pytest, python3-dask and python3-distributed to run the tests.
packages=(build-essential cmake ninja-build ccache pkg-config libeigen3-dev libboost-dev libsundials-dev
          nlohmann-json3-dev libgtest-dev libgmock-dev libbenchmark-dev coinor-libipopt-dev python3-matplotlib
          python3-dev pybind11-dev python3-numpy python3-pytest python3-dask python3-distributed "$@")
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "installing: ${missing[*]}"
  sudo_cmd=""
  [ "$(id -u)" -ne 0 ] && sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
