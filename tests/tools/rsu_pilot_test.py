#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""rsu-pilot as a user runs it: a small matrix with rsud's cap and with another one (printed with the
results), its outputs' fields (outline_seen per cell, the summary's shares), and a cap out of range refused
with exit 2."""
import argparse
import csv
import json
import pathlib
import shutil
import subprocess
import sys

GRID = ["--mounts", "6", "--models", "vlp16", "--distance-min-m", "10", "--distance-max-m", "14",
        "--distance-step-m", "2", "--spin-rate-deg-per-s", "120", "--threads", "1"]


def run(pilot, args, expect_rc=0):
    p = subprocess.run([pilot] + args, capture_output=True, text=True, timeout=120)
    if p.returncode != expect_rc:
        sys.exit(f"FAIL: rsu-pilot {' '.join(args)} exited {p.returncode}, expected {expect_rc}\n"
                 f"{p.stdout}\n{p.stderr}")
    return p


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rsu-pilot", required=True)
    ap.add_argument("--vehicles", required=True, help="the repository's scenarios/vehicles folder")
    ap.add_argument("--work", required=True)
    a = ap.parse_args()
    work = pathlib.Path(a.work)
    shutil.rmtree(work, ignore_errors=True)
    vehicle = str(pathlib.Path(a.vehicles) / "small_car.yaml")

    shipped = run(a.rsu_pilot, ["matrix", "--out", str(work / "shipped"), "--vehicles", vehicle] + GRID)
    if "NOT rsud's default" in shipped.stdout:
        sys.exit("FAIL: rsud's own cap reported as another\n" + shipped.stdout)
    other = run(a.rsu_pilot, ["matrix", "--out", str(work / "cap1"), "--vehicles", vehicle,
                              "--max-position-sigma-m", "1.0"] + GRID)
    if "NOT rsud's default: max_position_sigma_m 1 m" not in other.stdout:
        sys.exit("FAIL: another cap not printed with the results\n" + other.stdout)

    cell = work / "shipped" / "vlp16_6m_small_car"
    with open(cell / "cells.csv") as f:
        rows = list(csv.DictReader(f))
    if not rows or "outline_seen" not in rows[0]:
        sys.exit("FAIL: cells.csv has no outline_seen column")
    if {r["outline_seen"] for r in rows} - {"0", "1"}:
        sys.exit("FAIL: outline_seen is not 0 or 1")
    summary = json.loads((cell / "summary.json").read_text())["vlp16"]["improved"]
    for key in ("outline_seen_6_36m_30pts", "share_below_0p10_outline_seen", "beyond_3sigma_position",
                "beyond_3sigma_yaw", "hmi_fixes"):
        if key not in summary:
            sys.exit(f"FAIL: summary.json's improved has no {key}")
    dense = [r for r in rows if int(r["points"]) >= 30]
    seen = sum(r["outline_seen"] == "1" for r in dense)
    if dense and abs(summary["outline_seen_6_36m_30pts"] - seen / len(dense)) > 1e-9:
        sys.exit(f"FAIL: outline_seen share {summary['outline_seen_6_36m_30pts']} != {seen}/{len(dense)}")
    header = (work / "shipped" / "matrix.md").read_text().splitlines()[0]
    if "outline seen" not in header:
        sys.exit("FAIL: matrix.md has no outline column")

    # A larger cap withholds no more than the shipped one.
    def withheld(folder):
        with open(work / folder / "matrix.csv") as f:
            return float(next(csv.DictReader(f))["withheld_6_36m_30pts"])
    if withheld("cap1") > withheld("shipped"):
        sys.exit(f"FAIL: the 1 m cap withheld more ({withheld('cap1')}) than 0.5 m ({withheld('shipped')})")

    for bad in ("0", "-1", "10.5", "nan"):
        p = run(a.rsu_pilot, ["matrix", "--out", str(work / "bad"), "--max-position-sigma-m", bad] + GRID,
                expect_rc=2)
        if "max-position-sigma-m" not in p.stderr:
            sys.exit(f"FAIL: cap {bad} refused without saying which option\n{p.stderr}")
    print("rsu-pilot: outputs, cap override and refusals ok")


if __name__ == "__main__":
    main()
