#!/usr/bin/python3
"""Pictures of the fragments of a run, made from its own output (2D and 3D).

    scripts/plot_fragments.py OUT_DIR [--frames N] [--prefix NAME]

Reads OUT_DIR/fragments.csv, history.csv, summary.json and snapshots.h5 (written by `fdem run`
for a case with interfaces; snapshots need output.snapshot_count > 0) and writes into OUT_DIR:
  fragments_curves.png   number of fragments and largest fragment's mass fraction against time,
                         the platen loads against time (or against platen displacement when the
                         platens move), the momentum against time, and the final mass distribution
                         (mass fraction per decade of fragment mass fraction);
  fragments_<k>.png      the fragments at N instants (default 4, the last one included), each
                         fragment in its own colour, the largest one grey:
                         2D: the deformed mesh (true displacements) with the failed interfaces;
                         3D: element centroids at their current positions, seen from the side
                         (x-z projection, nearest in front) and a slice through the centre.
Uses Debian's python3-matplotlib, python3-h5py and python3-numpy (/usr/bin/python3).
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


def read_csv(path):
    if not os.path.exists(path):
        return [], np.zeros((0, 0))
    with open(path) as f:
        rows = list(csv.reader(f))
    header = rows[0]
    data = np.array([[float(x) for x in r] for r in rows[1:]]) if len(rows) > 1 else np.zeros((0, len(header)))
    return header, data


def col(header, data, name):
    return data[:, header.index(name)] if name in header else None


def fragment_colours(ids, masses_by_id):
    """One colour per element: a qualitative palette scrambled over the fragment ids; the largest
    fragment grey so that the small ones stand out."""
    pal = plt.get_cmap("tab20").colors + plt.get_cmap("tab20b").colors
    pal = np.array(pal)
    big = int(np.argmax(masses_by_id)) if len(masses_by_id) else -1
    c = pal[(ids.astype(np.int64) * 7919 + 13) % len(pal)]
    c[ids == big] = (0.78, 0.78, 0.78)
    return c


def plot_curves(out, prefix):
    fh, fd = read_csv(os.path.join(out, "fragments.csv"))
    hh, hd = read_csv(os.path.join(out, "history.csv"))
    if not len(fh) or not len(fd):
        return None
    fig, axes = plt.subplots(2, 2, figsize=(12, 8))
    t = col(fh, fd, "time [s]") * 1e3
    ax = axes[0, 0]
    ax.plot(t, col(fh, fd, "fragments"), "C0-", label="fragments")
    ax.plot(t, col(fh, fd, "fragments") - col(fh, fd, "single_element_fragments"), "C0--",
            label="fragments of 2 or more elements")
    ax.set_xlabel("time [ms]")
    ax.set_ylabel("number of fragments")
    ax.set_yscale("symlog", linthresh=10)
    ax.grid(alpha=0.3)
    ax2 = ax.twinx()
    ax2.plot(t, col(fh, fd, "largest_fraction"), "C3-", label="largest fragment's mass fraction")
    ax2.set_ylabel("largest fragment's mass fraction", color="C3")
    ax2.set_ylim(0, 1.05)
    lines = ax.get_lines() + ax2.get_lines()
    ax.legend(lines, [ln.get_label() for ln in lines], fontsize=8, loc="center right")
    ax.set_title("fragments")

    ax = axes[0, 1]
    if len(hh):
        th = col(hh, hd, "time [s]") * 1e3
        platens = [h[: -len("_load [N]")] for h in hh if h.endswith("_load [N]")]
        moving = [p for p in platens if np.ptp(col(hh, hd, p + "_displacement [m]")) > 0]
        if moving:
            for p in moving:
                ax.plot(col(hh, hd, p + "_displacement [m]") * 1e3, col(hh, hd, p + "_load [N]") / 1e3, label=p)
            ax.set_xlabel("platen displacement [mm]")
        else:
            for p in platens:
                ax.plot(th, col(hh, hd, p + "_load [N]") / 1e3, label=p)
            ax.set_xlabel("time [ms]")
        ax.set_ylabel("load on the body [kN]")
        ax.set_title("platen loads")
        ax.grid(alpha=0.3)
        if platens:
            ax.legend(fontsize=8)

    ax = axes[1, 0]
    if len(hh):
        for h in hh:
            if h.startswith("momentum_"):
                ax.plot(th, col(hh, hd, h), label=h.replace(" [N s]", ""))
        ax.set_xlabel("time [ms]")
        ax.set_ylabel("momentum [N s]")
        ax.set_title("total linear momentum")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)

    ax = axes[1, 1]
    names = [h[len("mass_"):] for h in fh if h.startswith("mass_")]
    last = fd[-1]
    mass = [last[fh.index("mass_" + n)] for n in names]
    count = [last[fh.index("count_" + n)] for n in names]
    labels = ["[%s, %s)" % (n, "1" if i == 0 else names[i - 1]) if n != "0" else "< " + names[i - 1]
              for i, n in enumerate(names)]
    labels[0] = "[%s, 1]" % names[0]
    x = np.arange(len(names))
    ax.bar(x, mass, color="C2")
    for xi, (m, c) in enumerate(zip(mass, count)):
        if c > 0:
            ax.text(xi, m, "%d" % c, ha="center", va="bottom", fontsize=8)
    ax.set_xticks(x)
    ax.set_xticklabels(labels, rotation=30, fontsize=7)
    ax.set_xlabel("fragment mass fraction (numbers: fragments in the bin)")
    ax.set_ylabel("mass fraction in the bin")
    ax.set_ylim(0, 1.1)
    ax.set_title("mass distribution at t = %.3g ms" % (last[0] * 1e3))
    ax.grid(alpha=0.3, axis="y")
    fig.tight_layout()
    path = os.path.join(out, prefix + "_curves.png")
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def element_volumes(X, elems):
    if elems.shape[1] == 3:
        a = X[elems[:, 1]] - X[elems[:, 0]]
        b = X[elems[:, 2]] - X[elems[:, 0]]
        return 0.5 * np.abs(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])
    a = X[elems[:, 1]] - X[elems[:, 0]]
    b = X[elems[:, 2]] - X[elems[:, 0]]
    c = X[elems[:, 3]] - X[elems[:, 0]]
    return np.abs(np.einsum("ij,ij->i", a, np.cross(b, c))) / 6.0


def plot_frames(out, prefix, nframes):
    import h5py

    h5 = os.path.join(out, "snapshots.h5")
    if not os.path.exists(h5):
        return []
    paths = []
    with h5py.File(h5, "r") as f:
        mesh = f["mesh"]
        dim = int(mesh.attrs["dim"])
        elems = mesh["elements"][()]
        ifaces = mesh["interfaces"][()]
        X = mesh["reference_coordinates"][()][:, :dim]
        vol = element_volumes(X, elems)
        steps = sorted(k for k in f.keys() if k.startswith("step_") and "fragment" in f[k])
        if not steps:
            return []
        pick = sorted(set(np.linspace(0, len(steps) - 1, min(nframes, len(steps))).round().astype(int)))
        for k, i in enumerate(pick):
            g = f[steps[i]]
            x = g["coordinates"][()][:, :dim]
            ids = g["fragment"][()]
            nf = int(ids.max()) + 1 if len(ids) else 0
            vol_by_id = np.bincount(ids, weights=vol, minlength=nf)
            colours = fragment_colours(ids, vol_by_id)
            t = float(g.attrs["time"])
            title = "t = %.3g ms: %d fragments, largest %.1f %% of the volume" % (
                t * 1e3, nf, 100 * vol_by_id.max() / vol_by_id.sum() if nf else 0)
            if dim == 2:
                fig, ax = plt.subplots(figsize=(6.5, 6.5))
                ax.add_collection(PolyCollection(x[elems], facecolors=colours, edgecolors="none"))
                dmg = g["damage"][()]
                if len(ifaces):
                    ax.add_collection(LineCollection(x[ifaces][dmg >= 1], colors="k", linewidths=0.6))
                size = np.ptp(X, axis=0).max()
                ax.set_xlim(x[:, 0].min() - 0.03 * size, x[:, 0].max() + 0.03 * size)
                ax.set_ylim(x[:, 1].min() - 0.03 * size, x[:, 1].max() + 0.03 * size)
                ax.set_aspect("equal")
                ax.set_xticks([])
                ax.set_yticks([])
                ax.set_title(title + "\nfailed interfaces black", fontsize=9)
            else:
                cen = x[elems].mean(axis=1)
                cen0 = X[elems].mean(axis=1)
                fig, axes = plt.subplots(1, 2, figsize=(12, 6))
                order = np.argsort(-cen[:, 1])  # far (large y) first, near drawn on top
                size = np.ptp(X, axis=0).max()
                s = max(0.5, 2e4 / max(len(cen), 1))
                axes[0].scatter(cen[order, 0], cen[order, 2], c=colours[order], s=s, linewidths=0)
                axes[0].set_title("side view (x-z), all elements", fontsize=9)
                mid = np.median(cen0[:, 1])
                h = np.mean(vol) ** (1.0 / 3.0)
                sl = np.abs(cen0[:, 1] - mid) < 0.75 * h
                axes[1].scatter(cen[sl, 0], cen[sl, 2], c=colours[sl], s=4 * s, linewidths=0)
                axes[1].set_title("slice: elements whose reference centroid is within %.2g mm of y = %.3g mm"
                                  % (0.75 * h * 1e3, mid * 1e3), fontsize=9)
                for ax in axes:
                    ax.set_aspect("equal")
                    ax.set_xlim(cen[:, 0].min() - 0.03 * size, cen[:, 0].max() + 0.03 * size)
                    ax.set_ylim(cen[:, 2].min() - 0.03 * size, cen[:, 2].max() + 0.03 * size)
                    ax.set_xlabel("x [m]")
                    ax.set_ylabel("z [m]")
                fig.suptitle(title, fontsize=10)
            fig.tight_layout()
            path = os.path.join(out, "%s_%d.png" % (prefix, k))
            fig.savefig(path, dpi=110)
            plt.close(fig)
            paths.append(path)
    return paths


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out", help="output folder of a run")
    ap.add_argument("--frames", type=int, default=4)
    ap.add_argument("--prefix", default="fragments", help="file name prefix (default: fragments)")
    a = ap.parse_args()
    if not os.path.exists(os.path.join(a.out, "fragments.csv")):
        sys.exit("plot_fragments.py: %s: no fragments.csv (a run of a case with interfaces writes it)" % a.out)
    written = [plot_curves(a.out, a.prefix)] + plot_frames(a.out, a.prefix, a.frames)
    for p in written:
        if p:
            print(p)


if __name__ == "__main__":
    main()
