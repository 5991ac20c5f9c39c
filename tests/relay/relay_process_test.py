#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""rsu-relay as a process on loopback: a stand-in vehicle and a stand-in RSU (two UDP sockets)
exchange datagrams through it. Asserts that announcements reach the RSU from the relay's RSU-side
address at the vehicle's port (so that rsud's reply-to check passes), that answers sent back there reach
the vehicle, that each direction is delayed by --delay-ms, that --loss drops about that share, and that a
usage error exits 2. Every wait is bounded."""
import argparse
import os
import signal
import socket
import subprocess
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools", "python"))
from rsu_processes import Children, free_udp_port, wait_for_line  # noqa: E402

RSU_SIDE = "127.0.0.2"


def udp(port=0):
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", port))
    s.settimeout(2.0)
    return s


def start(children, relay, work, vehicle_port, listen_port, rsu_port, extra, name):
    log = os.path.join(work, name + ".log")
    p = children.spawn([relay, "--vehicle", "127.0.0.1:%d" % vehicle_port, "--listen", "127.0.0.1:%d" % listen_port,
                        "--rsu", "127.0.0.1:%d" % rsu_port, "--rsu-side", RSU_SIDE,
                        "--stats", os.path.join(work, name + ".stats")] + extra, log)
    wait_for_line(log, "ready", 10, watch=p)
    return p


def stop(p, work, name):
    p.send_signal(signal.SIGTERM)
    assert p.wait(timeout=5) == 0, "relay exited with %s" % p.returncode
    with open(os.path.join(work, name + ".stats")) as f:
        return {k: int(v) for k, v in (line.split() for line in f)}


def delays_and_routes(children, relay, work):
    vehicle, rsu = udp(), udp()
    listen_port = free_udp_port()
    p = start(children, relay, work, vehicle.getsockname()[1], listen_port, rsu.getsockname()[1],
              ["--delay-ms", "100"], "delay")
    up, down = [], []
    for k in range(5):
        t0 = time.monotonic()
        vehicle.sendto(b"announcement %d" % k, ("127.0.0.1", listen_port))
        data, sender = rsu.recvfrom(2048)
        up.append(time.monotonic() - t0)
        assert data == b"announcement %d" % k, data
        # rsud answers to where the announcement came from: the relay's RSU side at the vehicle's port.
        assert sender == (RSU_SIDE, vehicle.getsockname()[1]), sender
        t0 = time.monotonic()
        rsu.sendto(b"correction %d" % k, sender)
        data, _ = vehicle.recvfrom(2048)
        down.append(time.monotonic() - t0)
        assert data == b"correction %d" % k, data
    stats = stop(p, work, "delay")
    assert stats["uplink.forwarded"] == 5 and stats["downlink.forwarded"] == 5, stats
    for d in up + down:
        assert 0.099 <= d < 0.300, "one-way latency %.3f s, expected 0.1 s plus scheduling" % d
    print("delay 100 ms: uplink %.1f-%.1f ms, downlink %.1f-%.1f ms" % (
        1e3 * min(up), 1e3 * max(up), 1e3 * min(down), 1e3 * max(down)))


def loss(children, relay, work):
    vehicle, rsu = udp(), udp()
    rsu.settimeout(0.3)
    listen_port = free_udp_port()
    p = start(children, relay, work, vehicle.getsockname()[1], listen_port, rsu.getsockname()[1],
              ["--loss", "0.3", "--seed", "5"], "loss")
    n = 400
    got = 0

    def drain():
        nonlocal got
        try:
            while True:
                rsu.recvfrom(2048)
                got += 1
        except (socket.timeout, BlockingIOError):
            pass

    rsu.setblocking(False)
    for k in range(n):
        vehicle.sendto(b"%d" % k, ("127.0.0.1", listen_port))
        time.sleep(0.001)
        drain()  # as it comes: 400 waiting datagrams would overflow the socket's receive buffer
    rsu.settimeout(0.3)
    drain()
    stats = stop(p, work, "loss")
    assert stats["uplink.received"] == n, stats
    assert got == stats["uplink.forwarded"] == n - stats["uplink.dropped"], (got, stats)
    # Binomial(400, 0.3): 120 +- 9.2; within 5 standard deviations.
    assert 74 <= stats["uplink.dropped"] <= 166, stats
    print("loss 0.3: %d of %d dropped" % (stats["uplink.dropped"], n))


def usage_error(relay):
    r = subprocess.run([relay, "--vehicle", "127.0.0.1:1", "--listen", "127.0.0.1:2", "--rsu", "127.0.0.1:3",
                        "--loss", "1.5"], capture_output=True, text=True, timeout=10)
    assert r.returncode == 2 and "--loss" in r.stderr, (r.returncode, r.stderr)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--relay", required=True)
    ap.add_argument("--work", required=True)
    args = ap.parse_args()
    os.makedirs(args.work, exist_ok=True)
    children = Children()
    try:
        delays_and_routes(children, args.relay, args.work)
        loss(children, args.relay, args.work)
        usage_error(args.relay)
    finally:
        children.kill_all()
    print("ok")


if __name__ == "__main__":
    main()
