#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# One command-line convention across the programs: `--version` prints "<program> <version>" and exits 0
# (even where other options are required), an unknown option is a usage error (exit 2), and so is
# rsu-keygen or rsu-sim given nothing to do; an option renamed to carry its unit keeps its old name. Usage: cli_convention.sh VERSION PROGRAM...
set -u
version=$1; shift
for program in "$@"; do
  name=$(basename "$program")
  out=$("$program" --version 2>&1); rc=$?
  [ $rc -eq 0 ] && [ "$out" = "$name $version" ] || { echo "FAIL: $name --version: exit $rc, \"$out\""; exit 1; }
  "$program" --no-such-option >/dev/null 2>&1; rc=$?
  [ $rc -eq 2 ] || { echo "FAIL: $name --no-such-option: exit $rc, expected 2"; exit 1; }
  "$program" --help >/dev/null 2>&1 || { echo "FAIL: $name --help"; exit 1; }
  echo "ok: $out"
done
for program in "$@"; do
  case $(basename "$program") in
    rsu-vehicle)  # an option renamed to carry its unit still takes its old name, with a warning
      out=$("$program" --length 4.5 --help 2>&1 >/dev/null); rc=$?
      [ $rc -eq 0 ] || { echo "FAIL: rsu-vehicle --length (the old name): exit $rc"; exit 1; }
      case "$out" in *"--length is deprecated, use --length-m"*) echo "ok: $out" ;;
        *) echo "FAIL: no deprecation warning: $out"; exit 1 ;; esac ;;
    rsu-keygen|rsu-sim)
      "$program" >/dev/null 2>&1; rc=$?
      [ $rc -eq 2 ] || { echo "FAIL: $program with no arguments: exit $rc, expected 2"; exit 1; } ;;
  esac
done
echo OK
