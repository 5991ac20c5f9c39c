#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The main job: installs what is missing, builds, and runs the end-to-end demo.
#   1. the paper's realistic experiment (Sec. 4) in the corridor street, through the real processes on
#      loopback: the vehicle's NDT self-localization, then for the VLP-16 and the VLP-32C the real rsud
#      fed with Velodyne packets by the simulator, and the real vehicle client announcing, receiving
#      corrections and fusing them, every V2I message signed (Ed25519) with keys rsu-keygen makes into
#      out/corridor/keys/; prints the paper's table and writes the figures;
#   2. the same experiment in the degraded corridor, the paper's street as it describes it (a road between
#      two tall buildings where NDT degrades along the road): its table beside the paper's, its figures;
#      then that street with traffic (six more vehicles both ways, two of them connected, trucks that hide
#      the car): the same table, and every correction rsud sent to the wrong vehicle;
#   3. the V2I link impaired there: a relay between rsud and the vehicle delays, loses, jitters and
#      reorders datagrams both ways (the one-factor sweeps and 200 ms with 30 % loss); a table, a figure;
#   4. the paper's pilot experiment (Sec. 3.1): heat maps over distance x yaw, both LiDAR models;
#   5. one simulated frame of the street as PCD, pcap and a top-down picture;
#   6. two RSUs on one DDS bus hand a driving vehicle over: two rsud, two simulated LiDARs 40 m apart, one
#      rsu-vehicle announcing to the first RSU only; prints corrections per RSU, gaps, jumps, errors.
# Everything goes to out/ (override with OUT=...).
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${OUT:-out}
PY=/usr/bin/python3  # Debian's python3, which has python3-matplotlib and python3-yaml

scripts/install-deps.sh
echo "== building (Release) =="
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j "$(nproc)" --target rsu-sim rsu-pilot rsu-corridor rsud rsu-vehicle rsu-keygen rsu-relay rsu-fleet

echo "== 1. realistic experiment: corridor street, NDT vs RSU vs fused (paper Sec. 4) =="
$PY eval/corridor/run_experiment.py --build build --out "$OUT/corridor"

echo "== 2. realistic experiment in the degraded corridor: NDT degrades between two tall buildings =="
$PY eval/corridor/run_experiment.py --build build --experiment scenarios/corridor_degraded_experiment.yaml \
  --out "$OUT/corridor_degraded"
echo "-- the degraded corridor with traffic (issue 13 item 3) --"
$PY eval/corridor/run_experiment.py --build build --experiment scenarios/corridor_degraded_traffic_experiment.yaml \
  --out "$OUT/corridor_traffic"

echo "== 3. the V2I link impaired between rsud and the vehicle, degraded corridor (12 live runs) =="
$PY eval/corridor/run_link_impairment.py --build build --quick --out "$OUT/link_impairment" | tail -1

echo "== 4. pilot experiment: 75 distances x 180 yaw angles, VLP-16 and VLP-32C (paper Sec. 3.1) =="
build/eval/rsu-pilot --out "$OUT/pilot"
$PY eval/plots/pilot_heatmaps.py "$OUT/pilot" >/dev/null
echo "heat maps: $OUT/pilot/<model>_<metric>.png; every cell: $OUT/pilot/cells.csv; $OUT/pilot/summary.json"

echo "== 5. one frame of the street: PCD, Velodyne pcap, top-down picture =="
build/tools/rsu-sim simulate scenarios/corridor.yaml --out "$OUT/sim" | tail -3
$PY eval/plots/topdown.py "$OUT/sim"

echo "== 6. two RSUs on one DDS bus hand a driving vehicle over (issue 6) =="
$PY tests/integration/handover_integration.py --rsud build/daemon/rsud --rsu-sim build/tools/rsu-sim \
  --vehicle build/vehicle_client/rsu-vehicle --keygen build/tools/rsu-keygen --work "$OUT/handover" |
  tee "$OUT/handover_summary.txt"
echo "every correction: $OUT/handover/corrections.csv; logs and stats of both rsud: $OUT/handover/"

for street in corridor corridor_degraded corridor_traffic; do
  echo
  echo "== the realistic experiment in the street $street (also $OUT/$street/table.txt, paper_comparison.txt) =="
  cat "$OUT/$street/table.txt" "$OUT/$street/paper_comparison.txt"
  echo "figures: $OUT/$street/error_vs_position.png, $OUT/$street/error_boxplot.png"
done
echo
echo "== the V2I link impaired (also $OUT/link_impairment/table.txt) =="
cat "$OUT/link_impairment/table.txt"
echo "figure: $OUT/link_impairment/fused_error_vs_link.png"
