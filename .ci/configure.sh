#!/usr/bin/env bash
# Configures a build directory: bash .ci/configure.sh <source> <build> [cmake args...]. Ninja when
# the directory is new and ninja is installed (an existing directory keeps its generator); the
# compiler runs through ccache when it is installed (CMakeLists.txt, SALTUS_CCACHE).
set -euo pipefail
source_dir=$1
build_dir=$2
shift 2
generator=()
if [ ! -f "$build_dir/CMakeCache.txt" ] && command -v ninja > /dev/null; then generator=(-G Ninja); fi
cmake -S "$source_dir" -B "$build_dir" "${generator[@]}" "$@"
