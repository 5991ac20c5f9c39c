#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Fails if the given rsud binary links a library it must not (issue 15): the simulator's Embree and TBB,
# VTK, OpenNI, libusb. Prints what it links either way, so that a failure shows the culprit.
set -euo pipefail
rsud=${1:?usage: check_rsud_links.sh PATH/TO/rsud}
libs=$(ldd "$rsud")
echo "$libs"
count=$(echo "$libs" | wc -l)
echo "rsud links $count shared libraries"
if bad=$(echo "$libs" | grep -E 'libembree|libtbb|libvtk|libOpenNI|libusb'); then
  echo "FAILED: rsud links what it must not:" >&2
  echo "$bad" >&2
  exit 1
fi
if [ "$count" -lt 5 ]; then
  echo "FAILED: ldd listed only $count lines: not a dynamically linked rsud?" >&2
  exit 1
fi
