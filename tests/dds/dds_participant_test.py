#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""rsud over DDS seen by an independent ROS 2-style participant (issue 6, "must show"): the real rsud
with its dds_pointcloud2 input, the real Cyclone DDS on loopback (deploy/cyclonedds-loopback.xml, given
to the participant through CYCLONEDDS_URI as a ROS 2 user would), `rsu-sim simulate` for the scene, the
test announcer for the vehicle's V2I announcements, and tests/dds/participant/ros2_participant (plain C,
its own IDL) publishing sensor_msgs/PointCloud2 and reading the geometry_msgs/PoseWithCovarianceStamped
rsud publishes, each message one rotation (or, with --parts N, each rotation in N messages and rsud's
input set to whole_rotation: false). Checks:
  - poses arrive for the announced vehicle, each within 0.10 m and 2 deg of the simulated truth;
  - the covariance is symmetric, positive semi-definite, its yaw variance finite and positive;
  - header.stamp is the sweep time: inside the span of one published cloud (stamp .. stamp + 0.1 s / N);
  - header.frame_id is the configured one;
  - the object list (rsu_msgs/VehicleFixArray, read through IDL written from dds/msg/*.msg) arrives
    once per rotation with the vehicle at the same place;
  - two broken layouts among the clouds are refused, counted by reason and logged, an empty cloud is
    counted and skipped, the rest served; another sensor's clouds (other header.frame_id) are refused;
  - rsud drains and exits 0 on SIGTERM;
  - with --sidecar: rsu-autoware-sidecar turns rsud's poses into the vehicle's base_link pose for a second
    participant playing Autoware (publishing the vehicle's own pose, 2 deg off in heading, reading the
    sidecar's output): one base_link pose per rsud pose, in the map frame, stamped with rsud's sweep
    time, within 0.15 m and 3 deg of the truth's base_link, z from the own pose.
Every wait is bounded; every child is killed on the way out.
"""
import argparse
import math
import os
import shutil
import signal
import struct
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "tools", "python"))
from pcd_file import read_binary_pcd  # noqa: E402
from rsu_processes import Children, free_udp_port, read_text, wait_for_line  # noqa: E402

TRUTH = (14.0, -5.0, math.radians(25.0))  # footprint centre x, y (m), yaw (rad) of the static car
FRAME_ID = "test_map"
TOLERANCE_M = 0.10
TOLERANCE_YAW = math.radians(2.0)
BASE_LINK_OFFSET = (-1.4, 0.0)  # base_link minus box centre, vehicle frame (the sidecar's --ref-offset-*-m)
OWN_Z = 0.37
ROTATION_S = 0.1
BROKEN = {"short": "data_too_short", "overlap": "overlapping_fields"}  # cloud file kind -> rsud's reason


SCENE = """lidar:
  model: vlp32c
  mount: {x: 0, y: 0, z: 2.0}
  noise: {range_sigma_m: 0.02, angle_sigma_rad: 0.001, seed: 11}
scene:
  ground: {half_extent_m: 60}
  buildings:
    - {x: 0, y: 30, length: 40, width: 10, height: 10}
    - {x: 0, y: -30, length: 40, width: 10, height: 10}
  poles:
    - {x: -5, y: 3, radius: 0.15, height: 6}
simulation: {start_s: 0.0, frames: 4}
"""


def read_pcd(path):
    """The binary PCD rsu-sim writes, as a list of points (dicts of field -> value)."""
    return read_binary_pcd(path)[1]


def write_cloud_file(points, path, broken=None):
    """A Velodyne-ROS-driver-like PointCloud2 (x y z _ intensity ring _ time, 32-byte points, time in
    float32 seconds relative to the stamp = the rotation's first firing), in ros2_participant's format.
    broken: "short" declares more points than the data holds, "overlap" puts y over x."""
    t0 = min((p["time"] for p in points), default=0.0)
    layout = [("x", 0, 7), ("y", 4, 7), ("z", 8, 7), ("intensity", 16, 7), ("ring", 20, 4), ("time", 24, 7)]
    if broken == "overlap":
        layout[1] = ("y", 2, 7)
    step = 32
    data = bytearray(step * len(points))
    for i, p in enumerate(points):
        struct.pack_into("<fff", data, i * step, p["x"], p["y"], p["z"])
        struct.pack_into("<fHxxf", data, i * step + 16, p["intensity"], p["ring"], p["time"] - t0)
    width = len(points) + (1000 if broken == "short" else 0)
    out = b"PC2B" + struct.pack("<IIIIBBI", width, 1, step, step * width, 0, 1, len(layout))
    for name, offset, datatype in layout:
        out += struct.pack("<B", len(name)) + name.encode() + struct.pack("<IBI", offset, datatype, 1)
    out += struct.pack("<I", len(data)) + bytes(data)
    with open(path, "wb") as f:
        f.write(out)


def symmetric_psd(m, n=6):
    """Symmetric within 1e-12 and positive semi-definite (Cholesky of m + tiny ridge succeeds)."""
    for i in range(n):
        for j in range(n):
            if abs(m[i * n + j] - m[j * n + i]) > 1e-12 * max(1.0, abs(m[i * n + j])):
                return False
    ridge = 1e-12
    L = [[0.0] * n for _ in range(n)]
    for i in range(n):
        for j in range(i + 1):
            s = m[i * n + j] + (ridge if i == j else 0.0) - sum(L[i][k] * L[j][k] for k in range(j))
            if i == j:
                if s <= 0:
                    return False
                L[i][i] = math.sqrt(s)
            else:
                L[i][j] = s / L[j][j]
    return True


class Harness:
    def __init__(self, args):
        self.args = args
        self.work = args.work
        shutil.rmtree(self.work, ignore_errors=True)
        os.makedirs(self.work)
        self.children = Children()

    def path(self, name):
        return os.path.join(self.work, name)

    def spawn(self, cmd, out_name, env=None):
        return self.children.spawn(cmd, self.path(out_name), env=env)

    def read(self, name):
        return read_text(self.path(name))

    def simulate(self):
        with open(self.path("empty.yaml"), "w") as f:
            f.write("name: empty\n" + SCENE)
        vehicle = """vehicles:
  - id: 1
    shape: {length: 4.89, width: 1.92, height: 1.70}
    trajectory:
      static: {x: %.3f, y: %.3f, yaw_deg: %.3f}
""" % (TRUTH[0], TRUTH[1], math.degrees(TRUTH[2]))
        with open(self.path("street.yaml"), "w") as f:
            f.write("name: street\n" + SCENE + vehicle)
        for name, out in (("empty.yaml", "bg"), ("street.yaml", "street")):
            r = subprocess.run([self.args.rsu_sim, "simulate", self.path(name), "-o", self.path(out), "--frames", "4"],
                               capture_output=True, text=True, timeout=60)
            assert r.returncode == 0, r.stdout + r.stderr
        listing = lambda d: sorted(os.path.join(self.path(d), f) for f in os.listdir(self.path(d)) if f.endswith(".pcd"))
        self.background = listing("bg")
        self.clouds = []
        street = listing("street")
        parts = self.args.parts
        for i, pcd in enumerate(street):
            points = read_pcd(pcd)
            t0 = min(p["time"] for p in points)
            for k in range(parts):  # parts of the rotation by firing time, in order
                part = [p for p in points if k == min(parts - 1, int((p["time"] - t0) / ROTATION_S * parts))]
                path = self.path("cloud_%d_%d.bin" % (i, k))
                write_cloud_file(part, path)
                self.clouds.append(path)
        # Two broken layouts among the good clouds: each must be refused, counted, and harm nothing.
        for kind in BROKEN:
            path = self.path("broken_%s.bin" % kind)
            write_cloud_file(read_pcd(street[0]), path, broken=kind)
            self.clouds.append(path)
        # And an empty cloud (width 0): valid, but nothing for rsud to process or learn from.
        write_cloud_file([], self.path("empty.bin"))
        self.clouds.append(self.path("empty.bin"))
        assert len(self.background) == 4 and len(street) == 4, (self.background, street)

    def write_config(self, v2i_port, domain):
        text = """rsu_id: 5
lidar:
  model: vlp32c
  mount: {x: 0, y: 0, z: 2.0}
  input:
    dds_pointcloud2: {topic: test/points, whole_rotation: %s, ring_order: channel, frame_id: lidar,
                      qos: {history_depth: 8}}
background:
  pcd_files: [%s]
v2i:
  listen_address: 127.0.0.1
  port: %d
dds:
  enabled: true
  domain_id: %d
  cyclone_config: %s
  pose_topic: test/vehicles/{vehicle_id}/pose
  object_list_topic: test/fixes
  frame_id: %s
security:
  mode: insecure  # this test is about DDS; signed V2I is tests/integration's security case
logging:
  level: info
  stats_interval_s: 0.5
  stats_file: %s
""" % ("true" if self.args.parts == 1 else "false", ", ".join(self.background), v2i_port, domain, self.args.cyclone_config, FRAME_ID, self.path("stats"))
        with open(self.path("rsud.yaml"), "w") as f:
            f.write(text)

    def stats(self):
        values = {}
        with open(self.path("stats")) as f:
            for line in f:
                k, v = line.split()
                values[k] = float(v)
        return values


def parse_participant(text):
    published, poses, lists = [], [], []
    for line in text.splitlines():
        w = line.split()
        if w and w[0] == "published":
            published.append({"stamp": int(w[2]), "sent": int(w[3])})
        elif w and w[0] == "pose" and len(w) == 47:
            poses.append({"recv": int(w[1]), "stamp": int(w[2]), "frame_id": w[3],
                          "x": float(w[4]), "y": float(w[5]), "z": float(w[6]),
                          "q": [float(v) for v in w[7:11]], "cov": [float(v) for v in w[11:47]]})
        elif w and w[0] == "fixes" and len(w) == 6 + 6 * int(w[5]):
            fixes = [{"vehicle": int(w[i]), "sweep": int(w[i + 1]), "x": float(w[i + 2]), "y": float(w[i + 3]),
                      "yaw_var": float(w[i + 4]), "points": int(w[i + 5])} for i in range(6, len(w), 6)]
            lists.append({"recv": int(w[1]), "stamp": int(w[2]), "frame_id": w[3], "rsu": int(w[4]), "fixes": fixes})
    return published, poses, lists


def truth_base_link():
    c, s = math.cos(TRUTH[2]), math.sin(TRUTH[2])
    return (TRUTH[0] + c * BASE_LINK_OFFSET[0] - s * BASE_LINK_OFFSET[1],
            TRUTH[1] + s * BASE_LINK_OFFSET[0] + c * BASE_LINK_OFFSET[1])


def start_sidecar(h, domain, env):
    """rsu-autoware-sidecar on rsud's pose topic, and a participant playing Autoware: the vehicle's own
    pose at 20 Hz (live stamps, heading 2 deg off, z = OWN_Z), reading the sidecar's output."""
    x, y = truth_base_link()
    yaw = TRUTH[2] + math.radians(2.0)
    start = time.time_ns()
    cov = " ".join(["0.01"] + ["0"] * 13 + ["0.04"] + ["0"] * 20 + ["0.001"])
    with open(h.path("own_poses.txt"), "w") as f:
        for i in range(600):  # 30 s; the participant is stopped long before
            t = start + i * 50_000_000
            f.write("%d %d %s %.6f %.6f %.3f 0 0 %.12f %.12f %s\n" % (t, t, FRAME_ID, x + 0.2, y, OWN_Z,
                                                                      math.sin(yaw / 2), math.cos(yaw / 2), cov))
    sidecar = h.spawn([h.args.sidecar, "--vehicle-id", "1", "--rsu-topic", "test/vehicles/{vehicle_id}/pose",
                       "--rsu-domain", str(domain), "--vehicle-domain", str(domain), "--cyclone-config",
                       h.args.cyclone_config, "--map-frame", FRAME_ID, "--own-pose-topic", "test/autoware/ndt_pose",
                       "--output-topic", "test/autoware/rsu_pose", "--ref-offset-x-m", str(BASE_LINK_OFFSET[0]),
                       "--ref-offset-y-m", str(BASE_LINK_OFFSET[1])], "sidecar.out")
    h.autoware = h.spawn([h.args.participant, "--domain", str(domain), "--publish-poses", h.path("own_poses.txt"),
                          "--pose-out-topic", "rt/test/autoware/ndt_pose", "--pose-topic", "rt/test/autoware/rsu_pose"],
                         "autoware.out", env)
    return sidecar


def check_sidecar(h, sidecar, rsud_poses):
    sidecar.send_signal(signal.SIGTERM)
    rc = sidecar.wait(timeout=10)
    assert rc == 0, "sidecar exited with %d:\n%s" % (rc, h.read("sidecar.out"))
    time.sleep(0.3)
    h.autoware.kill()
    h.autoware.wait(timeout=5)
    stats = dict((w[0], int(w[1])) for w in (l.split() for l in h.read("sidecar.out").splitlines()) if len(w) == 2)
    base = parse_participant(h.read("autoware.out"))[1]
    assert stats.get("published", 0) >= len(rsud_poses) - 2 and len(base) >= stats["published"] - 1, (stats, len(base))
    assert len(base) >= 10, "only %d base_link poses:\n%s" % (len(base), h.read("sidecar.out"))
    x, y = truth_base_link()
    rsud_stamps = set(p["stamp"] for p in rsud_poses)
    worst = 0.0
    for p in base:
        worst = max(worst, math.hypot(p["x"] - x, p["y"] - y))
        assert p["frame_id"] == FRAME_ID and p["z"] == OWN_Z, p
        assert math.hypot(p["x"] - x, p["y"] - y) < 0.15, "base_link %s vs truth %.3f %.3f" % (p, x, y)
        yaw = 2.0 * math.atan2(p["q"][2], p["q"][3])
        assert abs(math.remainder(yaw - TRUTH[2], 2 * math.pi)) < math.radians(3.0), (yaw, TRUTH[2])
        assert p["cov"][0] > 0 and p["cov"][7] > 0 and p["cov"][14] == 0.04, p["cov"]
    # rsud's poses and the sidecar's were read by two participants: compare where both saw one.
    assert sum(p["stamp"] in rsud_stamps for p in base) >= min(len(base), len(rsud_stamps)) - 2
    print("ok: %d base_link poses from the sidecar, worst %.3f m from the truth's base_link (%s)" % (
        len(base), worst, ", ".join("%s %d" % kv for kv in stats.items())))


def run(h):
    h.simulate()
    v2i_port = free_udp_port()
    domain = 100 + v2i_port % 100  # its own DDS domain: no crosstalk with tests running beside it
    h.write_config(v2i_port, domain)
    rsud = h.spawn([h.args.rsud, "--config", h.path("rsud.yaml")], "rsud.log")
    wait_for_line(h.path("rsud.log"), "ready: serving", 15, watch=rsud)

    seconds = 4.0
    pose = "%f,%f,%f" % (TRUTH[0] + 0.4, TRUTH[1] - 0.3, TRUTH[2] + 0.05)  # the vehicle's own estimate is off
    h.spawn([h.args.announcer, "--rsu", "127.0.0.1:%d" % v2i_port, "--bind", "127.0.0.1", "--id", "1", "--pose",
             pose, "--seconds", str(seconds + 3), "--insecure", "1"], "vehicle.out")
    env = dict(os.environ, CYCLONEDDS_URI="file://" + os.path.abspath(h.args.cyclone_config))
    sidecar = start_sidecar(h, domain, env) if h.args.sidecar else None
    participant = h.spawn([h.args.participant, "--domain", str(domain), "--cloud-topic", "rt/test/points",
                           "--pose-topic", "rt/test/vehicles/1/pose", "--fixes-topic", "rt/test/fixes",
                           "--rate-hz", str(10 * h.args.parts), "--rotation-s", str(ROTATION_S / h.args.parts),
                           "--seconds", str(seconds), "--linger-s", "1.0"] + h.clouds,
                          "participant.out", env)
    rc = participant.wait(timeout=seconds + 20)
    out = h.read("participant.out")
    assert rc == 0, "participant exited with %d:\n%s" % (rc, out)
    published, poses, lists = parse_participant(out)
    n_files = len(h.clouds)
    # The file list ends with the broken ones and then the empty one.
    broken_sent = sum(1 for i in range(len(published)) if n_files - 1 - len(BROKEN) <= i % n_files < n_files - 1)
    empty_sent = sum(1 for i in range(len(published)) if i % n_files == n_files - 1)
    assert len(published) >= int(seconds * 10 * h.args.parts) - 1, "published %d clouds" % len(published)
    assert len(poses) >= 10, "only %d poses received:\n%s\n%s" % (len(poses), out[-2000:], h.read("rsud.log")[-3000:])

    stamps = sorted(p["stamp"] for p in published)
    worst = 0.0
    for p in poses:
        err = math.hypot(p["x"] - TRUTH[0], p["y"] - TRUTH[1])
        worst = max(worst, err)
        assert err < TOLERANCE_M, "pose %s is %.3f m from the truth" % (p, err)
        qx, qy, qz, qw = p["q"]
        # The participant prints each component with 9 decimals (within 5e-10): the squared norm is 1 within
        # 2 (|qz| + |qw|) 5e-10 <= 1.5e-9.
        assert abs(qx * qx + qy * qy + qz * qz + qw * qw - 1.0) < 2e-9 and abs(qx) < 1e-12 and abs(qy) < 1e-12, p["q"]
        yaw = 2.0 * math.atan2(qz, qw)
        dyaw = abs((yaw - TRUTH[2] + math.pi) % (2 * math.pi) - math.pi)
        assert dyaw < TOLERANCE_YAW, "yaw %.4f vs truth %.4f" % (yaw, TRUTH[2])
        assert p["frame_id"] == FRAME_ID, p["frame_id"]
        cov = p["cov"]
        assert all(math.isfinite(v) for v in cov), cov
        assert symmetric_psd(cov), "covariance not symmetric PSD: %s" % cov
        assert 0.0 < cov[35] < 1.0, "yaw variance %g" % cov[35]
        assert 0.0 < cov[0] < 1.0 and 0.0 < cov[7] < 1.0, cov
        # The sweep time lies within the rotation of one cloud that was published.
        assert any(s <= p["stamp"] <= s + int(ROTATION_S / h.args.parts * 1e9) for s in stamps), \
            "pose stamp %d is in no published rotation" % p["stamp"]
        assert p["recv"] >= p["stamp"], p

    # The object list: once per rotation, from rsu 5, in the configured frame, holding the vehicle while
    # its fixes are current, at the same place as its poses.
    assert len(lists) >= int(seconds * 10) // 2, "only %d object lists" % len(lists)
    with_vehicle = [l for l in lists if any(f["vehicle"] == 1 for f in l["fixes"])]
    assert len(with_vehicle) >= len(lists) // 2, "the vehicle is in %d of %d lists" % (len(with_vehicle), len(lists))
    for l in lists:
        assert l["rsu"] == 5 and l["frame_id"] == FRAME_ID, l
        for f in l["fixes"]:
            assert f["vehicle"] == 1 and math.hypot(f["x"] - TRUTH[0], f["y"] - TRUTH[1]) < TOLERANCE_M, f
            assert 0 <= l["stamp"] - f["sweep"] <= 0.3e9 + 1e6, (l["stamp"], f)  # object_list_max_age_s
            assert 0.0 < f["yaw_var"] < 1.0 and f["points"] > 0, f

    if sidecar:
        check_sidecar(h, sidecar, poses)

    # Another sensor's clouds on the topic (header.frame_id "camera", not the configured "lidar"): refused.
    other = h.spawn([h.args.participant, "--domain", str(domain), "--cloud-topic", "rt/test/points", "--frame-id",
                     "camera", "--rate-hz", "10", "--seconds", "0.3", "--linger-s", "0.5", h.clouds[0]],
                    "other_sensor.out", env)
    rc = other.wait(timeout=20)
    assert rc == 0, "second participant exited with %d:\n%s" % (rc, h.read("other_sensor.out"))
    other_sent = len(parse_participant(h.read("other_sensor.out"))[0])

    # A clean drain (and, under ASan, no leak report): SIGTERM, exit 0.
    rsud.send_signal(signal.SIGTERM)
    rc = rsud.wait(timeout=15)
    assert rc == 0 and "stopped:" in h.read("rsud.log"), "rsud exited with %d:\n%s" % (rc, h.read("rsud.log")[-3000:])
    s = h.stats()
    for kind, reason in BROKEN.items():
        n = s["dds.clouds_rejected." + reason]
        assert 1 <= n <= broken_sent, "%s: %d rejected of %d broken sent" % (reason, n, broken_sent)
        assert ("dds_pointcloud2." + reason) in h.read("rsud.log"), "no log line for " + reason
    assert 1 <= s["dds.clouds_rejected.frame_id"] <= other_sent, (s["dds.clouds_rejected.frame_id"], other_sent)
    assert "dds_pointcloud2.frame_id" in h.read("rsud.log")
    rejected = sum(v for k, v in s.items() if k.startswith("dds.clouds_rejected."))
    assert s["dds.clouds_received"] >= len(published) - 2, (s["dds.clouds_received"], len(published))
    assert s["dds.clouds_accepted"] == s["dds.clouds_received"] - rejected, s
    assert 1 <= s["dds.clouds_empty"] <= empty_sent, (s["dds.clouds_empty"], empty_sent)
    assert s["dds.points_accepted"] > 20000 / h.args.parts * (s["dds.clouds_accepted"] - s["dds.clouds_empty"]), s
    assert s["dds.poses_published"] >= len(poses), s
    print("ok: %d clouds published (%d broken), %d taken by rsud (%d refused), %d poses and %d object lists back, "
          "worst error %.3f m" % (len(published), broken_sent, s["dds.clouds_received"], rejected, len(poses),
                                  len(lists), worst))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rsud", required=True)
    ap.add_argument("--rsu-sim", required=True)
    ap.add_argument("--announcer", required=True)
    ap.add_argument("--participant", required=True)
    ap.add_argument("--cyclone-config", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--parts", type=int, default=1, help="publish each rotation in this many messages")
    ap.add_argument("--sidecar", help="rsu-autoware-sidecar: also check its base_link poses")
    args = ap.parse_args()
    h = Harness(args)
    try:
        run(h)
    finally:
        h.children.kill_all()


if __name__ == "__main__":
    sys.exit(main())
