#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Two RSUs on one DDS bus hand a vehicle over (issue 6, its first "must show"), through the real processes
on loopback: two rsud (the shipped loopback Cyclone configuration, a DDS domain of this run's own), two
`rsu-sim stream` (scenarios/handover_west.yaml and handover_east.yaml: two VLP-16s 40 m apart, coverage
radius 29 m each, overlapping from x = 12 m to 28 m along the lane) sharing one epoch, and ONE vehicle, the
real `rsu-vehicle`, that drives past both at 10 m/s and announces to the WEST RSU only.

What is checked (t is a correction's sweep time on the scenario clock; the truth is the scenario's straight
drive, x = -20 + 10 t, y = -1.75, yaw 0, computed here):
  * the vehicle is corrected by both RSUs (rsu_id 1 and 2); the east RSU only ever heard of it over the bus
    (its stats: peer.accepted > 0, datagram.accepted = 0);
  * over the whole drive, all corrections of both RSUs in sweep-time order: the first within 0.3 s of the
    start, the last within 0.3 s of the end, and no gap between consecutive ones over 200 ms;
  * no jump: between consecutive corrections (whichever RSU sent them), the change of the correction's
    error vs the truth, d = e(k+1) - e(k), is within 3 sigma of the two corrections' combined stated
    covariance along d: |d| <= 3 sqrt(u' (C(k) + C(k+1)) u), u = d / |d| (position); the yaw error's change
    within 3 sqrt(var(k) + var(k+1)) (yaw modulo pi);
  * every correction within 0.25 m of the truth, and its yaw within 3 of its own stated sigma;
  * the vehicle fused corrections of both RSUs, and its fused pose (rsu-vehicle's EKF over its own poses,
    0.29 m off, and both RSUs' corrections) is within 0.15 m of the truth from t = 0.5 s to the end.
It prints the figures: corrections per RSU, the largest gap, the largest jump against its bound, errors.

The bad_peers case: one rsud and a misbehaving peer on the bus (rsud_test_peer_publisher: garbage, a reply_to
that is not the sender, rsud's own rsu_id, no sender, a flood from one origin, then a well-behaved peer):
each counted by reason, logged at a bounded rate, the flood limited, the good peer's vehicle registered.

Every wait is bounded in time; every child is killed on the way out.
"""
import argparse
import math
import os
import random
import shutil
import signal
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tools", "python"))
from rsu_processes import Children, ChildExited, free_udp_port, read_text, wait_for, wait_for_line  # noqa: E402

SCENARIOS = {1: "handover_west.yaml", 2: "handover_east.yaml"}
MOUNTS = {1: (0.0, -8.5), 2: (40.0, -8.5)}  # as in the scenario files
COVERAGE_M = 29.0
DRIVE_S = 8.0
SPEED = 10.0
X0, Y0 = -20.0, -1.75

MAX_GAP_S = 0.200
MAX_ERROR_M = 0.25
# The L-shape yaw of a VLP-16 box seen along the road is a few degrees off at times (3.7 deg at 21 m); the
# fix's stated yaw sigma says so (lib/perception/fix_covariance.h: grazing faces, measured body departure),
# so every fix's yaw error is held to 3 of its own stated sigma (about 3 deg here), not a fixed 5 deg.
YAW_SIGMAS = 3.0
NDT_BIAS = (0.25, -0.15, 0.017)  # the vehicle's own poses: the truth this far off (0.29 m)
MAX_FUSED_ERROR_M = 0.15
JUMP_SIGMAS = 3.0


def truth_at(t):
    t = min(max(t, 0.0), DRIVE_S)
    return X0 + SPEED * t, Y0, 0.0


def yaw_mod_pi(a):
    return (a + math.pi / 2) % math.pi - math.pi / 2


class Run:
    def __init__(self, args):
        self.args = args
        self.work = args.work
        shutil.rmtree(self.work, ignore_errors=True)
        os.makedirs(self.work)
        self.children = Children()
        self.rsud = {}
        self.make_keys()

    def make_keys(self):
        """Signed V2I, as deployed: rsu-keygen makes each RSU's key (the vehicle trusts RSU n for rsu id n)
        and the car's (both RSUs trust it for vehicle 1): the east RSU verifies the car's own signature on
        the datagram the west RSU shares."""
        keys = self.path("keys")
        os.makedirs(keys)
        for name, trust, role, ids in (("rsu1", "vehicle_trust.list", "rsu", "1"),
                                       ("rsu2", "vehicle_trust.list", "rsu", "2"),
                                       ("car", "rsu_trust.list", "vehicle", "1")):
            subprocess.run([self.args.keygen, os.path.join(keys, name), "--trust-list", os.path.join(keys, trust),
                            "--role", role, "--ids", ids], check=True, stdout=subprocess.DEVNULL, timeout=30)

    def path(self, name):
        return os.path.join(self.work, name)

    def background(self, rsu):
        out = self.path("bg_%d" % rsu)
        subprocess.run([self.args.rsu_sim, "simulate", os.path.join(ROOT, "scenarios", SCENARIOS[rsu]),
                        "--without-vehicles", "--frames", "3", "--out", out], check=True, stdout=subprocess.DEVNULL,
                       timeout=60)
        return sorted(os.path.join(out, f) for f in os.listdir(out) if f.endswith(".pcd"))

    def start_rsud(self, rsu, domain):
        lidar_port, v2i_port = free_udp_port(), free_udp_port()
        x, y = MOUNTS[rsu]
        config = self.path("rsud_%d.yaml" % rsu)
        with open(config, "w") as f:
            f.write("""rsu_id: %d
lidar:
  model: vlp16
  mount: {x: %s, y: %s, z: 2.0}
  input:
    velodyne_udp: {bind_address: 127.0.0.1, port: %d}
background:
  pcd_files: [%s]
perception:
  coverage_radius_m: %s
v2i:
  listen_address: 127.0.0.1
  port: %d
security:
%s
dds:
  enabled: true
  domain_id: %d
  cyclone_config: %s
  peers:
    enabled: true
%s
logging:
  level: info
  bad_input_log_first: 3
  summary_interval_s: 1.0
  stats_interval_s: 0.5
  stats_file: %s
""" % (rsu, x, y, lidar_port, ", ".join(self.background(rsu)), COVERAGE_M, v2i_port,
                # bad_peers publishes unsigned announcements: it is about the bus, not signatures.
                "  mode: insecure" if self.args.case == "bad_peers" else
                "  key_file: keys/rsu%d.key\n  trust_list_file: keys/rsu_trust.list" % rsu, domain,
                os.path.join(ROOT, "deploy", "cyclonedds-loopback.xml"),
                # bad_peers: a per-origin limit well below what reaches rsud of its flood, whatever the load.
                "    rate_per_s: 100.0\n    burst: 100" if self.args.case == "bad_peers" else "",
                self.path("stats_%d" % rsu)))
        log = self.path("rsud_%d.log" % rsu)
        proc = self.children.spawn([self.args.rsud, "--config", config], log)
        self.rsud[rsu] = {"proc": proc, "log": log, "lidar_port": lidar_port, "v2i_port": v2i_port}

    def stats(self, rsu):
        values = {}
        for line in read_text(self.path("stats_%d" % rsu)).splitlines():
            k, v = line.split()
            values[k] = float(v)
        return values

    def stop_rsud(self, rsu):
        r = self.rsud[rsu]
        r["proc"].send_signal(signal.SIGTERM)
        rc = r["proc"].wait(timeout=10)
        assert rc == 0, "rsud %d exited with %d on SIGTERM:\n%s" % (rsu, rc, read_text(r["log"])[-3000:])

    def corrections(self):
        rows = []
        lines = read_text(self.path("corrections.csv")).splitlines()
        header = lines[0].split(",")
        for line in lines[1:]:
            rows.append(dict(zip(header, line.split(","))))
        return rows


def own_domain():
    """A DDS domain of this run's own: other tests and demos on this host use the loopback configuration too.
    Above 199: the DDS tests that run beside this one take theirs from 100-199 (the participant and sidecar
    tests, the DDS benchmark's smoke run). In one CI run bad_peers counted 18 valid peer announcements
    it had not sent (peer.accepted 28 against 10, a second vehicle registered) while the sidecar test ran
    beside it: a shared domain is the likely cause, not proven. This case
    and the handover hold one lock (rsud_cpu), so they never run together."""
    return random.Random(os.getpid() ^ time.time_ns()).randint(200, 230)


def drive(run):
    domain = own_domain()
    for rsu in (1, 2):
        run.start_rsud(rsu, domain)
    for rsu in (1, 2):
        r = run.rsud[rsu]
        wait_for_line(r["log"], "ready: serving", 20, watch=r["proc"])
    # Each sees the other's announcement writer before the drive starts (discovery on loopback).
    for rsu in (1, 2):
        r = run.rsud[rsu]
        wait_for_line(r["log"], "peer bus: 1 other RSU(s)", 10, watch=r["proc"])

    # One clock: scenario time 0 is `epoch` on the host clock, for the packets and the vehicle.
    epoch = time.time_ns() + 1_000_000_000
    streams = [run.children.spawn([run.args.rsu_sim, "stream", os.path.join(ROOT, "scenarios", SCENARIOS[rsu]),
                                   "--to", "127.0.0.1:%d" % run.rsud[rsu]["lidar_port"], "--epoch-ns", str(epoch),
                                   "--start", "0", "--seconds", str(DRIVE_S + 0.3)],
                                  run.path("stream_%d.log" % rsu)) for rsu in (1, 2)]
    # The vehicle's own poses at 10 Hz: the truth 0.29 m and 1 deg off (an NDT with a bias).
    ndt = run.path("ndt.csv")
    with open(ndt, "w") as f:
        f.write("time_ns,x,y,yaw\n")
        for k in range(int(DRIVE_S * 10) + 1):
            x, y, yaw = truth_at(k * 0.1)
            f.write("%d,%.4f,%.4f,%.5f\n" % (epoch + k * 100_000_000, x + NDT_BIAS[0], y + NDT_BIAS[1],
                                              yaw + NDT_BIAS[2]))
    time.sleep(max(0.0, epoch / 1e9 - time.time()))
    vehicle = run.children.spawn([run.args.vehicle, "--vehicle-id", "1", "--rsu",
                                  "127.0.0.1:%d" % run.rsud[1]["v2i_port"], "--bind", "127.0.0.1:0", "--realtime",
                                  "--drain-ms", "300", "--corrections", run.path("corrections.csv"),
                                  "--key", run.path("keys/car.key"), "--trust-list", run.path("keys/vehicle_trust.list")],
                                 run.path("fused.csv"), stdin_path=ndt, stderr_path=run.path("vehicle.err"))
    for p in streams + [vehicle]:
        wait_for(lambda: p.poll() is not None, DRIVE_S + 15, "the drive to end")
    assert vehicle.returncode == 0, read_text(run.path("vehicle.err"))
    for rsu in (1, 2):
        run.stop_rsud(rsu)
    return epoch


def check(run, epoch):
    rows = run.corrections()
    fixes = []
    for r in rows:
        t = (int(r["time_ns"]) - epoch) * 1e-9
        tx, ty, tyaw = truth_at(t)
        c = [[float(r["cxx"]), float(r["cxy"])], [float(r["cxy"]), float(r["cyy"])]]
        fixes.append({"rsu": int(r["rsu_id"]), "t": t, "fused": r["fusion"] == "accepted", "ex": float(r["x"]) - tx, "ey": float(r["y"]) - ty,
                      "eyaw": yaw_mod_pi(float(r["yaw"]) - tyaw), "c": c, "vyaw": float(r["cyawyaw"]),
                      "x": tx})
    fixes.sort(key=lambda f: f["t"])
    per_rsu = {rsu: sum(1 for f in fixes if f["rsu"] == rsu) for rsu in (1, 2)}
    assert per_rsu[1] > 0 and per_rsu[2] > 0, "corrections per RSU: %s" % per_rsu
    fused_per_rsu = {rsu: sum(1 for f in fixes if f["rsu"] == rsu and f["fused"]) for rsu in (1, 2)}
    assert fused_per_rsu[1] > 0 and fused_per_rsu[2] > 0, "corrections fused per RSU: %s" % fused_per_rsu
    s1, s2 = run.stats(1), run.stats(2)
    assert s2.get("peer.accepted", 0) > 0 and s2.get("datagram.accepted", 0) == 0, \
        "east RSU: peer.accepted %s, datagram.accepted %s" % (s2.get("peer.accepted"), s2.get("datagram.accepted"))
    assert s1.get("peer.accepted", 0) == 0, "nothing flows back to the west RSU: %s" % s1.get("peer.accepted")

    assert fixes[0]["t"] < 0.3, "first correction at t = %.3f s" % fixes[0]["t"]
    assert fixes[-1]["t"] > DRIVE_S - 0.3, "last correction at t = %.3f s" % fixes[-1]["t"]
    gaps = [(b["t"] - a["t"], a["x"]) for a, b in zip(fixes, fixes[1:])]
    max_gap, gap_x = max(gaps)
    assert max_gap <= MAX_GAP_S, "a gap of %.3f s at x = %.1f m" % (max_gap, gap_x)

    worst_jump = (0.0, 1.0, None)  # (|d|, bound, where)
    worst_yaw_jump = (0.0, 1.0, None)
    for a, b in zip(fixes, fixes[1:]):
        dx, dy = b["ex"] - a["ex"], b["ey"] - a["ey"]
        n = math.hypot(dx, dy)
        if n > 0:
            ux, uy = dx / n, dy / n
            cc = [[a["c"][i][j] + b["c"][i][j] for j in range(2)] for i in range(2)]
            bound = JUMP_SIGMAS * math.sqrt(ux * (cc[0][0] * ux + cc[0][1] * uy) + uy * (cc[1][0] * ux + cc[1][1] * uy))
            assert n <= bound, "jump of %.3f m > %.3f m (3 sigma) at x = %.1f m, rsu %d -> %d" % (
                n, bound, b["x"], a["rsu"], b["rsu"])
            if n / bound > worst_jump[0] / worst_jump[1]:
                worst_jump = (n, bound, b["x"])
        dyaw = abs(yaw_mod_pi(b["eyaw"] - a["eyaw"]))
        ybound = JUMP_SIGMAS * math.sqrt(a["vyaw"] + b["vyaw"])
        assert dyaw <= ybound, "yaw jump of %.4f rad > %.4f rad (3 sigma) at x = %.1f m" % (dyaw, ybound, b["x"])
        if dyaw / ybound > worst_yaw_jump[0] / worst_yaw_jump[1]:
            worst_yaw_jump = (dyaw, ybound, b["x"])

    errors = [math.hypot(f["ex"], f["ey"]) for f in fixes]
    yaw_z = [abs(f["eyaw"]) / math.sqrt(f["vyaw"]) for f in fixes]
    both = [f for f in fixes if 12.0 <= f["x"] <= 28.0]
    print("handover: corrections per RSU %s (%d in the overlap 12..28 m: %s); largest gap %.0f ms at x = %.1f m; "
          "largest jump %.3f m vs its 3-sigma bound %.3f m (at x = %.1f m), yaw %.4f vs %.4f rad; "
          "error mean %.3f m, max %.3f m; yaw error max %.2f deg, at most %.2f stated sigma" % (
              per_rsu, len(both), {rsu: sum(1 for f in both if f["rsu"] == rsu) for rsu in (1, 2)},
              max_gap * 1e3, gap_x, worst_jump[0], worst_jump[1], worst_jump[2], worst_yaw_jump[0],
              worst_yaw_jump[1], sum(errors) / len(errors), max(errors),
              math.degrees(max(abs(f["eyaw"]) for f in fixes)), max(yaw_z)))
    print("east RSU: peer.accepted %d, peer.not_fresher %d; west RSU: peer.from_self %d" % (
        s2.get("peer.accepted", 0), s2.get("peer.not_fresher", 0), s1.get("peer.from_self", 0)))
    fused = []
    lines = read_text(run.path("fused.csv")).splitlines()
    header = lines[0].split(",")
    for line in lines[1:]:
        r = dict(zip(header, line.split(",")))
        t = (int(r["time_ns"]) - epoch) * 1e-9
        tx, ty, _ = truth_at(t)
        if t >= 0.5:
            fused.append(math.hypot(float(r["x"]) - tx, float(r["y"]) - ty))
    print("vehicle: fused corrections per RSU %s; its fused pose from t = 0.5 s: %d estimates, error mean %.3f m, "
          "max %.3f m (its own poses: %.3f m)" % (fused_per_rsu, len(fused), sum(fused) / len(fused), max(fused),
                                                  math.hypot(NDT_BIAS[0], NDT_BIAS[1])))
    assert max(fused) <= MAX_FUSED_ERROR_M, "the fused pose is %.3f m off" % max(fused)
    for f, e in zip(fixes, errors):
        assert e <= MAX_ERROR_M, "correction by rsu %d at x = %.1f m is %.3f m off" % (f["rsu"], f["x"], e)
        assert abs(f["eyaw"]) <= YAW_SIGMAS * math.sqrt(f["vyaw"]), \
            "yaw off by %.2f deg at x = %.1f m, beyond %g stated sigma (%.2f deg)" % (
                math.degrees(f["eyaw"]), f["x"], YAW_SIGMAS, math.degrees(math.sqrt(f["vyaw"])))


def bad_peers(run):
    """A misbehaving peer on the bus (rsud_test_peer_publisher): every bad sample counted by reason, logged at a
    bounded rate, a flood from one origin limited, and a well-behaved peer's vehicle still registered."""
    domain = own_domain()
    run.start_rsud(2, domain)
    r = run.rsud[2]
    wait_for_line(r["log"], "ready: serving", 20, watch=r["proc"])
    go = run.path("go")
    os.makedirs(go, exist_ok=True)
    publisher = run.children.spawn([run.args.peer_publisher, "--domain", str(domain), "--cyclone-config",
                                    os.path.join(ROOT, "deploy", "cyclonedds-loopback.xml"), "--topic",
                                    "rsu/peer_announcements", "--rsu-id", "2", "--flood", "5000",
                                    "--go-dir", go],
                                   run.path("publisher.out"))
    # Each phase waits for rsud, not for a fixed time: under TSan and a loaded host, rsud's reader matched
    # late or took late, and the 12 bad samples were lost to best effort or pushed out by the flood.
    wait_for_line(r["log"], "peer bus: 1 other RSU(s)", 20, watch=r["proc"])
    open(os.path.join(go, "bad"), "w").close()
    reasons = ("peer:decode:parse_error", "peer:reply_to_mismatch:address", "peer:from_self", "peer_sample")
    wait_for(lambda: all(read_text(r["log"]).count("bad input (%s)" % k) >= 3 for k in reasons), 20,
             "rsud to log the 12 bad samples", watch=r["proc"], watch_log=r["log"])
    open(os.path.join(go, "flood"), "w").close()
    wait_for(lambda: publisher.poll() is not None, 30, "the peer publisher to finish")
    assert publisher.returncode == 0, read_text(run.path("publisher.out"))
    wait_for_line(r["log"], "vehicle 9 registered from RSU 79", 3, watch=r["proc"])
    time.sleep(1.2)  # a stats interval and a bad-input summary after the last sample
    assert r["proc"].poll() is None, "rsud died:\n" + read_text(r["log"])[-3000:]
    run.stop_rsud(2)
    s = run.stats(2)
    expect = {"peer.reply_to_mismatch": 3, "peer.from_self": 3, "peer_bus.received_malformed": 3,
              "peer.accepted": 10, "peer_bus.shared": 0}
    for k, v in expect.items():
        assert s.get(k) == v, "%s = %s, expected %d" % (k, s.get(k), v)
    # The garbage: 3, and the flood's first burst (100, as configured) before the per-origin limit cut in;
    # with best-effort QoS and the reader's KEEP_LAST history some of the flood never reaches rsud.
    assert s["peer.decode"] >= 3 + 100 - 1, s["peer.decode"]
    assert s["peer.flood_limited"] > 0, s["peer.flood_limited"]
    assert s["peer.decode"] + s["peer.flood_limited"] <= 3 + 5000, s
    log = read_text(r["log"])
    for reason in ("peer:decode:parse_error", "peer:reply_to_mismatch:address", "peer:from_self"):
        n = log.count("bad input (%s)" % reason)
        assert 1 <= n <= 3, "%d log lines for %s (at most 3 one by one)" % (n, reason)
    assert "rsu_id must be unique" in log, log[-3000:]
    assert log.count("\n") < 200, "the bad peer flooded the log (%d lines)" % log.count("\n")
    print("bad peers: counted %s" % {k: int(s[k]) for k in sorted(s) if k.startswith(("peer.", "peer_bus.")) and s[k]})


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("case", nargs="?", default="handover", choices=["handover", "bad_peers"])
    ap.add_argument("--rsud", required=True)
    ap.add_argument("--rsu-sim", required=True)
    ap.add_argument("--vehicle", required=True, help="rsu-vehicle")
    ap.add_argument("--peer-publisher", help="rsud_test_peer_publisher (the bad_peers case)")
    ap.add_argument("--keygen", required=True, help="rsu-keygen")
    ap.add_argument("--work", required=True)
    args = ap.parse_args()
    # Absolute: rsud resolves the paths in its configuration relative to the configuration's folder.
    args.work = os.path.abspath(args.work)
    run = Run(args)
    try:
        if args.case == "bad_peers":
            bad_peers(run)
        else:
            check(run, drive(run))
    except (AssertionError, TimeoutError, ChildExited, subprocess.CalledProcessError) as e:
        print("FAIL: %s" % e)
        for rsu, r in run.rsud.items():
            print("---- rsud %d log (tail) ----\n%s" % (rsu, read_text(r["log"])[-2500:]))
        return 1
    finally:
        run.children.kill_all()
    return 0


if __name__ == "__main__":
    sys.exit(main())
