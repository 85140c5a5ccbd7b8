#!/usr/bin/python3
"""Pictures of a run, made from its own output (2D runs; 3D runs get the curves only).

    scripts/plot.py OUT_DIR [--frames N] [--magnify M]

Writes into OUT_DIR:
  curves.png        platen load against platen displacement (and reactions against time when
                    there are no platens), and the energies with the balance error;
  cracks_<k>.png    the crack pattern at N instants (default 4, the last one included): the
                    deformed mesh in grey, damaged interfaces in orange, failed ones in red,
                    displacements magnified M times (default: chosen so that the largest
                    displacement is 2 % of the body's size).
Uses Debian's python3-matplotlib, python3-h5py and python3-numpy.
"""
import argparse
import csv
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import LineCollection, PolyCollection  # noqa: E402


def read_history(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    header = rows[0]
    data = np.array([[float(x) for x in r] for r in rows[1:]]) if len(rows) > 1 else np.zeros((0, len(header)))
    return header, data


def col(header, data, name):
    return data[:, header.index(name)] if name in header else None


def plot_curves(out, header, data, summary):
    platens = [h[: -len("_load [N]")] for h in header if h.endswith("_load [N]")]
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5))
    ax = axes[0]
    if platens:
        for p in platens:
            ax.plot(col(header, data, p + "_displacement [m]") * 1e3, col(header, data, p + "_load [N]"), label=p)
        ax.set_xlabel("platen displacement [mm]")
        ax.set_ylabel("load on the body [N]")
        res = summary.get("results", {})
        title = "load-displacement"
        if "tensile_strength_Pa" in res:
            title += "  (Brazilian strength %.2f MPa)" % (res["tensile_strength_Pa"] / 1e6)
        ax.set_title(title)
    else:
        t = col(header, data, "time [s]")
        for h in header:
            if "_reaction_" in h:
                ax.plot(t * 1e3, col(header, data, h), label=h.replace(" [N]", ""))
        ax.set_xlabel("time [ms]")
        ax.set_ylabel("reaction [N]")
        ax.set_title("reactions")
    ax.grid(alpha=0.3)
    ax.legend()
    ax = axes[1]
    t = col(header, data, "time [s]") * 1e3
    for name in ["W_external [J]", "E_kinetic [J]", "E_strain [J]", "E_interface [J]", "D_fracture [J]",
                 "D_damping [J]", "D_friction [J]", "energy_error [J]"]:
        y = col(header, data, name)
        if y is not None and np.any(y != 0):
            ax.plot(t, y, label=name.replace(" [J]", ""), lw=2 if name == "energy_error [J]" else 1)
    ax.set_xlabel("time [ms]")
    ax.set_ylabel("energy [J]")
    ax.set_title("energies")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    path = os.path.join(out, "curves.png")
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_cracks(out, nframes, magnify):
    import h5py

    h5 = os.path.join(out, "snapshots.h5")
    if not os.path.exists(h5):
        return []
    paths = []
    with h5py.File(h5, "r") as f:
        mesh = f["mesh"]
        if int(mesh.attrs["dim"]) != 2:
            return []
        elems = mesh["elements"][()]
        ifaces = mesh["interfaces"][()]
        X = mesh["reference_coordinates"][()][:, :2]
        # Elements coloured by region when there are several (grains of minerals), else grey.
        names = [n.decode() if isinstance(n, bytes) else str(n) for n in mesh["region_names"][()]] \
            if "region_names" in mesh else []
        face = "#e8e8e8"
        legend = []
        if len(names) > 1:
            from matplotlib.patches import Patch

            palette = ["#f2d7d0", "#d5e3f0", "#e4ecd2", "#efe2c0", "#e3d7ec", "#d3ece8", "#ecd3e0"]
            region = mesh["region"][()]
            face = [palette[r % len(palette)] for r in region]
            legend = [Patch(facecolor=palette[i % len(palette)], edgecolor="#b0b0b0", label=n)
                      for i, n in enumerate(names)]
        steps = sorted(k for k in f.keys() if k.startswith("step_"))
        if not steps:
            return []
        pick = sorted(set(np.linspace(0, len(steps) - 1, min(nframes, len(steps))).round().astype(int)))
        size = np.ptp(X, axis=0).max()
        umax = max(np.abs(f[s]["displacement"][()][:, :2]).max() for s in steps)
        mag = magnify if magnify is not None else (0.02 * size / umax if umax > 0 else 1.0)
        for k, i in enumerate(pick):
            g = f[steps[i]]
            x = X + mag * g["displacement"][()][:, :2]
            dmg = g["damage"][()]
            fig, ax = plt.subplots(figsize=(6.5, 6.5))
            ax.add_collection(PolyCollection(x[elems], facecolor=face, edgecolor="#c8c8c8", linewidths=0.2))
            if legend:
                ax.legend(handles=legend, loc="upper right", fontsize=8, framealpha=0.8)
            if len(ifaces):
                seg = x[ifaces]
                damaged = (dmg > 0) & (dmg < 1)
                failed = dmg >= 1
                ax.add_collection(LineCollection(seg[damaged], colors="orange", linewidths=0.8))
                ax.add_collection(LineCollection(seg[failed], colors="red", linewidths=1.4))
            ax.set_xlim(x[:, 0].min() - 0.02 * size, x[:, 0].max() + 0.02 * size)
            ax.set_ylim(x[:, 1].min() - 0.02 * size, x[:, 1].max() + 0.02 * size)
            ax.set_aspect("equal")
            t = float(g.attrs["time"])
            ax.set_title("t = %.3g ms: %d damaged (orange), %d failed (red); displacements x%.3g"
                         % (t * 1e3, int(((dmg > 0) & (dmg < 1)).sum()), int((dmg >= 1).sum()), mag), fontsize=9)
            ax.set_xticks([])
            ax.set_yticks([])
            path = os.path.join(out, "cracks_%d.png" % k)
            fig.tight_layout()
            fig.savefig(path, dpi=110)
            plt.close(fig)
            paths.append(path)
    return paths


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out", help="output folder of a run")
    ap.add_argument("--frames", type=int, default=4)
    ap.add_argument("--magnify", type=float, default=None)
    a = ap.parse_args()
    hist = os.path.join(a.out, "history.csv")
    if not os.path.exists(hist):
        sys.exit("plot.py: %s: no history.csv (is this the output folder of a run?)" % a.out)
    summary = {}
    if os.path.exists(os.path.join(a.out, "summary.json")):
        with open(os.path.join(a.out, "summary.json")) as f:
            summary = json.load(f)
    header, data = read_history(hist)
    written = [plot_curves(a.out, header, data, summary)] + plot_cracks(a.out, a.frames, a.magnify)
    for p in written:
        print(p)


if __name__ == "__main__":
    main()
