#!/usr/bin/env bash
# The test command: installs what is missing, builds, and runs every test in Release and again under
# ASan+UBSan, then runs the fuzz harnesses briefly. `scripts/test.sh --quick` runs the Release pass only.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh

scripts/build.sh release
ctest --test-dir build --output-on-failure -j "$(nproc)"

if [ "${1:-}" != "--quick" ]; then
  scripts/build.sh asan
  # Leak checking stays on; halt_on_error makes any report a test failure.
  ASAN_OPTIONS=detect_leaks=1:halt_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    ctest --test-dir build-asan --output-on-failure -j "$(nproc)"
  # Every parser of outside input under libFuzzer for 15 s each (fuzz/, clang build in build-fuzz/).
  scripts/fuzz.sh 15
fi
