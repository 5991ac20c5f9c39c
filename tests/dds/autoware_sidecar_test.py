#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""rsu-autoware-sidecar seen by independent ROS 2-style participants (issue 14 item 3, "must show"):
tests/dds/participant/ros2_participant (plain C on Cyclone's C API, its own IDL) plays the RSU on one DDS
domain, publishing the fixes an RSU publishes (geometry_msgs/PoseWithCovarianceStamped of the footprint box
centre, z = 0, the box yaw folded into [-90, 90) deg, (x, y, yaw) covariance, z/roll/pitch unknown), and a
second one plays Autoware on another domain, publishing the vehicle's own (NDT) poses and reading what the
sidecar publishes for ekf_localizer. The vehicle drives a curve through heading 180 deg (where the folded box
yaw is off by pi) with a known base_link trajectory; this test draws the RSU's errors from the covariance it
states. Checks, per published pose against the truth and against this test's own arithmetic:
  - one pose per good fix; the off-by-90-deg fix and the fix in another frame are refused and counted;
  - header.frame_id is the map frame; header.stamp is the fix's sweep time to the nanosecond;
  - the yaw is the truth's branch (within 4 sigma of the RSU's yaw error, never off by pi);
  - x, y = measured centre + R(yaw) offset, and the covariance = J S J^T (J: the offset's turn with yaw),
    computed here; z and its variance are the nearest own pose's; roll, pitch unknown (1e6);
  - the base_link errors against the truth are consistent with the stated covariance (at most 1 of the
    fixes beyond its 3-sigma ellipse).
Every wait is bounded; every child is killed on the way out.
"""
import argparse
import math
import os
import random
import shutil
import signal
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "tools", "python"))
from rsu_processes import Children, free_udp_port, read_text  # noqa: E402

VEHICLE_ID = 7
OFFSET = (-1.35, 0.05)
OWN_Z, OWN_Z_VAR = 0.42, 0.0025
RSU_COV = [[0.0100, 0.0020, 0.0004], [0.0020, 0.0060, -0.0003], [0.0004, -0.0003, 0.0016]]  # x, y, yaw
FIXES = 20  # at 10 Hz
OFF_BY_90, OTHER_FRAME = 6, 13  # indices of the fixes that must be refused
LEAD_S = 2.5  # from start to the first sweep: discovery happens meanwhile
RSU_TOPIC = "rt/vehicles/%d/rsu/pose_with_covariance" % VEHICLE_ID
OWN_TOPIC = "rt/localization/pose_estimator/pose_with_covariance"
OUT_TOPIC = "rt/localization/pose_estimator/rsu/pose_with_covariance"


def truth(t):
    """base_link x, y and heading at t s into the drive: 8 m/s on a left curve through 180 deg."""
    heading = 2.9 + 0.2 * t
    # Integral of 8 (cos, sin)(2.9 + 0.2 t) dt from 0.
    x = 20.0 + 40.0 * (math.sin(heading) - math.sin(2.9))
    y = -3.0 - 40.0 * (math.cos(heading) - math.cos(2.9))
    return x, y, heading


def rot(yaw, v):
    c, s = math.cos(yaw), math.sin(yaw)
    return (c * v[0] - s * v[1], s * v[0] + c * v[1])


def cholesky3(m):
    L = [[0.0] * 3 for _ in range(3)]
    for i in range(3):
        for j in range(i + 1):
            s = m[i][j] - sum(L[i][k] * L[j][k] for k in range(j))
            L[i][j] = math.sqrt(s) if i == j else s / L[j][j]
    return L


def quaternion(yaw):
    return (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))


def wrap(a):
    return math.remainder(a, 2 * math.pi)


def pose_line(publish_ns, stamp_ns, frame, x, y, z, yaw, cov6):
    return "%d %d %s %.9f %.9f %.9f %.12f %.12f %.12f %.12f %s\n" % (
        publish_ns, stamp_ns, frame, x, y, z, *quaternion(yaw), " ".join("%.12g" % v for v in cov6))


def rsu_cov6():
    c = [0.0] * 36
    idx = (0, 1, 5)
    for i in range(3):
        for j in range(3):
            c[idx[i] * 6 + idx[j]] = RSU_COV[i][j]
    for k in (2, 3, 4):
        c[k * 6 + k] = 1e6
    return c


def write_inputs(work, t0):
    """The RSU's fixes and the own poses; returns the fixes as dicts (what the sidecar was given)."""
    rng = random.Random(5)
    L = cholesky3(RSU_COV)
    fixes = []
    with open(os.path.join(work, "fixes.txt"), "w") as f:
        for k in range(FIXES):
            t = 0.1 * k
            x, y, h = truth(t)
            o = rot(h, OFFSET)
            n = [rng.gauss(0, 1) for _ in range(3)]
            e = [sum(L[i][j] * n[j] for j in range(3)) for i in range(3)]
            cx, cy, yaw = x - o[0] + e[0], y - o[1] + e[1], h + e[2]
            if k == OFF_BY_90:
                yaw += math.pi / 2  # the fitted box's long edge is the car's short edge
            folded = math.remainder(yaw, math.pi)  # a rectangle's yaw, [-90, 90] deg
            stamp = t0 + int(t * 1e9)
            frame = "rsu_lidar" if k == OTHER_FRAME else "map"
            f.write(pose_line(stamp + 30_000_000, stamp, frame, cx, cy, 0.0, folded, rsu_cov6()))
            fixes.append({"k": k, "stamp": stamp, "cx": cx, "cy": cy, "yaw": folded, "truth": (x, y, h)})
    with open(os.path.join(work, "own.txt"), "w") as f:
        for i in range(-25, int(FIXES * 5) + 10):  # 50 Hz, from 0.5 s before the first sweep
            t = 0.02 * i
            x, y, h = truth(t)
            cov = [0.0] * 36
            cov[0] = cov[7] = 0.04
            cov[14] = OWN_Z_VAR
            cov[21] = cov[28] = 0.01
            cov[35] = 0.003
            stamp = t0 + int(t * 1e9)
            # NDT's own heading 2 deg off, its position 0.3 m off: only the heading and z are used.
            f.write(pose_line(stamp + 10_000_000, stamp, "map", x + 0.3, y - 0.2, OWN_Z, h + math.radians(2), cov))
    return fixes


def parse_poses(text):
    poses = []
    for line in text.splitlines():
        w = line.split()
        if w and w[0] == "pose" and len(w) == 47:
            poses.append({"stamp": int(w[2]), "frame_id": w[3], "x": float(w[4]), "y": float(w[5]), "z": float(w[6]),
                          "q": [float(v) for v in w[7:11]], "cov": [float(v) for v in w[11:47]]})
    return poses


def expected(fix):
    """This test's own base_link pose and covariance for a fix (yaw on the truth's branch)."""
    h = fix["truth"][2]
    yaw = fix["yaw"] + math.pi * round(wrap(h - fix["yaw"]) / math.pi)
    o = rot(yaw, OFFSET)
    d = (-math.sin(yaw) * OFFSET[0] - math.cos(yaw) * OFFSET[1], math.cos(yaw) * OFFSET[0] - math.sin(yaw) * OFFSET[1])
    J = [[1, 0, d[0]], [0, 1, d[1]], [0, 0, 1]]
    JS = [[sum(J[i][k] * RSU_COV[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
    cov = [[sum(JS[i][k] * J[j][k] for k in range(3)) for j in range(3)] for i in range(3)]
    return fix["cx"] + o[0], fix["cy"] + o[1], yaw, cov


def check(fixes, poses, stats):
    good = [f for f in fixes if f["k"] not in (OFF_BY_90, OTHER_FRAME)]
    assert len(poses) == len(good), "%d poses back for %d good fixes" % (len(poses), len(good))
    assert stats.get("fixes") == FIXES and stats.get("published") == len(good), stats
    assert stats.get("refused.heading_disagreement") == 1 and stats.get("fixes_bad_stamp_or_frame") == 1, stats
    assert stats.get("refused.no_own_pose") == 0 and stats.get("own_poses_refused") == 0, stats
    beyond_3_sigma, worst_yaw = 0, 0.0
    by_stamp = {f["stamp"]: f for f in good}
    for p in poses:
        assert p["frame_id"] == "map", p["frame_id"]
        fix = by_stamp.get(p["stamp"])
        assert fix is not None, "stamp %d is no fix's sweep time" % p["stamp"]
        ex, ey, eyaw, ecov = expected(fix)
        yaw = 2 * math.atan2(p["q"][2], p["q"][3])
        assert abs(p["x"] - ex) < 1e-5 and abs(p["y"] - ey) < 1e-5, (p, ex, ey)
        assert abs(wrap(yaw - eyaw)) < 1e-6, (yaw, eyaw)
        tx, ty, th = fix["truth"]
        worst_yaw = max(worst_yaw, abs(wrap(yaw - th)))
        assert abs(wrap(yaw - th)) < 4 * math.sqrt(RSU_COV[2][2]), "yaw %.3f vs truth %.3f" % (yaw, th)
        idx = (0, 1, 5)
        for i in range(3):
            for j in range(3):
                got = p["cov"][idx[i] * 6 + idx[j]]
                assert abs(got - ecov[i][j]) <= 1e-6 * max(1e-3, abs(ecov[i][j])), (i, j, got, ecov[i][j])
        assert p["z"] == OWN_Z and abs(p["cov"][14] - OWN_Z_VAR) < 1e-12, (p["z"], p["cov"][14])
        assert p["cov"][21] == 1e6 and p["cov"][28] == 1e6
        # Consistency: the base_link error against the truth in sigmas of the stated x, y covariance.
        a, b, c = ecov[0][0], ecov[0][1], ecov[1][1]
        dx, dy = p["x"] - tx, p["y"] - ty
        m2 = (c * dx * dx - 2 * b * dx * dy + a * dy * dy) / (a * c - b * b)
        beyond_3_sigma += m2 > 11.83  # chi-square 2 dof, 99.73 %
    assert beyond_3_sigma <= 1, "%d of %d beyond 3 sigma" % (beyond_3_sigma, len(poses))
    print("ok: %d fixes, %d base_link poses back (2 refused as they must be), worst yaw error %.2f deg, %d beyond "
          "3 sigma" % (FIXES, len(poses), math.degrees(worst_yaw), beyond_3_sigma))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sidecar", required=True)
    ap.add_argument("--participant", required=True)
    ap.add_argument("--cyclone-config", required=True)
    ap.add_argument("--work", required=True)
    args = ap.parse_args()
    shutil.rmtree(args.work, ignore_errors=True)
    os.makedirs(args.work)
    children = Children()
    path = lambda name: os.path.join(args.work, name)  # noqa: E731
    try:
        rsu_domain = 100 + free_udp_port() % 100  # domains of their own: no crosstalk with tests beside it
        vehicle_domain = 100 + (rsu_domain - 99) % 100
        t0 = time.time_ns() + int(LEAD_S * 1e9)
        fixes = write_inputs(args.work, t0)
        sidecar = children.spawn([args.sidecar, "--vehicle-id", str(VEHICLE_ID), "--rsu-domain", str(rsu_domain),
                                  "--vehicle-domain", str(vehicle_domain), "--cyclone-config", args.cyclone_config,
                                  "--ref-offset-x-m", str(OFFSET[0]), "--ref-offset-y-m", str(OFFSET[1]),
                                  "--duration-s", "60"], path("sidecar.out"), stderr_path=path("sidecar.log"))
        env = dict(os.environ, CYCLONEDDS_URI="file://" + os.path.abspath(args.cyclone_config))
        rsu = children.spawn([args.participant, "--domain", str(rsu_domain), "--publish-poses", path("fixes.txt"),
                              "--pose-out-topic", RSU_TOPIC, "--linger-s", "0"], path("rsu.out"), env=env)
        autoware = children.spawn([args.participant, "--domain", str(vehicle_domain), "--publish-poses",
                                   path("own.txt"), "--pose-out-topic", OWN_TOPIC, "--pose-topic", OUT_TOPIC,
                                   "--linger-s", "1.0"], path("autoware.out"), env=env)
        limit = LEAD_S + FIXES * 0.1 + 20
        for name, p in (("rsu", rsu), ("autoware", autoware)):
            rc = p.wait(timeout=limit)
            assert rc == 0, "%s participant exited with %d:\n%s" % (name, rc, read_text(path(name + ".out")))
        sidecar.send_signal(signal.SIGTERM)
        rc = sidecar.wait(timeout=10)
        assert rc == 0, "sidecar exited with %d:\n%s" % (rc, read_text(path("sidecar.log")))
        stats = {}
        for line in read_text(path("sidecar.out")).splitlines():
            w = line.split()
            if len(w) == 2:
                stats[w[0]] = int(w[1])
        check(fixes, parse_poses(read_text(path("autoware.out"))), stats)
        log = read_text(path("sidecar.log"))
        assert "fix refused: heading_disagreement" in log and "frame_id not map" in log, log
    finally:
        children.kill_all()


if __name__ == "__main__":
    sys.exit(main())
