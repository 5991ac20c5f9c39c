#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Heat maps of the pilot experiment (paper Sec. 3.1, Figs. 3-4), one PNG per metric and LiDAR model.

Reads <folder>/cells.csv written by rsu-pilot and writes <folder>/<model>_<metric>.png: distance on x,
vehicle yaw on y, as in the paper. Several folders (rsu-pilot matrix writes one per cell) may be given;
--metrics picks the columns drawn.
"""
import argparse
import csv
import os
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

METRICS = [
    # column, title, colour bar label, colour limits, absolute value?
    ("lshape_center_err_m", "Centre error, L-shape fit (no correction)", "error (m)", (0, 1.0), False),
    ("points", "Number of vehicle points", "points", None, False),
    ("area_err_m2", "Box area error, L-shape fit", "|area error| (m²)", (0, 8.0), True),
    ("lshape_yaw_err_deg", "Yaw error, L-shape fit (longer edge)", "error (°)", (0, 90), False),
    ("alg1_center_err_m", "Centre error after Algorithm 1 (paper)", "error (m)", (0, 0.3), False),
    ("improved_center_err_m", "Centre error after the improved correction", "error (m)", (0, 0.3), False),
    ("improved_sigma_m", "Stated position sigma (improved, larger axis)", "sigma (m)", (0, 0.3), False),
    ("improved_position_nees", "Error against the stated covariance (NEES; > 11.83: beyond 3 sigma)", "NEES",
     (0, 20.0), False),
]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("folders", nargs="+")
    ap.add_argument("--metrics", help="comma-separated columns to draw (default: all)")
    args = ap.parse_args()
    wanted = set(args.metrics.split(",")) if args.metrics else None
    for folder in args.folders:
        draw_folder(folder, [m for m in METRICS if wanted is None or m[0] in wanted])


def draw_folder(folder, metrics):
    cells = defaultdict(list)
    with open(os.path.join(folder, "cells.csv"), newline="") as f:
        for row in csv.DictReader(f):
            cells[row["model"]].append(row)
    for model, rows in cells.items():
        where = ""
        if "lidar_height_m" in rows[0]:
            where = f" at {float(rows[0]['lidar_height_m']):g} m, {rows[0]['vehicle']}"
        distances = sorted({float(r["distance_m"]) for r in rows})
        frames = max(int(r["frame"]) for r in rows) + 1
        d_index = {d: i for i, d in enumerate(distances)}
        for column, title, label, limits, absolute in metrics:
            grid = np.full((frames, len(distances)), np.nan)
            for r in rows:
                v = r[column]
                if v in ("null", ""):
                    continue
                v = float(v)
                grid[int(r["frame"]), d_index[float(r["distance_m"])]] = abs(v) if absolute else v
            fig, ax = plt.subplots(figsize=(9, 5.5), dpi=110)
            step = distances[1] - distances[0] if len(distances) > 1 else 0.5
            extent = [distances[0] - step / 2, distances[-1] + step / 2, 0, 360]
            cmap = plt.get_cmap("magma").copy()
            cmap.set_bad("#2a6f2a")  # no fit
            kw = {} if limits is None else {"vmin": limits[0], "vmax": limits[1]}
            im = ax.imshow(grid, origin="lower", aspect="auto", extent=extent, cmap=cmap, interpolation="nearest", **kw)
            fig.colorbar(im, ax=ax, label=label + ("" if limits is None else f" (clipped at {limits[1]})"))
            ax.set_xlabel("distance from the LiDAR (m)")
            ax.set_ylabel("vehicle yaw at the start of the frame (°)")
            ax.set_yticks(range(0, 361, 45))
            ax.set_title(f"{model.upper()}{where}: {title}", fontsize=10)
            for x in (6, 36):
                ax.axvline(x, color="cyan", lw=0.8, ls="--")
            fig.tight_layout()
            out = os.path.join(folder, f"{model}_{column}.png")
            fig.savefig(out)
            plt.close(fig)
            print(f"wrote {out}")


if __name__ == "__main__":
    main()
