#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Configure and build one build tree. Usage: scripts/build.sh [release|asan|tsan] [TARGET...] (default
# release, every target of the tree).
# release -> build/      (Release, warnings are errors, benchmarks included)
# asan    -> build-asan/ (clang, RelWithDebInfo at -O1 with line tables, AddressSanitizer +
#                         UndefinedBehaviorSanitizer, no benchmarks; with the libFuzzer harnesses of fuzz/,
#                         which scripts/fuzz.sh runs: one sanitized tree for the tests and the fuzzers)
# tsan    -> build-tsan/ (clang, RelWithDebInfo at -O1 with line tables, ThreadSanitizer, no benchmarks; only
#                         the targets of the tests labelled `threads`, which is all scripts/test.sh runs
#                         under TSan; the simulator and fleet driving them come from build/: build release
#                         first)
set -euo pipefail
cd "$(dirname "$0")/.."
kind=${1:-release}
shift || true
targets=()
if [ $# -gt 0 ]; then
  targets=(--target "$@")
fi
jobs=${RSU_JOBS:-$(nproc)}
# ccache, when installed (developer machines), lets several checkouts share compiled objects.
launcher=()
if command -v ccache >/dev/null 2>&1; then
  launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
# The sanitizer trees are clang's, at -O1 with line tables only: the sanitizers' own recommendation, and the
# stack traces keep their lines. GCC with ASan+UBSan at -O2 -g took 5-7x a Release compile (PCL's NDT:
# 137 s vs 19 s for one file), at -O1 -g1 2.3-2.8x (49 s). With clang the libraries, daemon and tools also
# share precompiled headers (cmake/precompiled_headers.cmake). Warnings are errors in every tree: clang's
# -Wdouble-promotion flags every implicit float -> double (GCC's only those in arithmetic), so the sources
# widen with a cast or `.cast<double>()`.
clang_cflags="-O1 -gline-tables-only -DNDEBUG"
clang_flags=(-DCMAKE_CXX_FLAGS_RELWITHDEBINFO="$clang_cflags" -DCMAKE_C_FLAGS_RELWITHDEBINFO="$clang_cflags")
# A tree configured by GCC before (this script did so for build-asan/ until 2026-11-30, for build-tsan/
# until 2026-12-02) is started afresh: CMake does not switch a configured tree's compiler.
start_afresh_unless_clang() {
  if [ -f "$1/CMakeCache.txt" ] && ! grep -q '^CMAKE_CXX_COMPILER:.*clang++' "$1/CMakeCache.txt"; then
    rm -rf "$1"
  fi
}
case "$kind" in
  release)
    cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DRSU_WERROR=ON "${launcher[@]}" >/dev/null
    cmake --build build -j "$jobs" "${targets[@]}"
    ;;
  asan)
    # clang, not GCC: the fuzz harnesses need it (libFuzzer), and one tree for both saves a build. In CI
    # runs up to 810e31d (2 cores) GCC's ASan+UBSan tree took 741-827 s and the separate clang fuzz tree
    # ~210 s more; on fresh clones since, this tree, harnesses included, 411-479 s. Its tests took
    # 279-463 s against GCC's 236-248 s (README, Known shortfalls).
    start_afresh_unless_clang build-asan
    CC=clang CXX=clang++ cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DRSU_SANITIZE=ON \
      -DRSU_WERROR=ON -DRSU_FUZZ=ON "${clang_flags[@]}" -DRSU_BUILD_BENCHMARKS=OFF "${launcher[@]}" >/dev/null
    cmake --build build-asan -j "$jobs" "${targets[@]}"
    ;;
  tsan)
    # clang, as build-asan/: with the shared precompiled header this tree built in 188 s against GCC's 295 s
    # (2 cores, from scratch, 2026-12-02). The live tests' drivers (rsu-sim, rsu-fleet) come from the
    # Release build (tests/CMakeLists.txt).
    start_afresh_unless_clang build-tsan
    CC=clang CXX=clang++ cmake -S . -B build-tsan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DRSU_SANITIZE_THREAD=ON \
      -DRSU_WERROR=ON "${clang_flags[@]}" -DRSU_BUILD_BENCHMARKS=OFF -DRSU_TEST_TOOLS_DIR="$PWD/build" "${launcher[@]}" >/dev/null
    if [ ${#targets[@]} -eq 0 ]; then
      targets=(--target rsu_threaded_tests)
    fi
    cmake --build build-tsan -j "$jobs" "${targets[@]}"
    ;;
  *) echo "usage: $0 [release|asan|tsan] [TARGET...]" >&2; exit 2 ;;
esac
