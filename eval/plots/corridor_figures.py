#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Figures of the realistic experiment (paper Sec. 4, Figs. 9 and 10) from <folder>/frames.csv:
  error_vs_position.png  position error against the vehicle's position along the road, per method
  error_boxplot.png      box plots of the error within -36..36 m and -50..50 m
Lines join consecutive estimates only: where no fix came for longer than GAP_S, the line breaks.
"""
import argparse
import csv
import os
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

STYLE = {
    "ndt": ("NDT self-localization", "tab:gray"),
    "rsu_vlp16": ("RSU, VLP-16", "tab:orange"),
    "rsu_vlp32c": ("RSU, VLP-32C", "tab:blue"),
    "fused_vlp16": ("fused NDT + RSU VLP-16", "tab:red"),
    "fused_vlp32c": ("fused NDT + RSU VLP-32C", "tab:green"),
}
# Estimates come every LiDAR rotation (0.1 s); a longer silence is a gap the line must not bridge.
GAP_S = 0.15
# The paper's two ranges along the road (Table 2): +-36 m, where both LiDARs are effective, and +-50 m.
RANGES = ((36, "±36 m: the paper's effective range"), (50, "±50 m"))


def broken_line(points):
    """(time_s, x, error) sorted by time -> x and y lists with None where consecutive points are more than
    GAP_S apart, so that matplotlib draws no line across the gap."""
    xs, ys = [], []
    last_t = None
    for t, x, e in points:
        if last_t is not None and t - last_t > GAP_S:
            xs.append(None)
            ys.append(None)
        xs.append(x)
        ys.append(e)
        last_t = t
    return [float("nan") if v is None else v for v in xs], [float("nan") if v is None else v for v in ys]


def mark_ranges(ax):
    """Shades the +-36 m band and draws the +-50 m limits, each named at the top of the axes."""
    (inner, inner_name), (outer, outer_name) = RANGES
    ax.axvspan(-inner, inner, color="tab:olive", alpha=0.08, lw=0)
    for x in (-outer, outer):
        ax.axvline(x, color="k", lw=0.8, ls=":")
    for x in (-inner, inner):
        ax.axvline(x, color="tab:olive", lw=0.8, ls="--")
    transform = ax.get_xaxis_transform()
    ax.text(0, 0.985, inner_name, transform=transform, ha="center", va="top", fontsize=8, color="tab:olive")
    for x, ha in ((-outer, "left"), (outer, "right")):
        ax.text(x + (0.8 if ha == "left" else -0.8), 0.985, outer_name, transform=transform, ha=ha, va="top",
                fontsize=8)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("folder")
    ap.add_argument("--street", default="corridor", help="the scenario's name, for the titles")
    args = ap.parse_args()
    data = defaultdict(list)
    with open(os.path.join(args.folder, "frames.csv"), newline="") as f:
        for row in csv.DictReader(f):
            data[row["method"]].append((int(row["time_ns"]) * 1e-9, float(row["along_road_m"]),
                                        float(row["error_m"])))
    methods = [m for m in STYLE if m in data]

    fig, ax = plt.subplots(figsize=(13, 5.5), dpi=110)
    for m in methods:
        xs, ys = broken_line(sorted(data[m]))
        label, colour = STYLE[m]
        ax.plot(xs, ys, ".-" if m.startswith("rsu") else "-", ms=3, lw=1, label=label, color=colour)
    mark_ranges(ax)
    ax.set_xlabel("vehicle position along the road, relative to the RSU LiDAR (m)")
    ax.set_ylabel("position error (m, log scale)")
    ax.set_yscale("log")
    ax.set_title(f"Localization error along the street '{args.street}' (cf. paper Fig. 9); "
                 f"lines break where no estimate came for > {GAP_S:.2f} s")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.tight_layout()
    out = os.path.join(args.folder, "error_vs_position.png")
    fig.savefig(out)
    print(f"wrote {out}")

    fig, axes = plt.subplots(1, 2, figsize=(12, 5), dpi=110, sharey=True)
    for ax, (half, name) in zip(axes, RANGES):
        series = [[e for _, x, e in data[m] if abs(x) <= half] for m in methods]
        ax.boxplot(series, labels=[STYLE[m][0].replace(", ", "\n").replace(" + ", "\n+ ") for m in methods],
                   showfliers=True, whis=(5, 95))
        ax.set_title(f"{name} along the road\n(box: 25th-75th percentile, line: median, whiskers: 5th-95th)", fontsize=10)
        ax.set_yscale("log")
        ax.grid(True, axis="y", which="both", alpha=0.3)
        ax.tick_params(axis="x", labelsize=7)
    axes[0].set_ylabel("position error (m, log scale)")
    fig.suptitle(f"Error distribution along the street '{args.street}' (cf. paper Fig. 10)")
    fig.tight_layout()
    out = os.path.join(args.folder, "error_boxplot.png")
    fig.savefig(out)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
