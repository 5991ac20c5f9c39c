#!/usr/bin/env bash
# The main job: installs what is missing, builds, and runs the end-to-end demo.
#   1. simulates the corridor street (VLP-32C roadside LiDAR, a car driving through) and writes its
#      frames (PCD), the Velodyne packets (pcap) and a top-down picture;
#   2. reproduces the paper's pilot experiment (Sec. 3.1) for the VLP-16 and VLP-32C and draws the
#      heat maps.
# Everything goes to out/ (override with OUT=...).
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${OUT:-out}
PY=/usr/bin/python3  # Debian's python3, which has python3-matplotlib

scripts/install-deps.sh
echo "== building (Release) =="
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j "$(nproc)" --target rsu-sim rsu-pilot

echo "== 1. corridor street: simulate 10 frames =="
build/tools/rsu-sim simulate scenarios/corridor.yaml --out "$OUT/sim"
$PY eval/plots/topdown.py "$OUT/sim"

echo "== 2. the paper's pilot experiment (75 distances x 180 yaw angles, two LiDAR models) =="
build/eval/rsu-pilot --out "$OUT/pilot"
$PY eval/plots/pilot_heatmaps.py "$OUT/pilot" >/dev/null
echo "heat maps: $OUT/pilot/<model>_<metric>.png; every cell: $OUT/pilot/cells.csv; $OUT/pilot/summary.json"
echo
echo "done. Picture of one frame: $OUT/sim/topdown.png"
