#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The paper's realistic experiment (Sec. 4), end to end through the real processes on loopback, in the
street an experiment file names: scenarios/corridor_experiment.yaml (the default) or
scenarios/corridor_degraded_experiment.yaml (the street between two tall buildings where NDT degrades).

  1. The vehicle's own NDT self-localization over the drive (rsu-corridor ndt -> ndt.csv).
  2. For each RSU LiDAR model: the RSU's background recorded without vehicles (rsu-sim simulate); then the
     real rsud, the real simulator streaming Velodyne packets over UDP (rsu-sim stream) and the real vehicle
     client (rsu-vehicle, announcing its NDT poses, receiving corrections, fusing) run together on one clock:
     the host clock, scenario time 0 mapped to a shared epoch. Every V2I message is signed (Ed25519) with
     keys rsu-keygen writes into <out>/keys/, and verified by the receiver, as deployed.
  3. Scoring against the truth (rsu-corridor report): the paper's table, the same MAE beside the paper's
     (paper_comparison.txt), summary.json, frames.csv, figures.

Every wait is bounded; every child is killed on the way out.
"""
import argparse
import os
import signal
import subprocess
import sys
import time

import yaml

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tools", "python"))
from rsu_processes import ChildExited, Children, free_udp_port, wait_for_line  # noqa: E402


class Run:
    def __init__(self, args):
        self.args = args
        self.children = Children()

    def tool(self, name):
        path = os.path.join(self.args.build, name)
        if not os.path.exists(path):
            sys.exit("run_experiment: %s not found (build first: cmake --build %s)" % (path, self.args.build_dir))
        return path

    def spawn(self, cmd, stdout_path, stdin_path=None):
        # A .log gets stderr too; any other output file (a CSV) keeps stderr beside it in <file>.err.
        return self.children.spawn(cmd, stdout_path, stdin_path=stdin_path,
                                   stderr_path=None if stdout_path.endswith(".log") else stdout_path + ".err")


def wait_until_ready(log, rsud):
    try:
        wait_for_line(log, "ready: serving", 60, watch=rsud)
    except (TimeoutError, ChildExited) as e:
        sys.exit("run_experiment: rsud not ready: %s" % e)


def make_keys(run, out, vehicle_id):
    """Signed V2I as deployed: rsu-keygen makes the RSU's and the vehicle's keys into out/keys/ and the two
    trust lists (rsud trusts the vehicle's key for its id; the vehicle trusts the RSU's key for rsu id 1)."""
    keys = os.path.join(out, "keys")
    os.makedirs(keys, exist_ok=True)
    for name in ("rsud_trust.list", "vehicle_trust.list"):
        if os.path.exists(os.path.join(keys, name)):
            os.remove(os.path.join(keys, name))
    for name, trust, role, ids in (("rsu", "vehicle_trust.list", "rsu", "1"),
                                   ("vehicle", "rsud_trust.list", "vehicle", str(vehicle_id))):
        subprocess.run([run.tool("tools/rsu-keygen"), os.path.join(keys, name), "--force", "--trust-list",
                        os.path.join(keys, trust), "--role", role, "--ids", ids], check=True,
                       stdout=subprocess.DEVNULL, timeout=30)
    return keys


# Traffic (issue 13 item 3): the experiment file's traffic_connected vehicles announce their true poses
# (moved 0.3 m, as an own estimate is off) through rsu-fleet, each signed with its own test key, and
# record every correction they get (fleet_<tag>.corrections, scored by rsu-corridor report).
def trust_traffic(run, exp, scenario_path, keys):
    """Adds the traffic's connected vehicles' keys to rsud's trust list (before rsud reads it)."""
    fleet_list = os.path.join(keys, "fleet_trust.list")
    subprocess.run([run.tool("tests/fleet/rsu-fleet"), "--rsu", "127.0.0.1:1", "--scenario", scenario_path,
                    "--epoch-ns", "0", "--connected", ",".join(str(v) for v in exp["traffic_connected"]),
                    "--signed", fleet_list, "--write-trust-list-only"], check=True, stdout=subprocess.DEVNULL,
                   timeout=60)
    with open(fleet_list) as src, open(os.path.join(keys, "rsud_trust.list"), "a") as dst:
        dst.write(src.read())
    return fleet_list


def start_traffic(run, exp, scenario_path, v2i_port, fleet_list, epoch, duration, out, tag):
    seconds = duration + 0.3 - (time.time_ns() - epoch) * 1e-9
    return run.spawn([run.tool("tests/fleet/rsu-fleet"), "--rsu", "127.0.0.1:%d" % v2i_port, "--scenario",
                      scenario_path, "--epoch-ns", str(epoch), "--seconds", "%.3f" % seconds, "--connected",
                      ",".join(str(v) for v in exp["traffic_connected"]), "--signed", fleet_list,
                      "--corrections", os.path.join(out, "fleet_%s.corrections" % tag)],
                     os.path.join(out, "fleet_%s.log" % tag))


def record_background(run, scenario_path, model, bg_dir):
    """The RSU's background: frames of the street without vehicles (sensor frame), as PCD files."""
    subprocess.run([run.tool("tools/rsu-sim"), "simulate", scenario_path, "--model", model, "--without-vehicles",
                    "--frames", "5", "--out", bg_dir], check=True, stdout=subprocess.DEVNULL, timeout=120)
    return sorted(os.path.join(bg_dir, f) for f in os.listdir(bg_dir) if f.endswith(".pcd"))


# The V2I link impaired between rsud and the vehicle (eval/corridor/run_link_impairment.py): a relay
# process on loopback. The vehicle announces to the relay and names the relay's second loopback address
# as the one to answer to; the relay forwards from there (rsud answers only to the address an
# announcement came from), so the corrections come back through it.
RELAY_RSU_SIDE = "127.0.0.2"


def start_relay(run, link, v2i_port, out, tag):
    """Starts the relay (link: {"tool": path, "args": [its options: impairments, faults]}); returns the
    process and the vehicle's options that send its V2I traffic through it."""
    vehicle_port, listen_port = free_udp_port(), free_udp_port()
    log = os.path.join(out, "relay_%s.log" % tag)
    relay = run.spawn([link["tool"], "--vehicle", "127.0.0.1:%d" % vehicle_port, "--listen",
                       "127.0.0.1:%d" % listen_port, "--rsu", "127.0.0.1:%d" % v2i_port, "--rsu-side",
                       RELAY_RSU_SIDE, "--stats", os.path.join(out, "relay_%s.stats" % tag)] + link["args"], log)
    try:
        wait_for_line(log, "ready", 10, watch=relay)
    except (TimeoutError, ChildExited) as e:
        sys.exit("run_experiment: relay not ready: %s" % e)
    return relay, ["--rsu", "127.0.0.1:%d" % listen_port, "--bind", "127.0.0.1:%d" % vehicle_port,
                   "--reply-address", RELAY_RSU_SIDE]


class LiveCase:
    """What one live run varies (eval/faults/run_fault_table.py runs many): its name (file names), the
    RSU LiDAR model, a scenario file other than the experiment's (e.g. the LiDAR mounted higher), a yaw
    error of the mount rsud is configured with (the real LiDAR stays where the scenario puts it: a badly
    surveyed RSU), rsu-relay's fault options between rsud and the vehicle (None: no faults; "{epoch_ns}"
    in them is replaced by the run's epoch), extra rsu-vehicle options."""

    def __init__(self, model, tag=None, scenario_path=None, mount_yaw_error_deg=0.0, relay_args=None,
                 vehicle_args=()):
        self.model = model
        self.tag = tag or model
        self.scenario_path = scenario_path
        self.mount_yaw_error_deg = mount_yaw_error_deg
        self.relay_args = relay_args
        self.vehicle_args = list(vehicle_args)


def write_rsud_config(case, mount, pcds, lidar_port, v2i_port, keys, out):
    config = os.path.join(out, "rsud_%s.yaml" % case.tag)
    with open(config, "w") as f:
        f.write("""rsu_id: 1
lidar:
  model: %s
  mount: {x: %s, y: %s, z: %s, roll_deg: %s, pitch_deg: %s, yaw_deg: %s}
  input:
    velodyne_udp: {bind_address: 127.0.0.1, port: %d}
background:
  pcd_files: [%s]
v2i:
  listen_address: 127.0.0.1
  port: %d
security:
  mode: signed
  key_file: %s
  trust_list_file: %s
logging:
  level: info
  stats_interval_s: 1.0
  stats_file: %s
""" % (case.model, mount.get("x", 0), mount.get("y", 0), mount.get("z", 0), mount.get("roll_deg", 0),
            mount.get("pitch_deg", 0), float(mount.get("yaw_deg", 0)) + case.mount_yaw_error_deg, lidar_port,
            ", ".join(pcds), v2i_port, os.path.join(keys, "rsu.key"), os.path.join(keys, "rsud_trust.list"),
            os.path.join(out, "rsud_%s.stats" % case.tag)))
    return config


def shift_ndt_to_host_clock(ndt_path, shifted, epoch):
    """The vehicle's NDT poses on the host clock (scenario time 0 = epoch), with their covariance and the
    match's quality indicator (the vehicle lets RSU fixes take over its pose only when its own NDT says it
    failed); returns the first pose's scenario time."""
    first_ndt_ns = None
    with open(ndt_path) as src, open(shifted, "w") as dst:
        header = src.readline().strip().split(",")
        columns = tuple(c for c in ("time_ns", "x", "y", "yaw", "sxx", "syy", "syaw", "converged", "iterations",
                                    "fitness", "degeneracy", "weak_axis") if c in header)
        idx = [header.index(c) for c in columns]
        dst.write(",".join(columns) + "\n")
        for line in src:
            cells = line.strip().split(",")
            t = int(cells[idx[0]])
            first_ndt_ns = t if first_ndt_ns is None else first_ndt_ns
            dst.write(",".join([str(t + epoch)] + [cells[i] for i in idx[1:]]) + "\n")
    return first_ndt_ns


def live_run(run, exp, scenario_path, scenario, case, out, background=None, link=None, drain_ms=500,
             ndt_path=None):
    """One live run: rsud + rsu-sim stream + rsu-vehicle, on the host clock. case: the RSU LiDAR model, or a
    LiveCase (a case of the fault table); background: the background PCD files (recorded here when None);
    link: the relay impairing the V2I link (None: the vehicle talks to rsud directly, unless the case's
    faults need rsu-relay); drain_ms: how long the vehicle waits for corrections after its last pose;
    ndt_path: the vehicle's NDT poses (default <out>/ndt.csv). Returns rsud's counters."""
    if isinstance(case, str):
        case = LiveCase(case)
    if case.scenario_path:
        scenario_path = case.scenario_path
        with open(scenario_path) as f:
            scenario = yaml.safe_load(f)
    model, tag = case.model, case.tag
    mount = scenario["lidar"].get("mount", {})
    vehicle = next(v for v in scenario["vehicles"] if v["id"] == exp.get("vehicle_id", 1))
    shape = vehicle.get("shape", {})
    duration = float(exp.get("duration_s", 10.8))

    pcds = background or record_background(run, scenario_path, model, os.path.join(out, "background_" + tag))

    keys = make_keys(run, out, vehicle["id"])
    fleet_list = trust_traffic(run, exp, scenario_path, keys) if exp.get("traffic_connected") else None
    lidar_port, v2i_port = free_udp_port(), free_udp_port()
    config = write_rsud_config(case, mount, pcds, lidar_port, v2i_port, keys, out)
    log = os.path.join(out, "rsud_%s.log" % tag)
    rsud = run.spawn([run.tool("daemon/rsud"), "--config", config], log)
    wait_until_ready(log, rsud)

    # One clock: scenario time 0 is `epoch` on the host clock, for the packets and the announcements.
    epoch = time.time_ns() + 1_500_000_000
    with open(os.path.join(out, "epoch_%s.txt" % tag), "w") as f:
        f.write("%d\n" % epoch)
    shifted = os.path.join(out, "ndt_host_clock_%s.csv" % tag)
    first_ndt_ns = shift_ndt_to_host_clock(ndt_path or os.path.join(out, "ndt.csv"), shifted, epoch)

    if case.relay_args is not None:
        # A faulty RSU made by rsu-relay: it signs the corrections it alters with the RSU's key.
        faults = [a.replace("{epoch_ns}", str(epoch)) for a in case.relay_args]
        link = {"tool": run.tool("tools/rsu-relay"),
                "args": (link["args"] if link else []) + faults + [
                    "--rsu-key", os.path.join(keys, "rsu.key"),
                    "--tamper-log", os.path.join(out, "tamper_%s.csv" % tag)]}
    relay, v2i_route = None, ["--rsu", "127.0.0.1:%d" % v2i_port, "--bind", "127.0.0.1:0"]
    if link is not None:
        relay, v2i_route = start_relay(run, link, v2i_port, out, tag)
    stream = run.spawn([run.tool("tools/rsu-sim"), "stream", scenario_path, "--model", model, "--to",
                        "127.0.0.1:%d" % lidar_port, "--epoch-ns", str(epoch), "--start", "0",
                        "--seconds", str(duration)], os.path.join(out, "stream_%s.log" % tag))
    fleet = None
    if fleet_list:
        fleet = start_traffic(run, exp, scenario_path, v2i_port, fleet_list, epoch, duration, out, tag)
    # rsu-vehicle paces its rows from its own start: start it when the first NDT pose is due.
    start_at = (epoch + first_ndt_ns) / 1e9
    time.sleep(max(0.0, start_at - time.time()))
    vehicle_proc = run.spawn([run.tool("vehicle_client/rsu-vehicle"), "--vehicle-id", str(vehicle["id"]),
                              "--length-m", str(shape.get("length", 4.89)), "--width-m", str(shape.get("width", 1.92)),
                              "--height-m", str(shape.get("height", 1.70))] + v2i_route + [
                              "--realtime", "--drain-ms", str(int(drain_ms)),
                              "--key", os.path.join(keys, "vehicle.key"),
                              "--trust-list", os.path.join(keys, "vehicle_trust.list"),
                              "--corrections", os.path.join(out, "corrections_%s.csv" % tag),
                              "--stats", os.path.join(out, "vehicle_%s.stats" % tag)] + case.vehicle_args,
                             os.path.join(out, "fused_%s.csv" % tag), stdin_path=shifted)
    deadline = time.time() + duration + 30
    waited = [(stream, "rsu-sim stream"), (vehicle_proc, "rsu-vehicle")] + ([(fleet, "rsu-fleet")] if fleet else [])
    for p, name in waited:
        while p.poll() is None and time.time() < deadline:
            elapsed = time.time() - epoch / 1e9
            sys.stderr.write("\r  %-7s live run: %5.1f / %.1f s of the drive" % (tag, min(max(elapsed, 0), duration),
                                                                                    duration))
            sys.stderr.flush()
            time.sleep(0.2)
        if p.poll() is None:
            sys.exit("\nrun_experiment: %s did not finish in time" % name)
        if p.returncode != 0:
            sys.exit("\nrun_experiment: %s failed (%d); see %s" % (name, p.returncode, out))
    sys.stderr.write("\n")
    if relay is not None:
        relay.send_signal(signal.SIGTERM)  # it writes its counters
        relay.wait(timeout=10)
    rsud.send_signal(signal.SIGTERM)
    try:
        rsud.wait(timeout=10)
    except subprocess.TimeoutExpired:
        sys.exit("run_experiment: rsud did not stop on SIGTERM")
    if rsud.returncode != 0:
        sys.exit("run_experiment: rsud exited with %d; see %s" % (rsud.returncode, log))
    with open(os.path.join(out, "rsud_%s.stats" % tag)) as f:
        stats = dict(line.split() for line in f)
    refused = {k: v for k, v in stats.items() if k.startswith("auth.") and v != "0" and k not in (
        "auth.accepted", "auth.signers_tracked", "auth.trusted_keys", "auth.signatures_verified",
        "auth.signatures_checked_ahead")}
    # rsud sheds LiDAR packets it would process too late (max_packet_age_ms): on a host too busy to keep
    # the LiDAR's pace the run then measures the host, not the method; say so.
    shed = int(stats.get("packet.too_late", 0)) + int(stats.get("packet.lost", 0))
    print("  %-7s rsud verified %s signed announcements (refused: %s)%s" % (
        tag, stats.get("auth.accepted"), refused or "none",
        "; WARNING: rsud lost or shed %d LiDAR packets (host too busy), this run's fixes are fewer" % shed
        if shed else ""))
    return stats


def prepare(args):
    """Makes args.out, args.build and args.experiment absolute (the paths written into rsud's config are
    resolved relative to the config's own folder), creates args.out, and loads the experiment file and the
    scenario it names: (experiment, scenario path, scenario)."""
    args.out = os.path.abspath(args.out)
    args.build = os.path.abspath(args.build)
    args.experiment = os.path.abspath(args.experiment)
    args.build_dir = args.build
    os.makedirs(args.out, exist_ok=True)
    with open(args.experiment) as f:
        exp = yaml.safe_load(f)
    scenario_path = os.path.join(os.path.dirname(args.experiment), exp["scenario"])
    with open(scenario_path) as f:
        scenario = yaml.safe_load(f)
    return exp, scenario_path, scenario


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--experiment", default=os.path.join(ROOT, "scenarios", "corridor_experiment.yaml"))
    ap.add_argument("--build", default=os.path.join(ROOT, "build"), help="build folder with the tools")
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "corridor"))
    ap.add_argument("--rsu-mount-z-m", type=float,
                    help="the RSU LiDAR at this height instead of the scenario's (issue 12: an elevated RSU); "
                         "the scenario with it is written into --out")
    ap.add_argument("--seed", type=int,
                    help="draw the noise anew: this seed for the vehicle's LiDAR, map and NDT sampling (the experiment "
                         "file's seed) and for the RSU LiDAR's noise (the scenario's lidar.noise.seed); the experiment "
                         "and scenario files with it are written into --out")
    args = ap.parse_args()
    exp, scenario_path, scenario = prepare(args)
    if args.seed is not None:
        scenario = dict(scenario, lidar=dict(scenario["lidar"], noise=dict(scenario["lidar"].get("noise", {}),
                                                                           seed=args.seed)))
        scenario_path = os.path.join(args.out, "scenario_seed_%d.yaml" % args.seed)
        with open(scenario_path, "w") as f:
            f.write("# the scenario of %s with the RSU LiDAR's noise seed %d (run_experiment.py --seed)\n" % (
                args.experiment, args.seed))
            yaml.safe_dump(scenario, f)
        exp = dict(exp, seed=args.seed, scenario=scenario_path)
        args.experiment = os.path.join(args.out, "experiment_seed_%d.yaml" % args.seed)
        with open(args.experiment, "w") as f:
            f.write("# written by run_experiment.py --seed %d\n" % args.seed)
            yaml.safe_dump(exp, f)
    if args.rsu_mount_z_m is not None:
        scenario = dict(scenario, lidar=dict(scenario["lidar"], mount=dict(scenario["lidar"]["mount"],
                                                                           z=args.rsu_mount_z_m)))
        elevated = os.path.join(args.out, "scenario_rsu_%gm.yaml" % args.rsu_mount_z_m)
        with open(elevated, "w") as f:
            f.write("# %s with the RSU LiDAR at %g m (written by run_experiment.py)\n" % (scenario_path,
                                                                                        args.rsu_mount_z_m))
            yaml.safe_dump(scenario, f)
        print("RSU LiDAR at %g m above the road: %s" % (args.rsu_mount_z_m, elevated))
    run = Run(args)
    try:
        t0 = time.time()
        subprocess.run([run.tool("eval/rsu-corridor"), "ndt", args.experiment, "--out", args.out], check=True,
                       timeout=600)
        for model in exp["rsu_models"]:
            case = LiveCase(model, scenario_path=elevated if args.rsu_mount_z_m is not None else None)
            live_run(run, exp, scenario_path, scenario, case, args.out)
        subprocess.run([run.tool("eval/rsu-corridor"), "report", args.experiment, "--out", args.out], check=True,
                       timeout=120)
        subprocess.run(["/usr/bin/python3", os.path.join(ROOT, "eval", "plots", "corridor_figures.py"), args.out,
                        "--street", scenario.get("name", "corridor")],
                       check=True, timeout=120, stdout=subprocess.DEVNULL)
        print("figures: %s/error_vs_position.png, %s/error_boxplot.png; every frame: %s/frames.csv; "
              "summary: %s/summary.json; beside the paper: %s/paper_comparison.txt (%.0f s)" % (
                  args.out, args.out, args.out, args.out, args.out, time.time() - t0))
    except subprocess.CalledProcessError as e:
        sys.exit("run_experiment: %s failed with %d" % (" ".join(e.cmd[:2]), e.returncode))
    finally:
        run.children.kill_all()


if __name__ == "__main__":
    main()
