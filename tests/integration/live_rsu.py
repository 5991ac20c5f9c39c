# SPDX-License-Identifier: Apache-2.0
"""One RSU on loopback, for the fault, load and mis-association tests (issue 7): the real rsud fed by the
real `rsu-sim stream` (Velodyne packets of a scenario, paced on the host clock from a shared epoch) and the
real vehicles of `rsu-fleet` (announcing the scenario vehicles' true poses on the same clock, printing every
correction with its error against the truth of every vehicle).

  LiveRsu(work, tools, scenario)  work folder, tool paths (rsud, rsu_sim, fleet), scenario file
    .record_background()          the scene without vehicles (rsu-sim simulate), loaded by rsud at start
    .write_config(**options)      rsud.yaml (VLP model from the scenario; options below)
    .start_rsud() / .kill_rsud()  start and wait for "ready: serving" / SIGKILL
    .kill_and_restart()           SIGKILL and start again: when, and how soon ready and serving
    .stream(start_s, seconds, ..) rsu-sim stream on the shared epoch (loss / reorder options)
    .fleet(until_s, ..)           rsu-fleet on the shared epoch, announcing until scenario time until_s
    .corrections(path)            the fleet's correction lines as dicts
    .stats()                      rsud's stats file (counters)
  run_case(case, work, tools, scenario)  a test case's exit code, the rsud log's tail on failure

Every wait is bounded; children are killed by .close().
"""
import os
import shutil
import signal
import subprocess
import sys
import time

import yaml

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools", "python"))
from rsu_processes import ChildExited, Children, free_udp_port, read_text, wait_for  # noqa: E402

ROTATION_S = 0.1  # 600 rpm (docs/design.md §2)


class LiveRsu:
    def __init__(self, work, tools, scenario, lead_s=1.0):
        self.work = work
        shutil.rmtree(work, ignore_errors=True)
        os.makedirs(work)
        self.tools = tools  # dict: rsud, rsu_sim, fleet
        self.scenario = os.path.abspath(scenario)
        with open(self.scenario) as f:
            self.scene = yaml.safe_load(f)
        self.model = self.scene["lidar"]["model"]
        self.children = Children()
        self.lidar_port = free_udp_port()
        self.v2i_port = free_udp_port()
        self.rsud = None
        self.rsud_runs = 0
        self.log_path = None
        self.background = []
        self.trust_list = None  # signed mode: the fleet's trust list (make_keys)
        # An Ouster instead of the scenario's Velodyne (use_ouster): rsu-sim stream --ouster's options,
        # the metadata it writes and rsud reads.
        self.ouster_options = None
        self.metadata = self.path("ouster_metadata.json")
        # Scenario time 0 on the host clock, shared by the stream and the fleet (docs/design.md §3).
        self.epoch_ns = time.time_ns() + int(lead_s * 1e9)

    def path(self, name):
        return os.path.join(self.work, name)

    def close(self):
        self.children.kill_all()

    # ---- rsud ----------------------------------------------------------------------------------------
    def use_ouster(self, model, lidar_mode, profile):
        """The LiDAR is a simulated Ouster (rsu-sim stream --ouster): rsud decodes its lidar packets with the
        metadata the stream writes (start a stream before rsud; wait_for_metadata)."""
        self.model = model
        self.ouster_options = ["--ouster", model, "--lidar-mode", lidar_mode, "--profile", profile,
                               "--metadata-out", self.metadata]

    def wait_for_metadata(self, seconds=10):
        wait_for(lambda: os.path.exists(self.metadata) and read_text(self.metadata).rstrip().endswith("}"),
                 seconds, "rsu-sim stream to write the Ouster's metadata")

    def record_background(self, frames=3):
        out = self.path("background")
        r = subprocess.run([self.tools["rsu_sim"], "simulate", self.scenario, "--without-vehicles", "--frames",
                            str(frames), "--out", out], capture_output=True, text=True, timeout=120)
        assert r.returncode == 0, r.stdout + r.stderr
        self.background = sorted(os.path.join(out, f) for f in os.listdir(out) if f.endswith(".pcd"))
        assert len(self.background) == frames, self.background

    def make_keys(self):
        """Signed mode: the RSU's key (rsu-keygen) and the fleet's trust list (rsu-fleet's test keys)."""
        r = subprocess.run([self.tools["keygen"], self.path("rsu")], capture_output=True, text=True, timeout=30)
        assert r.returncode == 0, r.stdout + r.stderr
        self.trust_list = self.path("fleet.trust")

    def write_config(self, reorder_packets=0, capacity=256, learning_frames=None, extra="", signed=False,
                     verifier_thread=False, advertise_port=None, verify_beyond_coverage=None):
        """rsud.yaml; signed: verify the fleet's signatures (call make_keys() and write the fleet's trust
        list first, fleet(write_trust_list=...)), else insecure mode; verifier_thread: rsud's
        v2i.verifier_thread (False: announcements read and verified on its event loop's thread);
        advertise_port: rsud advertises to 127.0.0.1:advertise_port every 0.2 s; verify_beyond_coverage:
        security.verify_beyond_coverage_m (a margin in m, or "all"; None: rsud's default)."""
        mount = self.scene["lidar"].get("mount", {})
        lidar_input = "%s: {bind_address: 127.0.0.1, port: %d%s}" % (
            "udp" if self.ouster_options else "velodyne_udp", self.lidar_port,
            ", reorder_packets: %d" % reorder_packets if reorder_packets else "")
        background = ("learning_frames: %d" % learning_frames if learning_frames is not None
                      else "pcd_files: [%s]" % ", ".join(self.background))
        text = """rsu_id: 1
lidar:
  model: %s%s
  mount: {x: %s, y: %s, z: %s, roll_deg: %s, pitch_deg: %s, yaw_deg: %s}
  input:
    %s
background:
  %s
v2i:
  listen_address: 127.0.0.1
  port: %d
  verifier_thread: %s
%ssecurity:
  %s
registry:
  capacity: %d
logging:
  level: info
  stats_interval_s: 0.5
  stats_file: %s
%s""" % (self.model, "\n  metadata: %s" % self.metadata if self.ouster_options else "", mount.get("x", 0), mount.get("y", 0), mount.get("z", 0), mount.get("roll_deg", 0),
         mount.get("pitch_deg", 0), mount.get("yaw_deg", 0), lidar_input, background, self.v2i_port,
         "true" if verifier_thread else "false",
         "  advertisement: {enabled: true, address: 127.0.0.1, port: %d, interval_s: 0.2}\n" % advertise_port
         if advertise_port else "",
         "{mode: signed, key_file: %s, trust_list_file: %s%s}" % (
             self.path("rsu.key"), self.trust_list,
             "" if verify_beyond_coverage is None else ", verify_beyond_coverage_m: %s" % verify_beyond_coverage)
         if signed
         else "mode: insecure", capacity, self.path("stats"), extra)
        with open(self.path("rsud.yaml"), "w") as f:
            f.write(text)

    def start_rsud(self, wait_ready=True, own_session=False):
        """own_session: rsud in a session (and so a scheduling autogroup) of its own, as a service runs
        beside the load generators (rsu_processes.Children.spawn)."""
        self.rsud_runs += 1
        self.log_path = self.path("rsud_%d.log" % self.rsud_runs)
        self.rsud = self.children.spawn([self.tools["rsud"], "--config", self.path("rsud.yaml")], self.log_path,
                                        own_session=own_session)
        if wait_ready:
            self.wait_for(lambda: "ready: serving" in self.log(), 20, "rsud to become ready")
        return self.rsud

    def kill_rsud(self):
        self.rsud.send_signal(signal.SIGKILL)
        self.rsud.wait(timeout=5)

    def stop_rsud(self):
        self.rsud.send_signal(signal.SIGTERM)
        rc = self.rsud.wait(timeout=20)
        assert rc == 0, "rsud exited with %d on SIGTERM:\n%s" % (rc, self.log()[-3000:])

    def kill_and_restart(self):
        """SIGKILL, 0.3 s, start again: (host ns of the restart, s until ready, s until the first correction
        after it)."""
        self.kill_rsud()
        time.sleep(0.3)
        t_restart = time.time_ns()
        self.start_rsud(wait_ready=False)
        self.wait_for(lambda: "ready: serving" in self.log(), 5, "rsud to become ready again")
        ready_s = (time.time_ns() - t_restart) * 1e-9
        self.wait_for(lambda: any(c["recv_ns"] > t_restart for c in self.corrections()), 3,
                      "a correction after the restart")
        first_s = (min(c["recv_ns"] for c in self.corrections() if c["recv_ns"] > t_restart) - t_restart) * 1e-9
        return t_restart, ready_s, first_s

    def log(self):
        return read_text(self.log_path)

    def wait_for(self, condition, seconds, what):
        wait_for(condition, seconds, what, watch=self.rsud, watch_log=self.log_path)

    def stats(self):
        values = {}
        for line in read_text(self.path("stats")).splitlines():
            k, v = line.split()
            values[k] = float(v)
        return values

    # ---- the sensor and the vehicles -----------------------------------------------------------------
    def stream(self, start_s, seconds, name="stream", loss=0.0, reorder=0.0, seed=1, options=()):
        cmd = [self.tools["rsu_sim"], "stream", self.scenario, "--to", "127.0.0.1:%d" % self.lidar_port,
               "--epoch-ns", str(self.epoch_ns), "--start", str(start_s), "--seconds", str(seconds)]
        cmd += list(options) + (self.ouster_options or [])
        if loss or reorder:
            cmd += ["--loss", str(loss), "--reorder", str(reorder), "--impair-seed", str(seed)]
        return self.children.spawn(cmd, self.path(name + ".log"))

    def fleet(self, until_s, name="fleet", connected=None, extra=0, address_base="127.1.0.1", options=()):
        """rsu-fleet announcing from now until scenario time until_s."""
        seconds = until_s - self.scenario_s(time.time_ns())
        cmd = [self.tools["fleet"], "--rsu", "127.0.0.1:%d" % self.v2i_port, "--scenario", self.scenario,
               "--epoch-ns", str(self.epoch_ns), "--seconds", str(seconds), "--address-base", address_base,
               "--corrections", self.path(name + ".corrections")]
        if connected:
            cmd += ["--connected", ",".join(str(c) for c in connected)]
        if extra:
            cmd += ["--extra", str(extra)]
        if self.trust_list:
            cmd += ["--signed", self.trust_list]
        cmd += list(options)
        return self.children.spawn(cmd, self.path(name + ".out"))

    def write_trust_list(self, connected=None, extra=0):
        """Signed mode: the fleet's trust list, before rsud starts (it reads it at start)."""
        cmd = [self.tools["fleet"], "--rsu", "127.0.0.1:1", "--scenario", self.scenario, "--epoch-ns", "0",
               "--signed", self.trust_list, "--write-trust-list-only"]
        if connected:
            cmd += ["--connected", ",".join(str(c) for c in connected)]
        if extra:
            cmd += ["--extra", str(extra)]
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
        assert r.returncode == 0, r.stdout + r.stderr

    def corrections(self, name="fleet"):
        out = []
        for line in read_text(self.path(name + ".corrections")).splitlines():
            w = line.split()
            if len(w) == 16 and w[0] == "correction":
                out.append({"recv_ns": int(w[1]), "vehicle": int(w[2]), "named": int(w[3]), "rsu": int(w[4]),
                            "seq": int(w[5]), "sweep_ns": int(w[6]), "x": float(w[7]), "y": float(w[8]),
                            "yaw": float(w[9]), "points": int(w[10]), "error": float(w[11]),
                            "yaw_error": float(w[12]), "other": int(w[13]), "other_error": float(w[14]),
                            "sigmas": float(w[15])})
        return out

    def events(self, name="fleet"):
        """The fleet's event lines other than corrections, e.g. ["size_change", "1", "<ns>"]."""
        return [line.split() for line in read_text(self.path(name + ".corrections")).splitlines()
                if line and not line.startswith("correction ")]

    def fleet_summary(self, name="fleet"):
        for line in read_text(self.path(name + ".out")).splitlines():
            if line.startswith("summary "):
                return {k: int(v) for k, v in (w.split("=") for w in line.split()[1:])}
        return None

    def scenario_s(self, ns):
        """Host-clock ns -> scenario seconds."""
        return (ns - self.epoch_ns) * 1e-9

    def wait_until_scenario(self, t_s):
        time.sleep(max(0.0, (self.epoch_ns + t_s * 1e9 - time.time_ns()) * 1e-9))


def finish(process, seconds, what):
    """Waits for a child that must end by itself and succeed."""
    try:
        rc = process.wait(timeout=seconds)
    except subprocess.TimeoutExpired:
        raise AssertionError("%s did not finish within %.0f s" % (what, seconds))
    assert rc == 0, "%s exited with %d" % (what, rc)


def run_case(case, work, tools, scenario):
    """Runs case(LiveRsu) and returns the process exit code: 1 with the failure and the tail of rsud's log
    when an assertion or a bounded wait fails. The children are killed either way."""
    h = LiveRsu(work, tools, scenario)
    try:
        case(h)
    except (AssertionError, TimeoutError, ChildExited) as e:
        print("FAIL: %s" % e)
        if h.log_path and os.path.exists(h.log_path):
            print("---- rsud log (tail) ----\n" + h.log()[-4000:])
        return 1
    finally:
        h.close()
    return 0
