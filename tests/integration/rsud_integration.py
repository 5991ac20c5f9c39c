#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Integration tests of rsud over loopback (issues #4, #7): the real rsud, the real `rsu-sim stream`
sending Velodyne VLP-16 packets of a scenario, and a minimal announcing vehicle (rsud_test_announcer).
Keys are made by the real rsu-keygen; messages are signed (proto/v2i.proto) unless a case says not.

  corrections         the vehicle 15.5 m from the LiDAR gets corrections within 0.10 m of the truth
  bad_input           (insecure mode: the case is about malformed input, which Python cannot sign)
                      garbage / truncated / oversized / unknown version / NaN, 0 m, 100 m sizes / a flood
                      from one source: each counted (stats file), logged at a bounded rate, no crash,
                      and the vehicle keeps being served; insecure mode is warned about and in the stats
  restart_and_reload  SIGTERM drains and exits 0; restarted, corrections resume within 1 s without
                      restarting the vehicle; SIGHUP reloads keeping the registry, a broken file is refused
  security            forged corrections (unknown key, a vehicle's key), a replayed correction, replayed
                      and stale announcements, unsigned and unentitled announcements: each dropped and
                      counted by reason at rsud or the vehicle, while the genuine flow keeps working;
                      SIGHUP with a trust list without the vehicle's key revokes it, restoring it resumes

Every wait is bounded in time; every child is killed on the way out, whatever happens.
"""
import argparse
import math
import os
import shutil
import signal
import socket
import struct
import subprocess
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools", "python"))
from rsu_processes import ChildExited, Children, free_udp_port, wait_for  # noqa: E402

TRUTH = (15.0, 4.0, math.radians(20.0))  # the vehicle's footprint centre and yaw (static)


# ---- a hand-written protobuf encoder for an UNSIGNED SignedV2iMessage{V2iPayload{announcement}} -----
# (proto/v2i.proto, version 2). Python has no Ed25519 here: signed datagrams come from the C++ helpers.
def varint(n):
    n &= (1 << 64) - 1
    out = bytearray()
    while True:
        b = n & 0x7F
        n >>= 7
        out.append(b | (0x80 if n else 0))
        if not n:
            return bytes(out)


def field_varint(number, value):
    return varint(number << 3) + varint(value)


def field_double(number, value):
    return varint((number << 3) | 1) + struct.pack("<d", value)


def field_bytes(number, payload):
    return varint((number << 3) | 2) + varint(len(payload)) + payload


def announcement(vehicle_id, seq, length=4.89, width=1.92, height=1.70, version=2, reply=("127.0.0.2", 9)):
    pose = field_double(1, 30.0) + field_double(2, -20.0) + field_double(3, 0.1)
    cov = field_bytes(1, b"".join(struct.pack("<d", v) for v in (0.25, 0, 0, 0, 0.25, 0, 0, 0, 0.01)))
    reply_to = field_bytes(1, reply[0].encode()) + field_varint(2, reply[1])
    now = time.time_ns()
    body = (field_varint(1, vehicle_id) + field_varint(2, seq) + field_varint(3, now) +
            field_double(4, length) + field_double(5, width) + field_double(6, height) +
            field_bytes(9, pose) + field_bytes(10, cov) + field_bytes(13, reply_to))
    payload = field_varint(1, now) + field_varint(2, seq) + field_bytes(3, body)
    return field_varint(1, version) + field_bytes(2, payload)


# ---- the harness ------------------------------------------------------------------------------------
class Harness:
    def __init__(self, args):
        self.args = args
        self.work = args.work
        shutil.rmtree(self.work, ignore_errors=True)
        os.makedirs(self.work)
        self.children = Children()
        self.lidar_port = free_udp_port()
        self.v2i_port = free_udp_port()
        self.rsud = None
        self.rsud_runs = 0
        self.log_path = None
        self.insecure = False

    def keygen(self, *args):
        r = subprocess.run([self.args.keygen] + list(args), capture_output=True, text=True, timeout=30)
        assert r.returncode == 0, r.stdout + r.stderr
        return r.stdout

    def write_keys(self):
        """rsu-keygen: the RSU's key (trusted by the vehicle for rsu ids 1 and 2, the reload's), the car's
        (trusted by rsud for vehicle 1) and mallory's, trusted by nobody."""
        os.makedirs(self.path("keys"))
        self.keygen(self.path("keys/rsu"), "--trust-list", self.path("keys/vehicle_trust.list"), "--role", "rsu",
                    "--ids", "1,2")
        self.keygen(self.path("keys/car"), "--trust-list", self.path("keys/rsu_trust.list"), "--role", "vehicle",
                    "--ids", "1")
        self.keygen(self.path("keys/mallory"))
        assert oct(os.stat(self.path("keys/car.key")).st_mode & 0o777) == "0o600"

    def path(self, name):
        return os.path.join(self.work, name)

    def spawn(self, cmd, out_name):
        return self.children.spawn(cmd, self.path(out_name))

    def write_scenarios(self):
        scene = """lidar:
  model: vlp16
  mount: {x: 0, y: 0, z: 2.0}
  noise: {range_sigma_m: 0.02, angle_sigma_rad: 0.001, seed: 3}
scene:
  ground: {half_extent_m: 60}
  buildings:
    - {x: 0, y: 30, length: 40, width: 10, height: 10}
  poles:
    - {x: -5, y: 3, radius: 0.15, height: 6}
simulation: {start_s: 0.0, frames: 3}
"""
        vehicle = """vehicles:
  - id: 1
    shape: {length: 4.89, width: 1.92, height: 1.70}
    trajectory:
      static: {x: %.3f, y: %.3f, yaw_deg: %.3f}
""" % (TRUTH[0], TRUTH[1], math.degrees(TRUTH[2]))
        with open(self.path("empty.yaml"), "w") as f:
            f.write("name: empty\n" + scene)
        with open(self.path("street.yaml"), "w") as f:
            f.write("name: street\n" + scene + vehicle)
        # The background, recorded once without the vehicle (as an operator would), in the sensor frame.
        r = subprocess.run([self.args.rsu_sim, "simulate", self.path("empty.yaml"), "-o", self.path("bg"),
                            "--frames", "3"], capture_output=True, text=True, timeout=60)
        assert r.returncode == 0, r.stdout + r.stderr
        self.bg = sorted(os.path.join(self.path("bg"), f) for f in os.listdir(self.path("bg")) if f.endswith(".pcd"))
        assert len(self.bg) == 3, self.bg

    def write_config(self, rsu_id=1, broken=False):
        text = """rsu_id: %d
lidar:
  model: vlp16
  mount: {x: 0, y: 0, z: 2.0}
  input:
    velodyne_udp: {bind_address: 127.0.0.1, port: %d}
background:
  pcd_files: [%s]
v2i:
  listen_address: 127.0.0.1
  port: %d
  verifier_thread: %s
logging:
  level: info
  bad_input_log_first: 3
  summary_interval_s: 1.0
  stats_interval_s: 0.5
  stats_file: %s
""" % (rsu_id, self.lidar_port, ", ".join(self.bg), self.v2i_port,
       # The security case checks signatures on rsud's receiver thread (under TSan too); the rest on its loop.
       "true" if self.args.case == "security" else "false", self.path("stats"))
        if self.args.case == "security":
            # ... and prepares the fits and fixes on rsud's preparation thread (under TSan too).
            text += "perception:\n  prepare_thread: true\n"
        if self.insecure:
            text += "security:\n  mode: insecure\n"
        else:
            text += "security:\n  mode: signed\n  key_file: keys/rsu.key\n  trust_list_file: %s\n" % (
                self.path("keys/rsu_trust.list"))
        if broken:
            text = text.replace("model: vlp16", "model: vlp16\n  bogus_key: 1")
        with open(self.path("rsud.yaml"), "w") as f:
            f.write(text)

    def start_rsud(self):
        self.rsud_runs += 1
        self.log_path = self.path("rsud_%d.log" % self.rsud_runs)
        self.rsud = self.spawn([self.args.rsud, "--config", self.path("rsud.yaml")], os.path.basename(self.log_path))
        self.wait_for(lambda: "ready: serving" in self.log(), 10, "rsud to become ready")

    def log(self):
        with open(self.log_path) as f:
            return f.read()

    def start_stream(self, seconds):
        return self.spawn([self.args.rsu_sim, "stream", self.path("street.yaml"), "--to",
                           "127.0.0.1:%d" % self.lidar_port, "--clock", "wall", "--seconds", str(seconds)], "stream.log")

    def start_vehicle(self, seconds):
        pose = "%f,%f,%f" % (TRUTH[0] + 0.4, TRUTH[1] - 0.3, TRUTH[2] + 0.05)  # its own estimate is off
        security = (["--insecure", "1"] if self.insecure else
                    ["--key", self.path("keys/car.key"), "--trust-list", self.path("keys/vehicle_trust.list"),
                     "--dump-bytes", "1"])
        return self.spawn([self.args.announcer, "--rsu", "127.0.0.1:%d" % self.v2i_port, "--bind", "127.0.0.1",
                           "--id", "1", "--pose", pose, "--seconds", str(seconds)] + security, "vehicle.out")

    def vehicle_lines(self, tag):
        """The words of the announcer's lines starting with `tag` (bound, announced, received, refused)."""
        with open(self.path("vehicle.out")) as f:
            return [line.split()[1:] for line in f if line.startswith(tag + " ")]

    def send(self, *args):
        r = subprocess.run([self.args.send] + list(args), capture_output=True, text=True, timeout=30)
        assert r.returncode == 0, r.stdout + r.stderr

    def corrections(self):
        out = []
        with open(self.path("vehicle.out")) as f:
            for line in f:
                w = line.split()
                if len(w) == 14 and w[0] == "correction":
                    out.append({"recv_ns": int(w[1]), "vehicle": int(w[2]), "seq": int(w[3]), "sweep_ns": int(w[4]),
                                "x": float(w[5]), "y": float(w[6]), "yaw": float(w[7]), "points": int(w[8]),
                                "rsu": int(w[10]), "cov": (float(w[11]), float(w[12]), float(w[13]))})
        return out

    def stats(self):
        values = {}
        with open(self.path("stats")) as f:
            for line in f:
                k, v = line.split()
                values[k] = float(v)
        return values

    def wait_for(self, condition, seconds, what):
        wait_for(condition, seconds, what, watch=self.rsud, watch_log=self.log_path)

    def stop_rsud(self):
        self.rsud.send_signal(signal.SIGTERM)
        rc = self.rsud.wait(timeout=10)
        assert rc == 0, "rsud exited with %d on SIGTERM:\n%s" % (rc, self.log())
        assert "SIGTERM received: draining" in self.log() and "stopped:" in self.log(), self.log()


def position_sigmas(c):
    """The position error in standard deviations of the correction's own stated covariance (Mahalanobis)."""
    dx, dy = c["x"] - TRUTH[0], c["y"] - TRUTH[1]
    xx, xy, yy = c["cov"]
    det = xx * yy - xy * xy
    return math.sqrt(max(0.0, (yy * dx * dx - 2 * xy * dx * dy + xx * dy * dy) / det)) if det > 0 else float("inf")


def check_accuracy(corrections, max_error_m=0.10, or_within_sigmas=None):
    """Every correction within max_error_m of the truth; with or_within_sigmas, beyond it only if its own
    stated covariance covers the error by that many sigmas (a fix may be less accurate, never less honest)."""
    assert corrections, "no corrections"
    for c in corrections:
        err = math.hypot(c["x"] - TRUTH[0], c["y"] - TRUTH[1])
        covered = or_within_sigmas is not None and position_sigmas(c) <= or_within_sigmas
        assert err < max_error_m or covered, "correction %s is %.3f m from the truth (%.1f sigma)" % (
            c, err, position_sigmas(c))
        dyaw = abs((c["yaw"] - TRUTH[2] + math.pi / 2) % math.pi - math.pi / 2)  # modulo pi
        assert dyaw < math.radians(3.0), "yaw %f vs %f" % (c["yaw"], TRUTH[2])
        assert c["vehicle"] == 1


def check_accuracy_under_load(corrections):
    """As check_accuracy, where rsud may have been starved of CPU (sanitized, beside a flood, an attack or a
    restart): within 0.10 m, or beyond it (up to 0.25 m) only as far as the stated covariance covers by 3
    sigma. Starved, rsud sheds LiDAR packets (packet.too_late) and fixes the rotation with packets lost
    near the vehicle (README Known shortfalls)."""
    check_accuracy(corrections, max_error_m=0.10, or_within_sigmas=3.0)
    check_accuracy(corrections, max_error_m=0.25)


def case_corrections(h):
    h.start_rsud()
    h.start_stream(4.0)
    vehicle = h.start_vehicle(3.5)
    h.wait_for(lambda: len(h.corrections()) >= 15, 8, "15 corrections")
    cs = h.corrections()
    check_accuracy(cs)
    # One per rotation (10 Hz), consecutive sequence numbers, sweep times in the recent past.
    for a, b in zip(cs, cs[1:]):
        assert b["seq"] == a["seq"] + 1, (a, b)
        assert 50e6 < b["sweep_ns"] - a["sweep_ns"] < 150e6, (a, b)
    for c in cs:
        assert 0 < c["recv_ns"] - c["sweep_ns"] < 50e6, c  # swept at most 50 ms before it arrived
    vehicle.wait(timeout=10)
    h.stop_rsud()
    # Both sockets' receive buffers as the kernel granted them: what rsud asks for by default (8 MiB for
    # V2I, 4 MiB for the LiDAR), capped by net.core.rmem_max.
    with open("/proc/sys/net/core/rmem_max") as f:
        rmem_max = int(f.read())
    s = h.stats()
    for key, asked in (("v2i.receive_buffer_bytes", 8 << 20), ("lidar.receive_buffer_bytes", 4 << 20)):
        assert s.get(key) == min(asked, rmem_max), "%s = %s, expected min(%d, rmem_max %d)" % (
            key, s.get(key), asked, rmem_max)
    print("ok: %d corrections, worst error %.3f m" % (
        len(cs), max(math.hypot(c["x"] - TRUTH[0], c["y"] - TRUTH[1]) for c in cs)))


def case_bad_input(h):
    h.start_rsud()
    h.start_stream(30.0)  # killed at the end; long enough for a slow rsud
    h.start_vehicle(29.5)
    h.wait_for(lambda: len(h.corrections()) >= 3, 5, "first corrections")
    rsu = ("127.0.0.1", h.v2i_port)
    bad = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    bad.bind(("127.0.0.2", 0))
    good = announcement(7, 1)
    cases = {
        "garbage": b"\xde\xad\xbe\xef\xff\xff\xff\xff\xff\x01",
        "truncated": good[: len(good) // 2],
        "oversized": b"\x08" * 2000,
        "version": announcement(7, 2, version=9),
        "nan": announcement(7, 3, length=float("nan")),
        "zero": announcement(7, 4, length=0.0),
        "huge": announcement(7, 5, length=100.0),
    }
    for _ in range(3):
        for payload in cases.values():
            bad.sendto(payload, rsu)
        time.sleep(0.01)
    # A flood from one more source.
    flood = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    flood.bind(("127.0.0.3", 0))
    flood_start = time.monotonic()
    for i in range(5000):
        flood.sendto(b"\xff" * 40, rsu)
    flood_end_ns = time.time_ns()

    # A sanitized rsud on busy cores reads the queued flood for seconds: wait (bounded) until its stats
    # file accounts for every flood datagram, then for a summary interval (the "not logged" line).
    def flood_accounted(s):
        return (s.get("decode.parse_error", 0) - 6 + s.get("datagram.flood_limited", 0) +
                s.get("v2i.kernel_drops", 0))

    h.wait_for(lambda: os.path.exists(h.path("stats")) and flood_accounted(h.stats()) >= 5000, 30,
               "rsud to account for the 5000 flood datagrams")
    flood_read_s = time.monotonic() - flood_start  # at most this long between rsud's first and last read
    time.sleep(1.6)
    assert h.rsud.poll() is None, "rsud died:\n" + h.log()
    served_after = [c for c in h.corrections() if c["recv_ns"] > flood_end_ns]
    assert len(served_after) >= 5, "the vehicle was not served after the flood: %d" % len(served_after)
    # A sanitized rsud reading the flood sheds LiDAR packets (the TSan pass, 2026-11-30: packet.too_late 87)
    # and fixed the next rotation 0.109 m off, stating 1.5 sigma of it.
    check_accuracy_under_load(served_after)
    h.stop_rsud()
    s = h.stats()
    expect = {"decode.too_large": 3, "decode.unsupported_version": 3, "validation.non_finite": 3,
              "validation.length_out_of_range": 6, "security.insecure_mode": 1}
    for k, v in expect.items():
        assert s.get(k) == v, "%s = %s, expected %d" % (k, s.get(k), v)
    # Every flood datagram is accounted for: parsed (3 garbage + 3 truncated besides), refused by the
    # flood limit, or dropped by the kernel before rsud could read it (a slow, e.g. sanitized, rsud on
    # busy cores); the kernel may also have dropped a few of the vehicle's announcements meanwhile.
    drops = s["v2i.kernel_drops"]
    flood_parsed = s["decode.parse_error"] - 6
    flood_accounted = flood_parsed + s["datagram.flood_limited"] + drops
    assert 5000 <= flood_accounted <= 5000 + 20, (flood_parsed, s["datagram.flood_limited"], drops)
    received = 5000 - drops
    assert received >= 1000, "the kernel dropped %d of the 5000 flood datagrams" % drops
    # The flood's first 100 (the burst) are parsed before the limit cuts in, then 200/s refill while rsud
    # reads the queue (the default v2i.datagram_flood), and it refuses the rest.
    most_parsed = 100 + 200 * flood_read_s + 10
    assert 100 <= flood_parsed <= most_parsed, (flood_parsed, most_parsed, flood_read_s)
    assert s["datagram.flood_limited"] >= received - most_parsed, (s["datagram.flood_limited"], received)
    log = h.log()
    for reason in ("decode:parse_error", "decode:too_large", "validation:non_finite"):
        n = log.count("bad input (%s)" % reason)
        assert 1 <= n <= 3, "%d log lines for %s (at most 3 one by one)" % (n, reason)
    assert "not logged one by one since the last summary" in log, log[-3000:]
    assert log.count("\n") < 200, "the bad input flooded the log (%d lines)" % log.count("\n")
    assert "*** INSECURE MODE" in log, "insecure mode was not warned about"
    print("ok: bad input counted %s" % {k: s[k] for k in sorted(s) if k.startswith(("decode.", "validation.", "datagram."))
                                         and s[k] > 0})


def case_restart_and_reload(h):
    h.start_rsud()
    h.start_stream(9.0)
    h.start_vehicle(8.5)
    h.wait_for(lambda: len(h.corrections()) >= 3, 5, "first corrections")
    h.stop_rsud()
    time.sleep(0.3)
    # Restart: the vehicle keeps announcing; corrections must resume within 1 s of rsud's return.
    t_restart = time.time_ns()
    h.start_rsud()
    h.wait_for(lambda: any(c["recv_ns"] > t_restart for c in h.corrections()), 3, "corrections after the restart")
    first = min(c["recv_ns"] for c in h.corrections() if c["recv_ns"] > t_restart)
    resume_s = (first - t_restart) * 1e-9
    assert resume_s <= 1.0, "corrections resumed %.3f s after the restart" % resume_s
    check_accuracy_under_load([c for c in h.corrections() if c["recv_ns"] > t_restart])

    # SIGHUP with a new rsu_id: the registry is kept (no announcement is needed to resume).
    h.write_config(rsu_id=2)
    h.rsud.send_signal(signal.SIGHUP)
    h.wait_for(lambda: "configuration reloaded: 1 of 1 registered vehicle(s) kept, background kept" in h.log(), 3,
               "the reload")
    h.wait_for(lambda: any(c["rsu"] == 2 for c in h.corrections()), 2, "corrections from the reloaded config")
    # A broken file is refused; the old configuration goes on.
    h.write_config(rsu_id=3, broken=True)
    h.rsud.send_signal(signal.SIGHUP)
    h.wait_for(lambda: "reload rejected, keeping the previous configuration" in h.log(), 3, "the refusal")
    assert "lidar.bogus_key: unknown field" in h.log(), h.log()
    t = time.time_ns()
    h.wait_for(lambda: any(c["recv_ns"] > t and c["rsu"] == 2 for c in h.corrections()), 2, "service to go on")
    h.stop_rsud()
    print("ok: resumed %.3f s after the restart; reload kept the registry; broken reload refused" % resume_s)


def hex_bytes(words):
    return bytes.fromhex(words[0])


def case_security(h):
    h.start_rsud()
    h.start_stream(9.0)
    h.start_vehicle(8.5)
    h.wait_for(lambda: len(h.corrections()) >= 3, 5, "first corrections")
    vehicle_port = int(h.vehicle_lines("bound")[0][0])
    to_vehicle = "127.0.0.1:%d" % vehicle_port
    to_rsud = "127.0.0.1:%d" % h.v2i_port
    attacker = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    attacker.bind(("127.0.0.1", 0))  # the vehicle's host address: reply_to checks do not stop replays
    t_attack = time.time_ns()

    # At the vehicle: forged corrections (signed by a key nobody trusts, by the car's own key, which the
    # vehicle does not list as an RSU's, and unsigned), and a genuine correction replayed.
    h.send("--to", to_vehicle, "--kind", "correction", "--id", "1", "--rsu-id", "1", "--key",
           h.path("keys/mallory.key"))
    h.send("--to", to_vehicle, "--kind", "correction", "--id", "1", "--rsu-id", "1", "--key", h.path("keys/car.key"))
    h.send("--to", to_vehicle, "--kind", "correction", "--id", "1", "--rsu-id", "1", "--unsigned", "1")
    attacker.sendto(hex_bytes(h.vehicle_lines("received")[0]), ("127.0.0.1", vehicle_port))

    # At rsud: a genuine announcement replayed now (duplicate) and one from over a second ago (stale),
    # unsigned ones (the Python encoder, the helper), one signed by mallory, one by the car's key for
    # another vehicle id, one from 5 s in the future.
    time.sleep(1.2)  # so that the first announcement is over a second old
    announced = h.vehicle_lines("announced")
    attacker.sendto(hex_bytes(announced[-1]), ("127.0.0.1", h.v2i_port))
    attacker.sendto(hex_bytes(announced[0]), ("127.0.0.1", h.v2i_port))  # > 1 s old by now
    attacker.sendto(announcement(1, 999, reply=("127.0.0.1", vehicle_port)), ("127.0.0.1", h.v2i_port))
    h.send("--to", to_rsud, "--kind", "announcement", "--id", "1", "--unsigned", "1", "--reply-port", str(vehicle_port))
    h.send("--to", to_rsud, "--kind", "announcement", "--id", "1", "--key", h.path("keys/mallory.key"))
    # The car's key for another vehicle, under a sequence number far ahead of the car's own: the helper's
    # default (1) lay inside the car's replay window while it had sent 64 announcements or fewer, and was
    # refused as a duplicate before its subject was checked (the ASan pass, once).
    h.send("--to", to_rsud, "--kind", "announcement", "--id", "2", "--key", h.path("keys/car.key"), "--seq",
           "3000000")
    h.send("--to", to_rsud, "--kind", "announcement", "--id", "1", "--key", h.path("keys/car.key"), "--seq",
           "4000000", "--age-ms", "-5000")
    time.sleep(1.2)  # stats written, corrections flowing
    served_after = [c for c in h.corrections() if c["recv_ns"] > t_attack]
    assert len(served_after) >= 5, "the genuine flow stopped after the attacks: %d" % len(served_after)
    # And no forged fix (2 m off) was taken. In the ASan pass the attackers' helper processes starve rsud,
    # which sheds 61-75 packets (packet.too_late) and fixed the next rotation 0.109 m off.
    check_accuracy_under_load(served_after)
    refused = [w[0] for w in h.vehicle_lines("refused")]
    expect_vehicle = {"unknown_signer": 2, "unsigned": 1, "duplicate": 1}
    for reason, n in expect_vehicle.items():
        assert refused.count(reason) == n, "vehicle refused %s: %s" % (reason, refused)
    assert len(refused) == 4, refused
    s = h.stats()
    expect_rsud = {"auth.duplicate": 1, "auth.stale": 1, "auth.unsigned": 2, "auth.unknown_signer": 1,
                   "auth.wrong_subject": 1, "auth.future": 1, "auth.bad_signature": 0,
                   "auth.accepted_unverified": 0, "security.insecure_mode": 0}
    for k, v in expect_rsud.items():
        assert s.get(k) == v, "%s = %s, expected %d" % (k, s.get(k), v)
    assert s["auth.accepted"] >= 20, s["auth.accepted"]
    # Every signature was checked on the receiver thread (v2i.verifier_thread), none again on the loop.
    assert s.get("auth.signatures_verified", 0) == 0 and s["auth.signatures_checked_ahead"] >= s["auth.accepted"], s
    assert "bad input (auth:unsigned)" in h.log(), h.log()[-3000:]
    # Fits and fixes were prepared on rsud's preparation thread (perception.prepare_thread) and recorded.
    assert s.get("lidar.fixes_prepared", 0) > 0 and s.get("lidar.preparations_dropped_busy", 0) == 0, s

    # SIGHUP with the car's key revoked: its announcements are refused, it expires, no corrections;
    # the key restored, service resumes.
    trust = h.path("keys/rsu_trust.list")
    with open(trust) as f:
        listed = f.read()
    with open(trust, "w") as f:
        f.write("# nobody\n")
    h.rsud.send_signal(signal.SIGHUP)
    h.wait_for(lambda: "trust list of 0 key(s) in effect" in h.log(), 3, "the revoking reload")
    before = h.stats()["auth.unknown_signer"]
    h.wait_for(lambda: h.stats()["auth.unknown_signer"] >= before + 5, 3, "the car's announcements refused")
    with open(trust, "w") as f:
        f.write(listed)
    h.rsud.send_signal(signal.SIGHUP)
    h.wait_for(lambda: "trust list of 1 key(s) in effect" in h.log(), 3, "the restoring reload")
    t = time.time_ns()
    h.wait_for(lambda: any(c["recv_ns"] > t for c in h.corrections()), 3, "corrections after the key was restored")
    h.stop_rsud()
    s = h.stats()
    assert "auth.malformed" not in s, "undecodable datagrams are counted once, as decode.*"
    verdicts = ("unsigned", "malformed_signature", "unknown_signer", "bad_signature", "wrong_role",
                "wrong_subject", "stale", "future", "duplicate", "too_old")
    tried = s["auth.accepted"] + sum(s["auth." + v] for v in verdicts)
    print("ok: rsud: %d announcements tried, %d accepted, refused %s; vehicle refused %s" % (
        tried, s["auth.accepted"], {v: int(s["auth." + v]) for v in verdicts if s["auth." + v] > 0}, expect_vehicle))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("case", choices=["corrections", "bad_input", "restart_and_reload", "security"])
    ap.add_argument("--rsud", required=True)
    ap.add_argument("--rsu-sim", required=True)
    ap.add_argument("--announcer", required=True)
    ap.add_argument("--send", required=True)
    ap.add_argument("--keygen", required=True)
    ap.add_argument("--work", required=True)
    args = ap.parse_args()
    h = Harness(args)
    try:
        h.insecure = args.case == "bad_input"
        h.write_keys()
        h.write_scenarios()
        h.write_config()
        {"corrections": case_corrections, "bad_input": case_bad_input,
         "restart_and_reload": case_restart_and_reload, "security": case_security}[args.case](h)
    except (AssertionError, TimeoutError, ChildExited) as e:
        print("FAIL: %s" % e)
        if h.log_path and os.path.exists(h.log_path):
            print("---- rsud log (tail) ----\n" + h.log()[-4000:])
        return 1
    finally:
        h.children.kill_all()
    return 0


if __name__ == "__main__":
    sys.exit(main())
