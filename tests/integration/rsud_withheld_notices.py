#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Withheld-fix notices (issue 12 item 3) through the real processes, signed as deployed: the real rsud fed by
the real `rsu-sim stream` and the real `rsu-vehicle`, keys and trust lists made by rsu-keygen, all on
loopback. The street is scenarios/handover_west.yaml with its VLP-16 raised from 2 m to 6 m (an elevated
RSU, issue 12 item 5; written beside --work): the car drives past it at 10 m/s for 5 s, from 21 m before
it to 31 m after. From 6 m up the LiDAR sees parts of the car that leave its place open over more than a
fix may state at times: rsud withholds those fixes (position_unbounded) and tells the vehicle why.
Checked:
  * the vehicle got corrections and FixWithheld notices, each verified and counted by the vehicle by reason
    (fix_withheld.<reason> in its --stats equal to rsud's withheld_notice.<reason>: nothing lost on
    loopback), every reason one rsud names (never unspecified);
  * at most one per second: rsud held the rest back (withheld_notice.rate_limited.*), and no send failed;
  * rsu-vehicle logged one (its reason) and its summary line counts them; the latest, if its position was
    unbounded, states a sigma beyond the bound.
It prints the notices per reason, how many were held back, and the latest as the vehicle logged it.

Every wait is bounded; children are killed on the way out.
"""
import argparse
import os
import subprocess
import sys
import time

import yaml

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from live_rsu import finish, run_case  # noqa: E402
from rsu_processes import read_text  # noqa: E402  (live_rsu put tools/python on the path)

SCENARIO = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scenarios", "handover_west.yaml")
REASONS = ("position_unbounded", "yaw_unobserved", "inconsistent", "no_own_cluster", "no_fit", "out_of_coverage",
           "mount")
# The scenario's drive: x = -20 + 10 t, y = -1.75, yaw 0 (the LiDAR at x = 0, y = -8.5).
START_S, DRIVE_S = 0.0, 5.0
MOUNT_Z_M = 6.0


def truth_at(t):
    return -20.0 + 10.0 * t, -1.75, 0.0


def count(stats, key):
    return int(float(stats.get(key, "0")))


def keygen(h, *words):
    r = subprocess.run([h.tools["keygen"]] + list(words), capture_output=True, text=True, timeout=30)
    assert r.returncode == 0, r.stdout + r.stderr


def vehicle_stats(path):
    """rsu-vehicle's --stats: "key value" lines, one token each (eval/faults reads it so too)."""
    return dict(line.split() for line in read_text(path).splitlines())


def drive(h):
    """rsud (the car's key in its trust list), the stream and rsu-vehicle (the RSU's) on one clock."""
    h.record_background()
    h.make_keys()
    keygen(h, h.path("car"), "--trust-list", h.trust_list, "--role", "vehicle", "--ids", "1")
    keygen(h, "--public-key", h.path("rsu.pub"), "--trust-list", h.path("vehicle_trust.list"), "--role", "rsu",
           "--ids", "1")
    h.write_config(signed=True)
    h.start_rsud()
    h.epoch_ns = time.time_ns() + 1_000_000_000 - int(START_S * 1e9)  # START_S is 1 s from now
    stream = h.stream(START_S, DRIVE_S)
    start = h.epoch_ns + int(START_S * 1e9)
    with open(h.path("ndt.csv"), "w") as f:  # the vehicle's own poses: the truth 0.2 m off
        f.write("time_ns,x,y,yaw\n")
        for k in range(int(DRIVE_S * 10) + 1):
            x, y, yaw = truth_at(START_S + k * 0.1)
            f.write("%d,%.4f,%.4f,%.5f\n" % (start + k * 100_000_000, x + 0.2, y, yaw))
    h.wait_until_scenario(START_S)
    vehicle = h.children.spawn([h.tools["vehicle"], "--vehicle-id", "1", "--rsu", "127.0.0.1:%d" % h.v2i_port,
                                "--bind", "127.0.0.1:0", "--realtime", "--drain-ms", "300", "--key", h.path("car.key"),
                                "--trust-list", h.path("vehicle_trust.list"), "--stats", h.path("vehicle.stats")],
                               h.path("fused.csv"), stdin_path=h.path("ndt.csv"), stderr_path=h.path("vehicle.err"))
    finish(stream, DRIVE_S + 15, "rsu-sim stream")
    finish(vehicle, DRIVE_S + 15, "rsu-vehicle")
    h.stop_rsud()


def check(h):
    s, v = h.stats(), vehicle_stats(h.path("vehicle.stats"))
    notices = {r: count(s, "withheld_notice." + r) for r in REASONS}
    held_back = sum(count(s, "withheld_notice.rate_limited." + r) for r in REASONS)
    received = {r: count(v, "fix_withheld." + r) for r in REASONS}
    total = sum(notices.values())
    print("corrections sent %d, accepted by the vehicle %d; notices %s (%d held back by the limit)" % (
        count(s, "corrections_sent"), count(v, "corrections.accepted"),
        {r: n for r, n in notices.items() if n}, held_back))
    assert count(s, "corrections_sent") > 0 and count(v, "corrections.accepted") > 0, (s, v)
    assert total >= 2, "no notices: %s" % s
    assert received == notices, "the vehicle counted %s, rsud sent %s" % (received, notices)
    assert count(v, "fix_withheld.unspecified") == 0, v
    # One per second at most (the first at once): the drive lasts DRIVE_S.
    assert total <= DRIVE_S + 1, "%d notices in %.1f s" % (total, DRIVE_S)
    assert held_back > 0 and count(s, "withheld_notice_sends_failed") == 0, s
    last = v.get("fix_withheld.last", "")
    assert last in REASONS, v
    # An unbounded position says how far from a fix it was: the sigma it would have stated, beyond the bound.
    assert last != "position_unbounded" or (
        float(v["fix_withheld.last_sigma_m"]) > float(v["fix_withheld.last_max_sigma_m"])), v
    err = read_text(h.path("vehicle.err"))
    lines = [line for line in err.splitlines() if "withheld the fix of sweep" in line]
    assert lines and "RSU 1 (127.0.0.1:" in lines[0], err
    assert "; fixes withheld by RSUs " in err, err
    print("ok: the vehicle verified and counted every notice by reason; it logged e.g.\n  %s" % lines[-1])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rsud", required=True)
    ap.add_argument("--rsu-sim", required=True)
    ap.add_argument("--vehicle", required=True)
    ap.add_argument("--keygen", required=True)
    ap.add_argument("--work", required=True)
    args = ap.parse_args()
    with open(SCENARIO) as f:
        street = yaml.safe_load(f)
    street["lidar"]["mount"]["z"] = MOUNT_Z_M
    scenario = "%s_handover_west_%gm.yaml" % (os.path.abspath(args.work), MOUNT_Z_M)
    with open(scenario, "w") as f:
        yaml.safe_dump(street, f)
    tools = {"rsud": args.rsud, "rsu_sim": args.rsu_sim, "vehicle": args.vehicle, "keygen": args.keygen}
    return run_case(lambda h: (drive(h), check(h)), args.work, tools, scenario)


if __name__ == "__main__":
    sys.exit(main())
