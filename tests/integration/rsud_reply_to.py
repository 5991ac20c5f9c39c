#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""reply_to and refusal notices (issue 14 item 6) through the real processes, signed as deployed: the real
rsud (no LiDAR needed: announcements are judged while it learns its background), the real `rsu-vehicle`
and rsud_test_send, keys and trust lists made by rsu-keygen, all on loopback.

  1. rsu-vehicle announces for 2.5 s with a reply_to address that is not the one it sends from
     (--reply-address 127.0.0.2, bound to 127.0.0.1): rsud refuses every announcement
     (datagram.reply_to_mismatch, reply_to.address) and sends the vehicle signed refusal notices, at most
     one per second; the vehicle verifies them, counts every one by reason (refusal.reply_to_mismatch
     equals rsud's refusal.notices), logs the reason once (the same reason is not logged again within a
     minute) and keeps the latest in its stats (refusal.last reply_to_mismatch:address).
  2. A signed announcement whose reply_to has the sender's address but another port (rsud_test_send
     --reply-port) is refused as well: reply_to.port, logged as reply_to_mismatch:port.
  3. SIGHUP with v2i.reply_to: use_source (the operator's setting for vehicles behind NAT): the same
     vehicle is registered (reply_to.replaced counts its announcements), no refusal notice follows.

Every wait is bounded; children are killed on the way out.
"""
import argparse
import os
import shutil
import signal
import subprocess
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools", "python"))
from rsu_processes import ChildExited, Children, free_udp_port, read_text, wait_for  # noqa: E402

VEHICLE_ID = 7
RSU_ID = 1


class Run:
    def __init__(self, args):
        self.args = args
        self.work = args.work
        shutil.rmtree(self.work, ignore_errors=True)
        os.makedirs(self.work)
        self.children = Children()
        self.v2i_port = free_udp_port()
        self.rsud = None

    def path(self, name):
        return os.path.join(self.work, name)

    def keygen(self, *words):
        r = subprocess.run([self.args.keygen] + list(words), capture_output=True, text=True, timeout=30)
        assert r.returncode == 0, r.stdout + r.stderr

    def make_keys(self):
        self.keygen(self.path("rsu"), "--trust-list", self.path("vehicle_trust.list"), "--role", "rsu", "--ids",
                    str(RSU_ID))
        self.keygen(self.path("car"), "--trust-list", self.path("rsu_trust.list"), "--role", "vehicle", "--ids",
                    str(VEHICLE_ID))

    def write_config(self, reply_to):
        with open(self.path("rsud.yaml"), "w") as f:
            f.write("""rsu_id: %d
lidar:
  model: vlp16
  mount: {x: 0, y: 0, z: 2, roll_deg: 0, pitch_deg: 0, yaw_deg: 0}
  input:
    velodyne_udp: {bind_address: 127.0.0.1, port: %d}
background:
  learning_frames: 3
v2i:
  listen_address: 127.0.0.1
  port: %d
  reply_to: %s
security: {mode: signed, key_file: %s, trust_list_file: %s}
logging:
  level: info
  stats_interval_s: 0.2
  stats_file: %s
""" % (RSU_ID, free_udp_port(), self.v2i_port, reply_to, self.path("rsu.key"), self.path("rsu_trust.list"),
                self.path("stats")))

    def start_rsud(self):
        self.rsud = self.children.spawn([self.args.rsud, "--config", self.path("rsud.yaml")], self.path("rsud.log"))
        wait_for(lambda: "listening for V2I announcements" in read_text(self.path("rsud.log")), 10,
                 "rsud to listen", watch=self.rsud)

    def stats(self, name="stats"):
        values = {}
        for line in read_text(self.path(name)).splitlines():
            k, v = line.split(" ", 1)
            values[k] = v
        return values

    def vehicle(self, name, seconds, reply_address):
        """rsu-vehicle announcing a standing car's own pose at 10 Hz for `seconds`; returns its stats."""
        start = time.time_ns() + 200_000_000
        ndt = self.path(name + ".csv")
        with open(ndt, "w") as f:
            f.write("time_ns,x,y,yaw\n")
            for k in range(int(seconds * 10) + 1):
                f.write("%d,10.0,2.0,0.5\n" % (start + k * 100_000_000))
        p = self.children.spawn([self.args.vehicle, "--vehicle-id", str(VEHICLE_ID), "--rsu",
                                 "127.0.0.1:%d" % self.v2i_port, "--bind", "127.0.0.1:0", "--reply-address",
                                 reply_address, "--realtime", "--drain-ms", "300", "--key", self.path("car.key"),
                                 "--trust-list", self.path("vehicle_trust.list"), "--stats",
                                 self.path(name + ".stats")],
                                self.path(name + ".out"), stdin_path=ndt, stderr_path=self.path(name + ".err"))
        wait_for(lambda: p.poll() is not None, seconds + 10, "rsu-vehicle to finish")
        assert p.returncode == 0, read_text(self.path(name + ".err"))
        return self.stats(name + ".stats")


def count(stats, key):
    return int(float(stats.get(key, "0")))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rsud", required=True)
    ap.add_argument("--vehicle", required=True)
    ap.add_argument("--send", required=True)
    ap.add_argument("--keygen", required=True)
    ap.add_argument("--work", required=True)
    run = Run(ap.parse_args())
    try:
        run.make_keys()
        run.write_config("match_address_and_port")
        run.start_rsud()

        # 1. reply_to names another address than the one the vehicle sends from.
        v = run.vehicle("vehicle_wrong_address", 2.5, "127.0.0.2")
        time.sleep(0.5)  # the stats file rewritten
        s = run.stats()
        refused = count(s, "datagram.reply_to_mismatch")
        assert refused >= 20 and count(s, "reply_to.address") == refused, s
        assert count(s, "datagram.accepted") == 0 and count(s, "registry.vehicles") == 0, s
        notices = count(s, "refusal.notices")
        assert 2 <= notices <= 4, "%d refusal notices in 2.5 s (one per second)" % notices
        assert count(s, "refusal.rate_limited") == refused - notices, s
        assert count(v, "refusal.reply_to_mismatch") == notices, (v, notices)
        assert v.get("refusal.last") == "reply_to_mismatch:address", v
        assert count(v, "refusal.validation") == 0 and count(v, "refusal.registry") == 0, v
        err = read_text(run.path("vehicle_wrong_address.err"))
        lines = [l for l in err.splitlines() if "refused announcement" in l]
        assert len(lines) == 1 and "reply_to_mismatch (address)" in lines[0] and "RSU 1 " in lines[0], err
        assert "announcements refused by RSUs reply_to_mismatch=%d" % notices in err, err

        # 2. The sender's address, another port.
        for seq in (1, 2):
            r = subprocess.run([run.args.send, "--to", "127.0.0.1:%d" % run.v2i_port, "--kind", "announcement",
                                "--id", str(VEHICLE_ID), "--key", run.path("car.key"), "--seq", str(1000 + seq),
                                "--reply-port", str(free_udp_port())], capture_output=True, text=True, timeout=10)
            assert r.returncode == 0, r.stdout + r.stderr
        wait_for(lambda: count(run.stats(), "reply_to.port") == 2, 3, "two port mismatches counted",
                 watch=run.rsud)
        assert "reply_to_mismatch:port" in read_text(run.path("rsud.log")), read_text(run.path("rsud.log"))[-2000:]

        # 3. The operator allows NAT: the same vehicle is served at its source.
        run.write_config("use_source")
        run.rsud.send_signal(signal.SIGHUP)
        wait_for(lambda: read_text(run.path("rsud.log")).count("configuration reloaded") == 1, 5, "the reload",
                 watch=run.rsud)
        notices_before = count(run.stats(), "refusal.notices")
        v = run.vehicle("vehicle_behind_nat", 1.5, "127.0.0.2")
        time.sleep(0.5)
        s = run.stats()
        accepted = count(s, "datagram.accepted")
        # Every announcement of the vehicle had its reply_to replaced, and none was refused after that (the
        # client sends them in sequence order: a keep-alive never overtakes the announcement before it).
        assert accepted >= 10 and count(s, "reply_to.replaced") == accepted, s
        assert count(s, "datagram.registry") == 0 and count(s, "registry.stale_sequence") == 0, s
        assert count(s, "refusal.notices") == notices_before, s
        assert count(v, "refusal.reply_to_mismatch") == 0, v
        assert "vehicle %d registered from 127.0.0.1:" % VEHICLE_ID in read_text(run.path("rsud.log"))
        run.rsud.send_signal(signal.SIGTERM)
        assert run.rsud.wait(timeout=10) == 0
        print("ok: %d announcements with a foreign reply_to address refused, %d refusal notices (%d held back), "
              "every one verified and counted by the vehicle, one log line; 2 port mismatches refused; behind "
              "NAT (use_source) %d accepted at their source" % (refused, notices, refused - notices, accepted))
        return 0
    except (AssertionError, TimeoutError, ChildExited) as e:
        print("FAIL: %s" % e)
        print("---- rsud log (tail) ----\n" + read_text(run.path("rsud.log"))[-3000:])
        return 1
    finally:
        run.children.kill_all()


if __name__ == "__main__":
    sys.exit(main())
