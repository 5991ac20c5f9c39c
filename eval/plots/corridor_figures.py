#!/usr/bin/env python3
"""Figures of the realistic experiment (paper Sec. 4, Figs. 9 and 10) from <folder>/frames.csv:
  error_vs_position.png  position error against the vehicle's position along the road, per method
  error_boxplot.png      box plots of the error within -36..36 m and -50..50 m
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


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("folder")
    args = ap.parse_args()
    data = defaultdict(list)
    with open(os.path.join(args.folder, "frames.csv"), newline="") as f:
        for row in csv.DictReader(f):
            data[row["method"]].append((float(row["along_road_m"]), float(row["error_m"])))
    methods = [m for m in STYLE if m in data]

    fig, ax = plt.subplots(figsize=(11, 5), dpi=110)
    for m in methods:
        pts = sorted(data[m])
        label, colour = STYLE[m]
        ax.plot([p[0] for p in pts], [p[1] for p in pts], ".-" if m.startswith("rsu") else "-", ms=3, lw=1,
                label=label, color=colour)
    for x in (-50, -36, 36, 50):
        ax.axvline(x, color="k", lw=0.6, ls=":")
    ax.set_xlabel("vehicle position along the road, relative to the RSU (m)")
    ax.set_ylabel("position error (m)")
    ax.set_yscale("log")
    ax.set_title("Localization error along the corridor (cf. paper Fig. 9)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    out = os.path.join(args.folder, "error_vs_position.png")
    fig.savefig(out)
    print(f"wrote {out}")

    fig, axes = plt.subplots(1, 2, figsize=(12, 5), dpi=110, sharey=True)
    for ax, half in zip(axes, (36, 50)):
        series = [[e for x, e in data[m] if abs(x) <= half] for m in methods]
        ax.boxplot(series, labels=[STYLE[m][0].replace(", ", "\n").replace(" + ", "\n+ ") for m in methods],
                   showfliers=True, whis=(5, 95))
        ax.set_title(f"-{half} m to {half} m (whiskers: 5th-95th percentile)")
        ax.set_yscale("log")
        ax.grid(True, axis="y", which="both", alpha=0.3)
        ax.tick_params(axis="x", labelsize=7)
    axes[0].set_ylabel("position error (m)")
    fig.suptitle("Error distribution (cf. paper Fig. 10)")
    fig.tight_layout()
    out = os.path.join(args.folder, "error_boxplot.png")
    fig.savefig(out)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
