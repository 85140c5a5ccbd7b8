#!/usr/bin/python3
"""Brazilian disc: the failed (red) and damaged (orange) interfaces of several runs side by side,
in reference coordinates, from each run's last snapshot (issue 23: where the split runs).

    perf/plot_brazil_splits.py RUN_DIR [RUN_DIR ...] --out PNG [--titles "a;b;..."]

Each RUN_DIR is an `fdem run` output folder with snapshots.h5 and summary.json (e.g. the runs that
perf/brazil_scatter.py --keep leaves in DIR/runs/). Uses Debian's python3-matplotlib and -h5py.
"""
import argparse
import json
import os

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--out", required=True)
    ap.add_argument("--titles", default="")
    ap.add_argument("--ft", type=float, default=8e6)
    a = ap.parse_args()
    titles = a.titles.split(";") if a.titles else []
    n = len(a.runs)
    cols = min(n, 4)
    rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 3.4 * rows), squeeze=False)
    for k, run in enumerate(a.runs):
        ax = axes[k // cols][k % cols]
        with h5py.File(os.path.join(run, "snapshots.h5"), "r") as f:
            X = f["/mesh/reference_coordinates"][()][:, :2] * 1000
            I = f["/mesh/interfaces"][()]
            last = sorted(s for s in f if s.startswith("step_"))[-1]
            d = f["/" + last + "/damage"][()]
        seg = np.stack([X[I[:, 0]], X[I[:, 1]]], axis=1)
        ax.add_collection(LineCollection(seg[d <= 0], colors="0.85", linewidths=0.3))
        ax.add_collection(LineCollection(seg[(d > 0) & (d < 1)], colors="orange", linewidths=0.8))
        ax.add_collection(LineCollection(seg[d >= 1], colors="red", linewidths=1.5))
        with open(os.path.join(run, "summary.json")) as f:
            s = json.load(f)
        res = s["results"]  # a mesh from a file has no tensile_strength_Pa: 2 P / (pi D t), D 0.1 m, t 1 mm
        st = res.get("tensile_strength_Pa", 2 * res["peak_load_N"] / (np.pi * 0.1 * 0.001))
        err = st / a.ft - 1
        t = titles[k] if k < len(titles) else os.path.basename(run.rstrip("/"))
        ax.set_title(f"{t}\nsigma_t {100 * err:+.1f} %", fontsize=8)
        ax.set_xlim(-52, 52)
        ax.set_ylim(-52, 52)
        ax.set_aspect("equal")
        ax.tick_params(labelsize=6)
    for k in range(n, rows * cols):
        axes[k // cols][k % cols].axis("off")
    fig.suptitle("failed (red) and damaged (orange) interfaces at the end of each run [mm]", fontsize=9)
    fig.tight_layout()
    fig.savefig(a.out, dpi=110)
    print(a.out)


if __name__ == "__main__":
    main()
