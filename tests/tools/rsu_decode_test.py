#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""rsu-decode on the real captures (tests/data/real/SOURCES.md), as a user runs it.

  - the real VLP-32C capture: one PCD per rotation with the fields x y z intensity ring time, the counts
    it prints equal the files, times are ns since each rotation's first point, and at least 99 % of
    nebula's decoded points (its reference decode of the first rotation) have one of ours within 2 cm;
  - the dual-return VLP-16 capture the same against nebula's decode of its 4th rotation;
  - --help, usage errors (exit 2), a missing file and a pcapng file (exit 1, named, with the command that
    converts it).
Pure Python (no numpy): PCD files are read with struct, nearest neighbours by a hash grid.
"""
import argparse
import math
import os
import re
import shutil
import struct
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools", "python"))
from pcd_file import read_binary_pcd as read_pcd  # noqa: E402

def share_matched(reference, ours, radius):
    grid = {}
    for p in ours:
        key = (math.floor(p["x"] / radius), math.floor(p["y"] / radius), math.floor(p["z"] / radius))
        grid.setdefault(key, []).append((p["x"], p["y"], p["z"]))
    matched = 0
    for r in reference:
        cx, cy, cz = (math.floor(r["x"] / radius), math.floor(r["y"] / radius), math.floor(r["z"] / radius))
        found = False
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                for dz in (-1, 0, 1):
                    for q in grid.get((cx + dx, cy + dy, cz + dz), ()):
                        if (q[0] - r["x"]) ** 2 + (q[1] - r["y"]) ** 2 + (q[2] - r["z"]) ** 2 <= radius * radius:
                            found = True
                            break
                    if found:
                        break
                if found:
                    break
            if found:
                break
        matched += found
    return matched / len(reference)


def run(tool, *args):
    return subprocess.run([tool, *args], capture_output=True, text=True, timeout=120)


def decode(tool, capture, out, *extra):
    if os.path.exists(out):
        shutil.rmtree(out)
    r = run(tool, capture, "--out", out, *extra)
    assert r.returncode == 0, r.stderr
    listed = re.findall(r"^(rotation_\d{4}\.pcd)\s+(\d+) points", r.stdout, re.M)
    assert listed, r.stdout
    rotations = []
    for name, count in listed:
        names, points = read_pcd(os.path.join(out, name))
        assert names == ["x", "y", "z", "intensity", "ring", "time"], names
        assert len(points) == int(count), (name, len(points), count)
        times = [p["time"] for p in points]
        assert min(times) == 0, (name, min(times))  # ns since the rotation's first point
        assert max(times) < 250_000_000, (name, max(times))  # within a rotation at >= 300 rpm
        rotations.append(points)
    return r.stdout, rotations


def golden(tool, data, capture, reference, min_range, max_range, work):
    out, rotations = decode(tool, os.path.join(data, capture), work)
    _, ref = read_pcd(os.path.join(data, reference))
    ours = [p for rot in rotations for p in rot
            if min_range < math.sqrt(p["x"] ** 2 + p["y"] ** 2 + p["z"] ** 2) < max_range]
    share = share_matched(ref, ours, 0.02)
    print(f"{capture}: {len(rotations)} rotations, {share:.4f} of nebula's {len(ref)} points within 2 cm")
    assert share >= 0.99, share
    return out


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--rsu-decode", required=True)
    parser.add_argument("--data", required=True)
    parser.add_argument("--work", required=True)
    a = parser.parse_args()
    os.makedirs(a.work, exist_ok=True)
    tool = a.rsu_decode

    out = golden(tool, a.data, "nebula_vlp32c_5scans.pcap", "nebula_vlp32c_decoded_gt_1713492677464078412.pcd",
                 0.4, 50.0, os.path.join(a.work, "vlp32c"))
    assert "model vlp32c" in out and "accepted 379" in out and "limited field of view" in out, out
    golden(tool, a.data, "nebula_vlp16_dual_4scans.pcap", "nebula_vlp16_decoded_gt_1673400472138016708.pcd",
           0.3, 300.0, os.path.join(a.work, "vlp16_dual"))
    # One return of the dual pair: fewer points than both.
    _, both = decode(tool, os.path.join(a.data, "nebula_vlp16_dual_4scans.pcap"), os.path.join(a.work, "both"))
    _, last = decode(tool, os.path.join(a.data, "nebula_vlp16_dual_4scans.pcap"), os.path.join(a.work, "last"),
                     "--returns", "last")
    assert sum(map(len, last)) < sum(map(len, both)), (sum(map(len, last)), sum(map(len, both)))

    # An Ouster (its metadata given): whole frames, the IMU packets counted.
    out, rotations = decode(tool, os.path.join(a.data, "ouster", "OS-1-128_v2.3.0_1024x10_lb_n3.pcap"),
                            os.path.join(a.work, "os1_128"), "--model", "os1-128", "--metadata",
                            os.path.join(a.data, "ouster", "OS-1-128_v2.3.0_1024x10.json"))
    assert "accepted 192, imu 30" in out and len(rotations) >= 3, out
    assert max(p["ring"] for rot in rotations for p in rot) == 127, "the 128 rings"

    r = run(tool, "--help")
    assert r.returncode == 0 and "rotation_NNNN.pcd" in r.stdout, r
    for args in ([], ["x.pcap"], ["--out", "d"], ["x.pcap", "--out", "d", "--returns", "dual"], ["--bogus"]):
        r = run(tool, *args)
        assert r.returncode == 2, (args, r.returncode, r.stderr)
    r = run(tool, os.path.join(a.work, "missing.pcap"), "--out", os.path.join(a.work, "m"))
    assert r.returncode == 1 and "missing.pcap" in r.stderr, r.stderr
    pcapng = os.path.join(a.work, "capture.pcapng")
    with open(pcapng, "wb") as f:  # a pcapng section header block
        f.write(struct.pack("<III", 0x0A0D0D0A, 28, 0x1A2B3C4D) + bytes(16))
    r = run(tool, pcapng, "--out", os.path.join(a.work, "ng"))
    assert r.returncode == 1 and "pcapng" in r.stderr and "editcap -F pcap" in r.stderr, r.stderr
    print("rsu-decode: ok")


if __name__ == "__main__":
    sys.exit(main())
