#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Configure and build one build tree. Usage: scripts/build.sh [release|asan|tsan] (default release).
# release -> build/      (Release, warnings are errors, benchmarks included)
# asan    -> build-asan/ (RelWithDebInfo at -O1 -g1 with AddressSanitizer + UndefinedBehaviorSanitizer, no benchmarks)
# tsan    -> build-tsan/ (RelWithDebInfo at -O1 -g1 with ThreadSanitizer, no benchmarks; only the targets of the
#                         tests labelled `threads`, which is all scripts/test.sh runs under TSan; the
#                         simulator and fleet driving them come from build/: build release first)
set -euo pipefail
cd "$(dirname "$0")/.."
kind=${1:-release}
jobs=${RSU_JOBS:-$(nproc)}
# ccache, when installed (developer machines), lets several checkouts share compiled objects.
launcher=()
if command -v ccache >/dev/null 2>&1; then
  launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
# The sanitizer builds compile at -O1 with line tables only: GCC with ASan+UBSan at -O2 -g took 5-7x a
# Release compile (PCL's NDT: 137 s vs 19 s for one file), at -O1 -g1 2.3-2.8x (49 s): the sanitizers'
# own recommendation, and the stack traces keep their lines. GCC's -Wmaybe-uninitialized guesses from
# what its optimiser saw, and TSan's instrumentation at -O1 makes it guess wrong inside Eigen's assignment
# of a std::optional's payload (vehicle_client/cli); the Release build keeps the warning as an error.
sanitizer_cflags="-O1 -g1 -DNDEBUG -Wno-maybe-uninitialized"
sanitizer_flags=(-DCMAKE_CXX_FLAGS_RELWITHDEBINFO="$sanitizer_cflags" -DCMAKE_C_FLAGS_RELWITHDEBINFO="$sanitizer_cflags")
case "$kind" in
  release)
    cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DRSU_WERROR=ON "${launcher[@]}" >/dev/null
    cmake --build build -j "$jobs"
    ;;
  asan)
    cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DRSU_SANITIZE=ON \
      "${sanitizer_flags[@]}" -DRSU_BUILD_BENCHMARKS=OFF -DRSU_WERROR=ON "${launcher[@]}" >/dev/null
    cmake --build build-asan -j "$jobs"
    ;;
  tsan)
    # The live tests' drivers (rsu-sim, rsu-fleet) come from the Release build (tests/CMakeLists.txt).
    cmake -S . -B build-tsan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DRSU_SANITIZE_THREAD=ON \
      "${sanitizer_flags[@]}" -DRSU_BUILD_BENCHMARKS=OFF -DRSU_WERROR=ON -DRSU_TEST_TOOLS_DIR="$PWD/build" "${launcher[@]}" >/dev/null
    cmake --build build-tsan -j "$jobs" --target rsu_threaded_tests
    ;;
  *) echo "usage: $0 [release|asan|tsan]" >&2; exit 2 ;;
esac
