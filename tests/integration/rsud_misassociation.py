#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Mis-association test (issue 7 item 6): the real rsud, `rsu-sim stream` (VLP-32C) and `rsu-fleet` on
loopback, in scenarios/occlusion_street.yaml: seven vehicles close together and occluding each other (a
queue at a light, a car passing a parked van, two cars side by side), of which 2, 4 and 7 are NOT connected
(they never announce).

A correction is sent to the WRONG vehicle when its position is nearer the truth of another vehicle
(connected or not) than the truth of the vehicle it was addressed to, or when it names another vehicle.
Must hold: that count is zero; and the connected vehicles are served (at least 50 % of their rotations:
the rest are the corrections WITHHELD, where the RSU could not tell the vehicles apart or saw too little,
which is the safe side; reported). Also reported, not asserted: GROSS errors, corrections more than 1 m
from the truth of their own vehicle (still the nearest): a vehicle partly hidden behind a nearer one shows
a truncated face whose end is taken for the vehicle's end (occlusion, README's known shortfalls). rsud
passes each vehicle's fix the sweep's other objects nearer in its direction (core/sweep_occluders.h):
asserted, no correction is hazardously misleading (beyond 3 sigma of its stated covariance and more than
0.30 m off); the share beyond 3 sigma is reported.

Every wait is bounded in time; every child is killed on the way out.
"""
import argparse
import os
import sys
import time

import yaml

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from live_rsu import ROTATION_S, finish, run_case  # noqa: E402

SCENARIO = os.path.join(os.path.dirname(os.path.abspath(__file__)), "scenarios", "occlusion_street.yaml")
CONNECTED = [1, 3, 5, 6]
DRIVE_S = 8.0
GROSS_M = 1.0
SIGMAS_3 = 11.829 ** 0.5
HMI_M = 0.30


def run(h, mount_integrity=True):
    h.record_background()
    h.write_config(extra="" if mount_integrity else "mount_integrity: {enabled: false}\n")
    h.start_rsud()
    h.epoch_ns = time.time_ns() + 600_000_000
    stream = h.stream(0.0, DRIVE_S)
    fleet = h.fleet(DRIVE_S + 0.3, connected=CONNECTED)
    finish(stream, 40, "rsu-sim stream")
    finish(fleet, 40, "rsu-fleet")
    h.stop_rsud()
    cs = [c for c in h.corrections() if 0.0 <= h.scenario_s(c["sweep_ns"]) < DRIVE_S]
    wrong = [c for c in cs if c["named"] != c["vehicle"] or (c["other"] != 0 and c["other_error"] < c["error"])]
    gross = [c for c in cs if c not in wrong and c["error"] > GROSS_M]
    # A stated uncertainty is a promise: the position error in sigmas of the stated covariance (2-dof 3
    # sigma: sqrt(11.83)); hazardously misleading (HMI): beyond it and more than 0.30 m off.
    beyond = [c for c in cs if c["sigmas"] > SIGMAS_3]
    hmi = [c for c in beyond if c["error"] > HMI_M]
    rotations = int(round((DRIVE_S - 0.2) / ROTATION_S))  # the first rotation may precede registration
    per_vehicle = {v: [c for c in cs if c["vehicle"] == v] for v in CONNECTED}
    lines = []
    for v, got in per_vehicle.items():
        worst = max((c["error"] for c in got), default=float("nan"))
        lines.append("vehicle %d: %d corrections in %d rotations (%d withheld), worst %.3f m" % (
            v, len(got), rotations, max(0, rotations - len(got)), worst))
    print("\n".join(lines))
    print("corrections: %d, to the wrong vehicle: %d, withheld: %d of %d vehicle-rotations, gross (> %.0f m "
          "from their own vehicle, occluded): %d" % (
              len(cs), len(wrong), sum(max(0, rotations - len(g)) for g in per_vehicle.values()),
              rotations * len(CONNECTED), GROSS_M, len(gross)))
    print("beyond 3 sigma of their stated covariance: %d, HMI (and > %.2f m off): %d" % (len(beyond), HMI_M, len(hmi)))
    assert not wrong, "%d corrections went to the wrong vehicle, e.g. %s" % (len(wrong), wrong[:3])
    assert not hmi, "%d hazardously misleading corrections, e.g. %s" % (len(hmi), hmi[:3])
    for v, got in per_vehicle.items():
        assert len(got) >= 0.5 * rotations, "vehicle %d served in only %d of %d rotations" % (v, len(got), rotations)
    print("ok: zero wrong-vehicle corrections")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rsud", required=True)
    ap.add_argument("--rsu-sim", required=True)
    ap.add_argument("--fleet", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--mount-z-m", type=float,
                    help="the RSU LiDAR at this height instead of the street's 2 m (an elevated RSU, issue 12; "
                         "the street with it is written beside --work)")
    ap.add_argument("--mount-integrity", choices=("on", "off"), default="on",
                    help="off: rsud does not check its mount (to compare with: what the check withholds)")
    args = ap.parse_args()
    # The processes run inside --work: a relative path would be taken from there a second time.
    args.work = os.path.abspath(args.work)
    scenario = SCENARIO
    if args.mount_z_m is not None:
        with open(SCENARIO) as f:
            street = yaml.safe_load(f)
        street["lidar"]["mount"]["z"] = args.mount_z_m
        scenario = "%s_occlusion_street_%gm.yaml" % (args.work, args.mount_z_m)
        with open(scenario, "w") as f:
            yaml.safe_dump(street, f)
    return run_case(lambda h: run(h, args.mount_integrity == "on"), args.work, {"rsud": args.rsud, "rsu_sim": args.rsu_sim, "fleet": args.fleet}, scenario)

if __name__ == "__main__":
    sys.exit(main())
