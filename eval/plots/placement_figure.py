#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The LiDAR placement study's figure (issue 13 item 4) from <folder>/placement.csv (rsu-corridor
placement): one column per LiDAR model, against the mount height,
  coverage      metres of road within rsud's coverage radius (+-50 m) in whose bins at least 80 % of the
                vehicle-rotations got a fix under 0.10 m,
  HMI fixes     fixes beyond 3 sigma of their stated covariance and more than 0.30 m off,
  occlusion     of the vehicle-rotations another vehicle partly hid, the share without a fix under 0.10 m,
one line per lateral position. Each point is a placement that ran; a placement not run leaves a gap.
"""
import argparse
import csv
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

LATERAL = {"curb": ("curb (south sidewalk, y = -8.5 m)", "tab:blue", "o"),
           "median": ("median (y = 0 m)", "tab:orange", "s"),
           "across": ("across the road (north sidewalk, y = 8.5 m)", "tab:green", "^")}
MODEL = {"vlp16": "VLP-16", "vlp32c": "VLP-32C", "generic128": "128 rings (-25..+15 deg)",
         "generic64": "64 rings"}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("folder")
    args = ap.parse_args()
    with open(os.path.join(args.folder, "placement.csv")) as f:
        rows = list(csv.DictReader(f))
    models = list(dict.fromkeys(r["model"] for r in rows))
    heights = sorted({float(r["height_m"]) for r in rows})
    metrics = (("coverage_m", "coverage (m of the 100 m\nwithin ±50 m of the RSU)", lambda r: float(r["coverage_m"])),
               ("hmi", "HMI fixes (> 3σ and > 0.30 m off)", lambda r: int(r["hmi"])),
               ("occlusion", "occluded vehicle-rotations\nwithout a fix < 0.10 m (%)",
                lambda r: 100.0 * int(r["occlusion_losses"]) / int(r["occluded"]) if int(r["occluded"]) else None))
    fig, axes = plt.subplots(len(metrics), len(models), figsize=(4.2 * len(models), 9.0), sharex=True,
                             sharey="row", squeeze=False)
    for j, model in enumerate(models):
        for i, (_, label, value) in enumerate(metrics):
            ax = axes[i][j]
            for lateral, (name, colour, marker) in LATERAL.items():
                by_height = {float(r["height_m"]): value(r) for r in rows
                             if r["model"] == model and r["lateral"] == lateral}
                if not by_height:
                    continue
                # None where a height was not run (or has no occluded rotation): the line breaks there
                ys = [by_height.get(h) for h in heights]
                ax.plot(heights, [float("nan") if y is None else y for y in ys], marker=marker, color=colour,
                        label=name)
            ax.grid(True, alpha=0.3)
            if i == 0:
                ax.set_title("RSU LiDAR: %s" % MODEL.get(model, model))
                ax.set_ylim(0, 105)
            if i == len(metrics) - 1:
                ax.set_xlabel("mount height above the road (m)")
                ax.set_ylim(0, 105)
            if j == 0:
                ax.set_ylabel(label)
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=len(labels), fontsize=9, title="RSU LiDAR's lateral position")
    fig.suptitle("Where to mount the RSU LiDAR: degraded corridor with traffic (7 vehicles, both directions), "
                 "the vehicle-rotations within ±50 m")
    fig.tight_layout(rect=(0, 0.06, 1, 1))
    path = os.path.join(args.folder, "placement.png")
    fig.savefig(path, dpi=110)
    print(path)


if __name__ == "__main__":
    main()
