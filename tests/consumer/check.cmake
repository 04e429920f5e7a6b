# Installs the Saltus build tree into a scratch prefix, then configures, builds and runs the
# consumer project against it, and prints how long each consumer program took to compile (the
# README's compile-time figure for a user's scene). Arguments: -DSALTUS_BINARY_DIR=...
# -DCONSUMER_SOURCE_DIR=... -DWORK_DIR=... [-DCONSUMER_CXX_COMPILER=...: the compiler Saltus was
# built with, so that a clang build is consumed by clang and a GCC build by GCC]
# [-DCONSUMER_CXX_FLAGS_RELEASE=...: the consumer's Release flags (tests/CMakeLists.txt,
# SALTUS_CONSUMER_CXX_FLAGS_RELEASE); empty or absent: CMake's default -O3]
# [-DCONSUMER_CXX_COMPILER_LAUNCHER=...: Saltus' own launcher (ccache), so that a rerun, or a clone
# on a machine that ran the test before, hits the cache (CCACHE_BASEDIR, tests/run.sh); a hit
# prints a build time of a second or so, CCACHE_DISABLE=1 gives the compile times]
file(REMOVE_RECURSE "${WORK_DIR}")
execute_process(COMMAND "${CMAKE_COMMAND}" --install "${SALTUS_BINARY_DIR}" --prefix "${WORK_DIR}/prefix"
                RESULT_VARIABLE rc OUTPUT_QUIET)
if(rc)
  message(FATAL_ERROR "installing Saltus failed (${rc})")
endif()
# SUNDIALS is hidden from the consumer: find_package(Saltus) without the component cvode must not
# need it (the consumer's programs use Dormand-Prince, and check that CVODE is refused clearly).
set(consumer_compiler "")
if(CONSUMER_CXX_COMPILER)
  set(consumer_compiler "-DCMAKE_CXX_COMPILER=${CONSUMER_CXX_COMPILER}")
endif()
set(consumer_flags "")
if(CONSUMER_CXX_FLAGS_RELEASE)
  list(APPEND consumer_flags "-DCMAKE_CXX_FLAGS_RELEASE=${CONSUMER_CXX_FLAGS_RELEASE}")
endif()
if(CONSUMER_CXX_COMPILER_LAUNCHER)
  list(APPEND consumer_flags "-DCMAKE_CXX_COMPILER_LAUNCHER=${CONSUMER_CXX_COMPILER_LAUNCHER}")
endif()
execute_process(COMMAND "${CMAKE_COMMAND}" -S "${CONSUMER_SOURCE_DIR}" -B "${WORK_DIR}/build"
                        -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix -DCMAKE_BUILD_TYPE=Release
                        -DCMAKE_DISABLE_FIND_PACKAGE_SUNDIALS=TRUE ${consumer_compiler} ${consumer_flags}
                        RESULT_VARIABLE rc)
if(rc)
  message(FATAL_ERROR "configuring the consumer project failed (${rc})")
endif()
# Without CONSUMER_CXX_FLAGS_RELEASE the consumer builds with CMake's default Release flags (-O3
# for GCC and clang), not Saltus' own, and the build times printed below (without the cache) are
# the ones docs/build.md quotes. main.cpp's derivative check is compiled at -O3 either way
# (tests/consumer/CMakeLists.txt).
file(STRINGS "${WORK_DIR}/build/CMakeCache.txt" release_flags REGEX "^CMAKE_CXX_FLAGS_RELEASE:")
message(STATUS "consumer Release flags: ${release_flags}")
if(NOT CONSUMER_CXX_FLAGS_RELEASE AND NOT release_flags MATCHES "-O3")
  message(FATAL_ERROR "the consumer project is expected to build with CMake's default -O3")
endif()
# The user's scene first (its machinery, compiled once), then each program that links it.
foreach(target falling_mass consumer analysis readme_example old_paths puck optimal_landing)
  string(TIMESTAMP start "%s")
  execute_process(COMMAND "${CMAKE_COMMAND}" --build "${WORK_DIR}/build" --target ${target} RESULT_VARIABLE rc)
  string(TIMESTAMP stop "%s")
  if(rc)
    message(FATAL_ERROR "building the consumer target ${target} failed (${rc})")
  endif()
  math(EXPR seconds "${stop} - ${start}")
  message(STATUS "${target}: built in ${seconds} s (one job)")
  if(target STREQUAL "falling_mass" OR target STREQUAL "puck")
    continue()
  endif()
  execute_process(COMMAND "${WORK_DIR}/build/${target}" RESULT_VARIABLE rc)
  if(rc)
    message(FATAL_ERROR "the consumer program ${target} failed (${rc})")
  endif()
endforeach()
