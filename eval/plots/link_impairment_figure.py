#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Figure of the link-impairment experiment (eval/corridor/run_link_impairment.py) from
<folder>/link_impairment.csv -> <folder>/fused_error_vs_link.png:
  left    the vehicle's fused MAE within the RSU's coverage against the one-way delay, one line per loss
          rate, with NDT alone, the RSU's own fixes (unimpaired link) and the 1.5x goal marked
  middle  the fused maximum error, the same way, with NDT alone's maximum
  right   jitter and reordering cases beside the unimpaired link
"""
import argparse
import csv
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

# Loss rate -> colour, marker, line style (distinct, so that lines lying on each other stay visible).
LOSS_STYLE = {0.0: ("tab:green", "o", "-"), 0.1: ("tab:olive", "s", "--"), 0.3: ("tab:orange", "^", "-."),
              0.5: ("tab:red", "D", ":")}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("folder")
    ap.add_argument("--model", default="vlp32c")
    args = ap.parse_args()
    with open(os.path.join(args.folder, "link_impairment.csv"), newline="") as f:
        rows = [{k: (v if k == "case" else float(v)) for k, v in r.items()} for r in csv.DictReader(f)]
    plain = [r for r in rows if r["jitter_ms"] == 0 and r["reorder"] == 0]
    others = [r for r in rows if r["jitter_ms"] > 0 or r["reorder"] > 0]
    base = next(r for r in plain if r["delay_ms"] == 0 and r["loss"] == 0)
    model = {"vlp16": "VLP-16", "vlp32c": "VLP-32C"}.get(args.model, args.model)

    fig, axes = plt.subplots(1, 3, figsize=(16, 6.2), dpi=110, gridspec_kw={"width_ratios": [1.2, 1.2, 1]})
    for ax, metric, title in ((axes[0], "mae", "mean absolute error"), (axes[1], "max", "maximum error")):
        for loss, (colour, marker, line) in LOSS_STYLE.items():
            pts = sorted((r["delay_ms"], r["fused_%s_pm50" % metric]) for r in plain if r["loss"] == loss)
            if pts:
                ax.plot([p[0] for p in pts], [p[1] for p in pts], marker=marker, ls=line, color=colour, ms=6,
                        mfc="none", label="fused, %.0f %% loss each way" % (100 * loss))
        ax.axhline(base["ndt_%s_pm50" % metric], color="tab:gray", ls="--", lw=1.2, label="NDT alone (no RSU)")
        ax.axhline(base["rsu_%s_pm50" % metric], color="tab:blue", ls=":", lw=1.2,
                   label="RSU %s fixes alone (unimpaired link)" % model)
        if metric == "mae":
            ax.axhline(1.5 * base["fused_mae_pm50"], color="tab:purple", ls="-.", lw=1,
                       label="goal: 1.5 x the unimpaired fused MAE")
        ax.set_xlabel("one-way delay, each direction (ms)")
        ax.set_ylabel("vehicle position error within 50 m of the RSU (m)")
        ax.set_title("Fused %s against link delay and loss" % title, fontsize=10)
        ax.set_ylim(bottom=0)
        ax.grid(True, alpha=0.3)

    ax = axes[2]
    bars = [("unimpaired", base)] + [(describe(r), r) for r in others]
    xs = range(len(bars))
    ax.bar([x - 0.2 for x in xs], [b[1]["fused_mae_pm50"] for b in bars], width=0.4, color="tab:green",
           label="fused MAE")
    ax.bar([x + 0.2 for x in xs], [b[1]["fused_max_pm50"] for b in bars], width=0.4, color="tab:red",
           label="fused max")
    ax.axhline(base["ndt_mae_pm50"], color="tab:gray", ls="--", lw=1.2,
               label="NDT alone, MAE (its max: %.2f m)" % base["ndt_max_pm50"])
    ax.set_xticks(list(xs))
    ax.set_xticklabels([b[0] for b in bars], fontsize=7)
    ax.set_ylabel("vehicle position error within 50 m of the RSU (m)")
    ax.set_title("Jitter and reordering", fontsize=10)
    ax.grid(True, axis="y", alpha=0.3)
    ax.legend(fontsize=7, loc="upper left")
    fig.suptitle("V2I link impaired between rsud and the vehicle (degraded corridor, RSU %s at 2 m)" % model)
    # One legend for the two line panels (the same lines in both), under them.
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=4, fontsize=8, bbox_to_anchor=(0.36, 0.0))
    fig.tight_layout(rect=(0, 0.1, 1, 1))
    out = os.path.join(args.folder, "fused_error_vs_link.png")
    fig.savefig(out)
    print("wrote %s" % out)


def describe(r):
    parts = ["%.0f ms" % r["delay_ms"]]
    if r["jitter_ms"]:
        parts.append("±%.0f ms jitter" % r["jitter_ms"])
    if r["loss"]:
        parts.append("%.0f %% loss" % (100 * r["loss"]))
    if r["reorder"]:
        parts.append("%.0f %% reordered" % (100 * r["reorder"]))
    return "\n".join(parts)


if __name__ == "__main__":
    main()
