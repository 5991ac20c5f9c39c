#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""gpsd-style golden replay (issue 11): the real rsud replays each real capture (tests/data/real/SOURCES.md:
the Velodyne captures and the Ouster ones with their metadata) at maximum pace, and

  - every record of the capture is accounted for in rsud's counters: records = datagrams to the LiDAR's
    ports + to other ports + records that are no UDP datagram; the LiDAR's datagrams = accepted +
    position packets + refused by reason; accepted = released to perception + refused for the clock +
    shed as too late + dropped as late or duplicate;
  - two replays of one capture write identical stats files (the run's clock is the capture's);
  - the sensor's counters (packet.*, decoder.*, capture.*, clock.*, the rotation rate, the rotations
    learned) equal the committed golden summary in tests/integration/golden/replay_<capture>.txt. On a
    difference the test prints it; after a change that is meant to change them, regenerate with
        python3 tests/integration/rsud_replay.py --rsud build/daemon/rsud --data tests/data/real \
            --work /tmp/replay --regenerate
    and commit the new files with the change that explains them;
  - the VLP-32C capture, whose sensor clock is 52 s behind its recording host, is served with
    time_source host_receive (with a warning naming the offset and saying that points are stamped by
    arrival), and with time_source sensor every packet is refused (packet.clock_offset) with a warning
    naming the offset: never silently.
"""
import argparse
import difflib
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "tools", "python"))
from rsu_processes import free_udp_port  # noqa: E402
GOLDEN = os.path.join(HERE, "golden")

# capture -> (lidar.model, what it shows, the Ouster metadata). The early-firmware VLP-16 says HDL-32E in
# its factory byte: the configured model wins.
CAPTURES = {
    "nebula_vlp32c_5scans.pcap": ("vlp32c", "VLP-32C, limited field of view, clock 52 s behind", None),
    "nebula_vlp16_dual_4scans.pcap": ("vlp16", "VLP-16 dual return", None),
    "einride_vlp16_1000pkts.pcap": ("vlp16", "VLP-16 strongest, 13 rotations", None),
    "rlu_vlp16_indoor_84pkts.pcap": ("vlp16", "VLP-16 strongest, clock 30 min off", None),
    "rlu_vlp16_earlyfw_84pkts.pcap": ("vlp16", "early VLP-16 firmware (factory byte 0x21), position packets", None),
    "rlu_hdl32e_driving_876pkts.pcap": ("hdl32e", "HDL-32E driving, position packets with GPS time", None),
    "rlu_hdl32e_short_91pkts.pcap": ("hdl32e", "HDL-32E, less than a rotation", None),
    "ouster/OS-1-32-G_v2.1.1_1024x10.pcap": ("os1-32", "OS-1-32 legacy profile", "ouster/OS-1-32-G_v2.1.1_1024x10.json"),
    "ouster/OS-1-128_v2.3.0_1024x10_lb_n3.pcap": (
        "os1-128", "OS-1-128 low-bandwidth profile, IMU packets", "ouster/OS-1-128_v2.3.0_1024x10.json"),
    "ouster/OS-0-128-U1_v2.3.0_1024x10.pcap": ("os0-128", "OS-0-128", "ouster/OS-0-128-U1_v2.3.0_1024x10.json"),
    "ouster/OS-2-128-U1_v2.3.0_1024x10.pcap": ("os2-128", "OS-2-128", "ouster/OS-2-128-U1_v2.3.0_1024x10.json"),
    "ouster/OS-2-32-U0_v2.0.0_1024x10.pcap": ("os2-32", "OS-2-32", "ouster/OS-2-32-U0_v2.0.0_1024x10.json"),
}
GOLDEN_PREFIXES = ("packet.", "decoder.", "capture.", "clock.", "lidar.rotation_hz", "lidar.background_frames")


def replay(rsud, capture, model, time_source, work, tag, metadata=None):
    os.makedirs(work, exist_ok=True)
    v2i_port = free_udp_port()  # the V2I socket is not used in a replay, but bound
    stats = os.path.join(work, f"{tag}.stats")
    config = os.path.join(work, f"{tag}.yaml")
    if os.path.exists(stats):
        os.remove(stats)
    metadata_line = f"\n  metadata: {metadata}" if metadata else ""
    with open(config, "w") as f:
        f.write(f"""rsu_id: 1
lidar:
  model: {model}
  time_source: {time_source}{metadata_line}
  mount: {{x: 0, y: 0, z: 2}}
  input:
    pcap: {{file: {capture}, pace: max}}
security: {{mode: insecure}}
v2i: {{listen_address: 127.0.0.1, port: {v2i_port}}}
logging: {{stats_file: {stats}, stats_interval_s: 0}}
""")
    r = subprocess.run([rsud, "--config", config], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, (capture, r.returncode, r.stderr[-2000:])
    values = {}
    with open(stats) as f:
        lines = f.read().splitlines()
    for line in lines:
        name, value = line.split(" ", 1)
        values[name] = value
    return lines, values, r.stderr + r.stdout


def check_accounting(name, v):
    n = lambda key: int(v[key])
    skipped = n("capture.not_ipv4") + n("capture.not_udp") + n("capture.fragmented") + n("capture.malformed")
    assert n("capture.records") == n("capture.lidar_datagrams") + n("capture.other_datagrams") + skipped, (name, v)
    outcomes = [k for k in v if k.startswith("packet.") and k not in (
        "packet.released", "packet.lost", "packet.reordered", "packet.late_dropped", "packet.duplicate",
        "packet.stream_gaps", "packet.too_late", "packet.clock_offset")]
    assert n("capture.lidar_datagrams") == sum(n(k) for k in outcomes), (name, outcomes, v)
    assert n("packet.accepted") == (n("packet.released") + n("packet.clock_offset") + n("packet.too_late") +
                                    n("packet.late_dropped") + n("packet.duplicate")), (name, v)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--rsud", required=True)
    parser.add_argument("--data", required=True)
    parser.add_argument("--work", required=True)
    parser.add_argument("--regenerate", action="store_true", help="write the golden summaries anew")
    a = parser.parse_args()
    failures = []
    for capture, (model, what, metadata) in CAPTURES.items():
        path = os.path.abspath(os.path.join(a.data, capture))
        meta = os.path.abspath(os.path.join(a.data, metadata)) if metadata else None
        stem = os.path.basename(capture).rsplit(".", 1)[0]
        first, values, log = replay(a.rsud, path, model, "host_receive", a.work, stem + "_1", meta)
        second, _, _ = replay(a.rsud, path, model, "host_receive", a.work, stem + "_2", meta)
        if first != second:
            failures.append(f"{capture}: two replays differ:\n" + "\n".join(difflib.unified_diff(first, second, lineterm="")))
            continue
        check_accounting(capture, values)
        if capture == "nebula_vlp32c_5scans.pcap" and not (
                "51.668 s behind the host's" in log and "host_receive stamps its points by arrival" in log):
            failures.append("time_source host_receive: the 52 s offset served without a warning naming it:\n" + log[-3000:])
        summary = [line for line in first if line.startswith(GOLDEN_PREFIXES)]
        golden = os.path.join(GOLDEN, f"replay_{stem}.txt")
        if a.regenerate:
            os.makedirs(GOLDEN, exist_ok=True)
            with open(golden, "w") as f:
                f.write("\n".join(summary) + "\n")
            print(f"{capture}: golden summary written ({what})")
            continue
        with open(golden) as f:
            expected = f.read().splitlines()
        if summary != expected:
            failures.append(f"{capture} ({what}): differs from {golden}:\n" + "\n".join(
                difflib.unified_diff(expected, summary, "golden", "this replay", lineterm="")))
        else:
            auxiliary = values.get("packet.position", values.get("packet.imu", "0"))
            print(f"{capture}: {values['packet.accepted']} accepted, {auxiliary} auxiliary packets, "
                  f"{values['decoder.points']} points, clock {values['clock.offset_ms']} ms: as golden ({what})")

    # The 52 s clock with time_source sensor: refused, loudly, naming the offset.
    _, v, log = replay(a.rsud, os.path.abspath(os.path.join(a.data, "nebula_vlp32c_5scans.pcap")), "vlp32c", "sensor", a.work,
                       "vlp32c_sensor_time")
    check_accounting("vlp32c, time_source sensor", v)
    if not (int(v["packet.clock_offset"]) == int(v["packet.accepted"]) > 0 and int(v["packet.released"]) == 0):
        failures.append(f"time_source sensor: the 52 s-off capture was not refused: {v}")
    if "51.668 s behind the host's" not in log or "REFUSED" not in log:
        failures.append("time_source sensor: no warning naming the offset:\n" + log[-3000:])
    else:
        print("vlp32c with time_source sensor: every packet refused, the warning names the offset (51.668 s behind)")

    if failures:
        print("\n\n".join(failures))
        return 1
    print("replay: ok")
    return 0


if __name__ == "__main__":
    sys.exit(main())
