#!/usr/bin/python3
"""Pictures of the fragments of a run, made from its own output (2D and 3D).

    scripts/plot_fragments.py OUT_DIR [--frames N] [--prefix NAME] [--dpi D]

Reads OUT_DIR/fragments.csv, history.csv, summary.json and snapshots.h5 (written by `fdem run`
for a case with interfaces; snapshots need output.snapshot_count > 0) and writes into OUT_DIR:
  fragments_curves.png   number of fragments and largest fragment's mass fraction against time,
                         the platen loads against time (or against platen displacement when the
                         platens move), the momentum against time, and the final mass distribution
                         (mass fraction per decade of fragment mass fraction);
  fragments_<k>.png      the fragments at N instants (default 4, the last one included), each
                         fragment in its own colour, the largest one grey:
                         2D: the deformed mesh (true displacements) with the failed interfaces;
                         3D: the fragments' surfaces (outer surface and failed faces between
                         fragments, at their current positions), whole and cut open at the
                         middle y (front half removed).
                         The platens are drawn at their positions (grey).
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

DPI = 110


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
    top = col(fh, fd, "fragments").max()
    if len(hh) and "interfaces_failed" in hh:
        failed = col(hh, hd, "interfaces_failed")
        ax.plot(col(hh, hd, "time [s]") * 1e3, np.maximum(failed, 0.5), "C7:", label="failed interfaces")
        top = max(top, failed.max())
    ax.set_xlabel("time [ms]")
    ax.set_ylabel("count")
    ax.set_yscale("log")
    ax.set_ylim(0.8, 2 * max(top, 1))
    ax.grid(alpha=0.3)
    ax2 = ax.twinx()
    ax2.plot(t, col(fh, fd, "largest_fraction"), "C3-", label="largest fragment's mass fraction")
    ax2.set_ylabel("largest fragment's mass fraction", color="C3")
    ax2.set_ylim(0, 1.05)
    lines = ax.get_lines() + ax2.get_lines()
    ax.legend(lines, [ln.get_label() for ln in lines], fontsize=8, loc="center right")
    ax.set_title("fragments and failed interfaces")

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
    fig.savefig(path, dpi=DPI)
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


TET_FACES = np.array([[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]])  # outward for positive tets


def draw_fragments_3d(ax, X, x, elems, ids, colours, keep):
    """Draws the faces of the kept tetrahedra that bound a fragment: faces on the outer surface,
    faces towards another fragment, and faces towards a removed element (a cut). Faces are matched
    by the reference positions of their nodes (elements of a fracturable region have their own
    copies of shared nodes)."""
    _, pos = np.unique(np.round(X / (1e-9 * np.ptp(X, axis=0).max())).astype(np.int64), axis=0,
                       return_inverse=True)
    pos = pos.ravel()
    ne = len(elems)
    fn = elems[:, TET_FACES].reshape(-1, 3)  # nodes of every face, 4 per element
    owner = np.repeat(np.arange(ne), 4)
    key = np.sort(pos[fn], axis=1)
    _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    inv = inv.ravel()
    # partner element of each face (-1: outer surface)
    order = np.argsort(inv, kind="stable")
    partner = np.full(len(fn), -1)
    si = inv[order]
    same = si[1:] == si[:-1]
    a, b = order[:-1][same], order[1:][same]
    partner[a] = owner[b]
    partner[b] = owner[a]
    o = owner
    p = np.maximum(partner, 0)
    show = keep[o] & ((partner < 0) | ~keep[p] | (ids[p] != ids[o]))
    tri = x[fn[show]]
    nrm = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    nrm /= np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-300)
    light = np.array([-0.4, -0.7, 0.6])
    light /= np.linalg.norm(light)
    shade = 0.45 + 0.55 * np.clip(nrm @ light, 0, 1)
    col = np.clip(colours[o[show]] * shade[:, None], 0, 1)
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    ax.add_collection3d(Poly3DCollection(tri, facecolors=col, edgecolors="none"))
    lo, hi = x[elems[keep]].reshape(-1, 3).min(axis=0), x[elems[keep]].reshape(-1, 3).max(axis=0)
    c, r = 0.5 * (lo + hi), 0.5 * (hi - lo).max()
    ax.set_xlim(c[0] - r, c[0] + r)
    ax.set_ylim(c[1] - r, c[1] + r)
    ax.set_zlim(c[2] - r, c[2] + r)
    try:
        ax.set_box_aspect((1, 1, 1))
    except AttributeError:
        pass
    ax.view_init(elev=15, azim=-75)
    ax.set_xlabel("x [m]", fontsize=8)
    ax.set_ylabel("y [m]", fontsize=8)
    ax.set_zlabel("z [m]", fontsize=8)
    ax.tick_params(labelsize=7)
    return c, r


def read_platens(out):
    """Platens of the run (from the resolved case.json): (point at t = 0, unit normal, shift), with
    shift(t) the plane's displacement from the point: v t for a prescribed platen (its `change`
    included), and for a platen with a mass its velocity across the normal times t plus the
    integral of history.csv's `<name>_speed [m/s]` along the normal."""
    try:
        with open(os.path.join(out, "case.json")) as f:
            case = json.load(f)
    except (OSError, ValueError):
        return []
    hh, hd = read_csv(os.path.join(out, "history.csv"))
    res = []
    for p in case.get("platens", []):
        n = np.array(p["normal"], float)
        n /= np.linalg.norm(n)
        v = np.array(p.get("velocity", [0] * len(n)), float)
        speed = p.get("name", "") + "_speed [m/s]"
        if p.get("mass", 0) > 0 and speed in hh:
            t, s = col(hh, hd, "time [s]"), col(hh, hd, speed)
            travel = np.concatenate([[0.0], np.cumsum(0.5 * (s[1:] + s[:-1]) * np.diff(t))])
            vt = v - np.dot(v, n) * n
            res.append((np.array(p["point"], float), n, lambda tt, t=t, a=travel, vt=vt, n=n: vt * tt + np.interp(tt, t, a) * n))
            continue
        ch = p.get("change")
        if ch:
            tc, v2 = float(ch["time"]), np.array(ch["velocity"], float)
            res.append((np.array(p["point"], float), n, lambda tt, v=v, tc=tc, v2=v2: v * tt if tt <= tc else v * tc + v2 * (tt - tc)))
        else:
            res.append((np.array(p["point"], float), n, lambda tt, v=v: v * tt))
    return res


def draw_platens_2d(ax, platens, t, lo, hi):
    for p0, n, shift in platens:
        c = p0 + shift(t)
        tang = np.array([-n[1], n[0]])
        s = np.linalg.norm(hi - lo)
        a, b = c - s * tang, c + s * tang
        ax.plot([a[0], b[0]], [a[1], b[1]], color="0.25", lw=3, solid_capstyle="butt", zorder=5)
        ax.plot([a[0] - 0.01 * s * n[0], b[0] - 0.01 * s * n[0]], [a[1] - 0.01 * s * n[1], b[1] - 0.01 * s * n[1]],
                color="0.6", lw=6, alpha=0.4, zorder=4)


def draw_platens_3d(ax, platens, t, centre, r):
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    for p0, n, shift in platens:
        c0 = p0 + shift(t)
        c = centre - np.dot(centre - c0, n) * n  # the body's centre projected on the plane
        a = np.cross(n, [1.0, 0, 0] if abs(n[0]) < 0.9 else [0, 1.0, 0])
        a /= np.linalg.norm(a)
        b = np.cross(n, a)
        quad = [c + r * (sa * a + sb * b) for sa, sb in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
        ax.add_collection3d(Poly3DCollection([quad], facecolors=[(0.3, 0.3, 0.35, 0.25)], edgecolors="0.3"))


def plot_frames(out, prefix, nframes):
    import h5py

    platens = read_platens(out)

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
                    seg = x[ifaces]
                    ax.add_collection(LineCollection(seg[dmg >= 1], colors="k", linewidths=0.6))
                size = np.ptp(X, axis=0).max()
                lo, hi = x.min(axis=0) - 0.03 * size, x.max(axis=0) + 0.03 * size
                draw_platens_2d(ax, platens, t, lo, hi)
                ax.set_xlim(lo[0], hi[0])
                ax.set_ylim(lo[1], hi[1])
                ax.set_aspect("equal")
                ax.set_xticks([])
                ax.set_yticks([])
                ax.set_title(title + "\nfailed interfaces black", fontsize=9)
            else:
                fig = plt.figure(figsize=(13, 6.5))
                cen0 = X[elems].mean(axis=1)
                mid = np.median(cen0[:, 1])
                views = [(np.ones(len(elems), bool), "outside"),
                         (cen0[:, 1] > mid, "cut open at y = %.3g mm (front half removed)" % (mid * 1e3))]
                for j, (keep, what) in enumerate(views):
                    ax = fig.add_subplot(1, 2, j + 1, projection="3d")
                    centre, r = draw_fragments_3d(ax, X, x, elems, ids, colours, keep)
                    draw_platens_3d(ax, platens, t, centre, r)
                    ax.set_title(what, fontsize=9)
                fig.suptitle(title + "\nfragment surfaces (outer surface and failed faces between fragments)",
                             fontsize=10)
            fig.tight_layout()
            path = os.path.join(out, "%s_%d.png" % (prefix, k))
            fig.savefig(path, dpi=DPI)
            plt.close(fig)
            paths.append(path)
    return paths


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out", help="output folder of a run")
    ap.add_argument("--frames", type=int, default=4)
    ap.add_argument("--prefix", default="fragments", help="file name prefix (default: fragments)")
    ap.add_argument("--dpi", type=int, default=110)
    a = ap.parse_args()
    global DPI
    DPI = a.dpi
    if not os.path.exists(os.path.join(a.out, "fragments.csv")):
        sys.exit("plot_fragments.py: %s: no fragments.csv (a run of a case with interfaces writes it)" % a.out)
    written = [plot_curves(a.out, a.prefix)] + plot_frames(a.out, a.prefix, a.frames)
    for p in written:
        if p:
            print(p)


if __name__ == "__main__":
    main()
