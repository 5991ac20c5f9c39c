#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""rsud with an Ouster (issue 11): the real low-bandwidth OS-1-128 capture (tests/data/real/ouster) sent to
the real rsud over loopback UDP, packet by packet as recorded (lidar packets and IMU packets to the one port,
as a sensor configured with udp_port_imu = udp_port_lidar sends them). Every payload must be accounted for
in rsud's stats: the 30 IMU packets as packet.imu, the 192 lidar packets decoded (packet.accepted,
decoder.frames_complete 3) and, since the capture's sensor counts time from its start (TIME_FROM_INTERNAL_OSC: 1.65e9 s off the host's
clock) and rsud takes points on the sensor's time, refused as packet.clock_offset with a warning that says
so: never used, never silent. (The RsuCore test tests/core/ouster_core_test.cpp serves the same packets
stamped by arrival.)

Usage: rsud_ouster_udp.py --rsud PATH --work DIR
"""
import argparse
import os
import shutil
import signal
import socket
import struct
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools", "python"))
from rsu_processes import Children, free_udp_port, wait_for  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.join(HERE, "..", "data", "real", "ouster")


def udp_payloads(path):
    """The UDP payloads of a classic little-endian pcap of Ethernet/IPv4/UDP records, in order."""
    with open(path, "rb") as f:
        data = f.read()
    assert struct.unpack("<I", data[:4])[0] == 0xA1B2C3D4, "not a little-endian microsecond pcap"
    at, out = 24, []
    while at + 16 <= len(data):
        length = struct.unpack("<I", data[at + 8:at + 12])[0]
        frame = data[at + 16:at + 16 + length]
        at += 16 + length
        ihl = (frame[14] & 15) * 4
        udp = frame[14 + ihl:]
        udp_length = struct.unpack(">H", udp[4:6])[0]
        out.append(udp[8:udp_length])
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rsud", required=True)
    ap.add_argument("--work", required=True)
    args = ap.parse_args()
    shutil.rmtree(args.work, ignore_errors=True)
    os.makedirs(args.work)
    lidar_port, v2i_port = free_udp_port(), free_udp_port()
    config = os.path.join(args.work, "rsud.yaml")
    stats = os.path.join(args.work, "stats")
    with open(config, "w") as f:
        f.write("""rsu_id: 3
lidar:
  model: os1-128
  metadata: %s
  mount: {x: 0, y: 0, z: 2.0}
  input:
    udp: {bind_address: 127.0.0.1, port: %d}
background:
  learning_frames: 2
v2i: {listen_address: 127.0.0.1, port: %d}
security: {mode: insecure}
logging: {level: info, stats_interval_s: 0.2, stats_file: %s}
""" % (os.path.join(DATA, "OS-1-128_v2.3.0_1024x10.json"), lidar_port, v2i_port, stats))
    children = Children()
    log = os.path.join(args.work, "rsud.log")
    try:
        rsud = children.spawn([args.rsud, "--config", config], log)
        # Ready to serve comes once the background is learned, from these packets: wait for the socket.
        wait_for(lambda: "receiving os1-128 packets on 127.0.0.1:%d" % lidar_port in open(log).read(), 10,
                 "rsud to listen for the LiDAR", watch=rsud, watch_log=log)
        payloads = udp_payloads(os.path.join(DATA, "OS-1-128_v2.3.0_1024x10_lb_n3.pcap"))
        assert len(payloads) == 222, len(payloads)
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
            s.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, 1 << 20)
            for p in payloads:
                s.sendto(p, ("127.0.0.1", lidar_port))
                time.sleep(0.002)  # a little slower than the sensor: nothing dropped by the kernel

        def counters():
            values = {}
            if os.path.exists(stats):
                for line in open(stats):
                    k, v = line.split()
                    values[k] = float(v)
            return values

        wait_for(lambda: counters().get("packet.accepted", 0) + counters().get("packet.imu", 0) >= 222, 10,
                 "rsud to count every packet", watch=rsud, watch_log=log)
        rsud.send_signal(signal.SIGTERM)
        assert rsud.wait(timeout=10) == 0, open(log).read()
        c = counters()
        nonzero = {k: v for k, v in c.items() if k.startswith("packet.") and v}
        print("rsud counted: %s, decoder.frames_complete %d" % (nonzero, c["decoder.frames_complete"]))
        # Decoded (accepted by the decoder), then refused by the core for their clock.
        assert nonzero == {"packet.accepted": 192, "packet.imu": 30, "packet.clock_offset": 192}, nonzero
        assert c["decoder.frames_complete"] == 3 and c["decoder.columns_skipped"] == 0, c
        text = open(log).read()
        assert "REFUSED (packet.clock_offset)" in text and "warning" in text, text[-2000:]
        print("OK")
        return 0
    finally:
        children.kill_all()


if __name__ == "__main__":
    sys.exit(main())
