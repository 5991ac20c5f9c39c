#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Top-down picture of one simulated frame: points coloured by height, true vehicle boxes drawn.

Reads the CSV files that `rsu-sim simulate` writes next to the frames:
  topdown_points.csv  x,y,z,label          (map frame; label = vehicle id, or -1 for the static scene)
  topdown_boxes.csv   id,x,y,yaw,length,width   (true footprint at the frame's middle time)
  topdown_lidar.csv   x,y,z
"""
import argparse
import csv
import math
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("folder", help="output folder of rsu-sim simulate")
    ap.add_argument("--out", default=None, help="PNG path (default: <folder>/topdown.png)")
    ap.add_argument("--range", type=float, default=60.0, help="half width of the view around the LiDAR, m")
    args = ap.parse_args()

    pts = np.loadtxt(os.path.join(args.folder, "topdown_points.csv"), delimiter=",", skiprows=1, ndmin=2)
    boxes = read_csv(os.path.join(args.folder, "topdown_boxes.csv"))
    lidar = read_csv(os.path.join(args.folder, "topdown_lidar.csv"))[0]
    lx, ly = float(lidar["x"]), float(lidar["y"])

    fig, (ax, zoom) = plt.subplots(1, 2, figsize=(16, 6), dpi=110, gridspec_kw={"width_ratios": [3, 1]})
    r = args.range
    p = pts[(np.abs(pts[:, 0] - lx) < r) & (np.abs(pts[:, 1] - ly) < r)] if pts.size else np.zeros((0, 4))
    order = np.argsort(p[:, 2])
    for axis, size in ((ax, 0.6), (zoom, 4.0)):
        axis.set_facecolor("#101018")
        sc = axis.scatter(p[order, 0], p[order, 1], c=p[order, 2], s=size, cmap="turbo", vmin=-0.2, vmax=6.0,
                          linewidths=0)
        for b in boxes:
            x, y, yaw = float(b["x"]), float(b["y"]), float(b["yaw"])
            hl, hw = float(b["length"]) / 2, float(b["width"]) / 2
            c, s = math.cos(yaw), math.sin(yaw)
            corners = [(x + c * dx - s * dy, y + s * dx + c * dy)
                       for dx, dy in ((hl, hw), (-hl, hw), (-hl, -hw), (hl, -hw), (hl, hw))]
            axis.plot([q[0] for q in corners], [q[1] for q in corners], color="white", lw=1.2)
            axis.annotate("", xy=(x + c * hl, y + s * hl), xytext=(x, y), arrowprops=dict(arrowstyle="->", color="white"))
        axis.plot([lx], [ly], marker="*", color="red", markersize=14)
        axis.set_aspect("equal")
        axis.set_xlabel("x east (m)")
        axis.set_ylabel("y north (m)")
    fig.colorbar(sc, ax=zoom, label="height z (m)", shrink=0.9)
    on_vehicles = int((p[:, 3] >= 0).sum())
    ax.set_title(f"one frame, top-down: {len(p)} points, {on_vehicles} on vehicles; white = true box; red star = RSU LiDAR")
    ax.set_xlim(lx - r, lx + r)
    if len(p):
        # Fit the view to what the LiDAR saw (a corridor is long and narrow), keeping the LiDAR in it.
        lo, hi = min(np.percentile(p[:, 1], 0.5), ly), max(np.percentile(p[:, 1], 99.5), ly)
        ax.set_ylim(lo - 4, hi + 4)
    if boxes:
        bx, by = float(boxes[0]["x"]), float(boxes[0]["y"])
        zoom.set_xlim(bx - 5, bx + 5)
        zoom.set_ylim(by - 5, by + 5)
        zoom.set_title(f"vehicle {boxes[0]['id']}, {int((p[:, 3] == float(boxes[0]['id'])).sum())} points")
    out = args.out or os.path.join(args.folder, "topdown.png")
    fig.tight_layout()
    fig.savefig(out)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
