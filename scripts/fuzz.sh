#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Runs every libFuzzer harness in fuzz/ (issue 7): installs what is missing, builds them with clang in
# the sanitized tree build-asan/ (ASan + UBSan + libFuzzer; scripts/build.sh asan, only the harnesses and
# what they link), and fuzzes each for SECONDS (default 20) on a copy of its seed corpus in
# fuzz/corpus/<name>/, so a run never rewrites the repository's corpus.
# Usage: scripts/fuzz.sh [SECONDS]. Exits non-zero if any harness crashed, leaked, hit undefined
# behaviour or timed out, printing the path of the input that did it.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-20}
scripts/install-deps.sh

harnesses=()
for src in fuzz/*_fuzzer.cpp; do
  harnesses+=("$(basename "$src" .cpp)")
done
scripts/build.sh asan "${harnesses[@]}"

runs=build-asan/fuzz-runs
rm -rf "$runs"
failed=()
for harness in "${harnesses[@]}"; do
  name=${harness%_fuzzer}
  work=$runs/$name
  mkdir -p "$work/corpus" "$work/artifacts"
  cp -r "fuzz/corpus/$name/." "$work/corpus/"
  # -max_len: room for several Velodyne packets (1206 bytes each) or pcap records in one input.
  # -timeout: one input taking seconds is a hang in a parser, reported like a crash.
  rc=0
  "build-asan/fuzz/$harness" -max_total_time="$seconds" -max_len=16384 -timeout=10 -print_final_stats=1 \
    -artifact_prefix="$work/artifacts/" "$work/corpus" >"$work/log.txt" 2>&1 || rc=$?
  execs=$(grep -m1 '^stat::number_of_executed_units' "$work/log.txt" | awk '{print $2}' || true)
  printf 'fuzz: %-16s %10s executions in %ss' "$name" "${execs:-?}" "$seconds"
  if [ "$rc" -ne 0 ]; then
    printf '  FAILED (exit %d)\n' "$rc"
    grep -E '^(==[0-9]+==ERROR|SUMMARY|.*runtime error)' "$work/log.txt" | head -5 || true
    for input in "$work"/artifacts/*; do
      if [ -e "$input" ]; then
        echo "fuzz: crashing input: $input (reproduce: build-asan/fuzz/$harness $input)"
      fi
    done
    echo "fuzz: full log: $work/log.txt"
    failed+=("$name")
  else
    printf '  ok\n'
  fi
done

if [ ${#failed[@]} -ne 0 ]; then
  echo "fuzz: FAILED: ${failed[*]}" >&2
  exit 1
fi
echo "fuzz: all ${#harnesses[@]} harnesses ran ${seconds}s each without a finding"
