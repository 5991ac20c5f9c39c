#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The pilot matrix (mounts x LiDAR models x vehicles) with heat maps of every cell of the matrix.
#   eval/pilot/run_matrix.sh [OUT] [rsu-pilot matrix options...]     (from the repository's top folder)
# Writes OUT/matrix.md (the table), OUT/matrix.csv and OUT/<model>_<mount>m_<vehicle>/ with cells.csv,
# summary.json and the heat maps of the centre error, the point count, the stated sigma and the NEES.
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-out/pilot_matrix}
shift || true
BUILD=${BUILD:-build}
PY=/usr/bin/python3  # Debian's python3, which has python3-matplotlib
"$BUILD/eval/rsu-pilot" matrix --out "$OUT" "$@"
$PY eval/plots/pilot_heatmaps.py --metrics improved_center_err_m,points,improved_sigma_m,improved_position_nees \
  "$OUT"/*/ >/dev/null
echo "heat maps: $OUT/<model>_<mount>m_<vehicle>/<model>_<metric>.png"
