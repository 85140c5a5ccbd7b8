#!/usr/bin/python3
"""Curves, crack path and pictures of a sen_beam run, from its own output.

    cases/sen_beam/plot_sen.py OUT_DIR [--magnify M]

Writes into OUT_DIR:
  sen_curves.png    load against crack-mouth opening displacement (CMOD) and against the
                    deflection of the top edge at the load, and the supports' share of the load
                    (1 in equilibrium: the local damping or inertia carry the rest);
  sen_crack.png     the beam at the end with the deformation magnified M times (default 10, as
                    in the paper): damaged interfaces orange, failed red, the crack path black;
  crack_path.csv    the crack path as a polyline (x, y in mm from the mid-span of the bottom edge):
                    the failed interfaces connected to the notch tip, their mid-points averaged
                    over 5 mm bins of height;
  sen_results.json  peak load, CMOD at the peak, where the crack path ends, equilibrium.
Load: the load platen's force on the beam; CMOD: the x displacement of the notch's right mouth
corner minus the left one. Uses Debian's python3-matplotlib, python3-h5py and python3-numpy.
"""
import argparse
import csv
import json
import os
from collections import defaultdict, deque

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import LineCollection, PolyCollection  # noqa: E402

NOTCH_TIP = (0.0, 0.075)


def crack_path(X, I, failed, region_of_iface=None):
    """Failed interfaces connected (through shared vertices) to the notch tip; polyline."""
    key = lambda p: (round(p[0] * 1e6), round(p[1] * 1e6))  # noqa: E731
    ends = defaultdict(list)
    ids = np.nonzero(failed)[0]
    for q in ids:
        for n in I[q]:
            ends[key(X[n])].append(q)
    mids = 0.5 * (X[I[:, 0]] + X[I[:, 1]])
    start = [q for q in ids if np.hypot(mids[q, 0] - NOTCH_TIP[0], mids[q, 1] - NOTCH_TIP[1]) < 0.012]
    seen, todo = set(start), deque(start)
    while todo:
        q = todo.popleft()
        for n in I[q]:
            for r in ends[key(X[n])]:
                if r not in seen:
                    seen.add(r)
                    todo.append(r)
    pts = mids[sorted(seen)]
    if len(pts) == 0:
        return np.zeros((0, 2)), []
    bins = np.floor((pts[:, 1] - NOTCH_TIP[1]) / 0.005).astype(int)
    poly = [NOTCH_TIP]
    for b in sorted(set(bins)):
        if b < 0:
            continue
        sel = pts[bins == b]
        poly.append((sel[:, 0].mean(), sel[:, 1].mean()))
    return np.array(poly), sorted(seen)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out")
    ap.add_argument("--magnify", type=float, default=10)
    a = ap.parse_args()
    out = a.out
    with open(os.path.join(out, "history.csv")) as f:
        rows = list(csv.DictReader(f))
    h = {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}
    P = h["load_load [N]"]
    R = h["supports_load [N]"]
    cmod = h["mouth_right_ux [m]"] - h["mouth_left_ux [m]"]
    defl = -h["load_point_uy [m]"]
    ip = int(np.argmax(P))
    res = {"peak_load_N": float(P[ip]), "cmod_at_peak_m": float(cmod[ip]), "deflection_at_peak_m": float(defl[ip]),
           "supports_over_load_at_peak": float(R[ip] / P[ip]) if P[ip] > 0 else None,
           "supports_over_load_mean_above_half_peak": float(np.mean(R[P > 0.5 * P[ip]] / P[P > 0.5 * P[ip]])),
           "final_cmod_m": float(cmod[-1]), "final_load_N": float(P[-1]),
           "interfaces_failed": int(h["interfaces_failed"][-1])}

    fig, axes = plt.subplots(1, 3, figsize=(15, 4.4))
    axes[0].plot(cmod * 1e3, P / 1e3, "k-")
    axes[0].plot(cmod[ip] * 1e3, P[ip] / 1e3, "ro")
    axes[0].set_xlabel("CMOD [mm]")
    axes[0].set_ylabel("load [kN]")
    axes[0].set_title("load-CMOD: peak %.2f kN at CMOD %.3f mm" % (P[ip] / 1e3, cmod[ip] * 1e3))
    axes[1].plot(defl * 1e3, P / 1e3, "k-")
    axes[1].set_xlabel("deflection of the top edge at the load [mm]")
    axes[1].set_ylabel("load [kN]")
    axes[1].set_title("load-deflection")
    ok = P > 0.05 * P[ip]
    axes[2].plot(h["time [s]"][ok] * 1e3, R[ok] / P[ok], "b-")
    axes[2].set_ylim(0.8, 1.2)
    axes[2].set_xlabel("time [ms]")
    axes[2].set_ylabel("support reactions / load")
    axes[2].set_title("equilibrium")
    for ax in axes:
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "sen_curves.png"), dpi=110)
    plt.close(fig)

    import h5py

    with h5py.File(os.path.join(out, "snapshots.h5"), "r") as f:
        E = f["mesh/elements"][()]
        I = f["mesh/interfaces"][()]
        X = f["mesh/reference_coordinates"][()][:, :2]
        region = f["mesh/region"][()]
        steps = sorted(k for k in f.keys() if k.startswith("step_"))
        g = f[steps[-1]]
        u = g["displacement"][()][:, :2]
        dmg = g["damage"][()]
    poly, ids = crack_path(X, I, dmg >= 1)
    with open(os.path.join(out, "crack_path.csv"), "w") as f:
        f.write("x [mm],y [mm]\n")
        for x, y in poly:
            f.write("%.2f,%.2f\n" % (x * 1e3, y * 1e3))
    if len(poly) > 1:
        res["crack_path_end_mm"] = [float(poly[-1][0] * 1e3), float(poly[-1][1] * 1e3)]
        res["crack_path_points"] = len(poly)
        res["crack_failed_interfaces"] = len(ids)

    x = X + a.magnify * u
    fig, ax = plt.subplots(figsize=(13, 4.2))
    col = np.where(region[:, None] == region.max(), [0.6, 0.6, 0.9, 1.0], [0.9, 0.9, 0.9, 1.0])
    ax.add_collection(PolyCollection(x[E], facecolors=col, edgecolors="#bbbbbb", linewidths=0.2))
    seg = x[I]
    ax.add_collection(LineCollection(seg[(dmg > 0) & (dmg < 1)], colors="orange", linewidths=0.6))
    ax.add_collection(LineCollection(seg[dmg >= 1], colors="red", linewidths=1.4))
    if len(poly) > 1:
        ax.plot(poly[:, 0], poly[:, 1], "k--", lw=1, label="crack path (undeformed), crack_path.csv")
        ax.legend(loc="lower left", fontsize=8)
    ax.set_xlim(-0.36, 0.36)
    ax.set_ylim(-0.03, 0.18)
    ax.set_aspect("equal")
    ax.set_title("end of the run: %d damaged (orange), %d failed (red) interfaces; deformation x%g"
                 % (((dmg > 0) & (dmg < 1)).sum(), (dmg >= 1).sum(), a.magnify), fontsize=9)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "sen_crack.png"), dpi=110)
    plt.close(fig)
    with open(os.path.join(out, "sen_results.json"), "w") as f:
        json.dump(res, f, indent=2)
    print(json.dumps(res, indent=2))


if __name__ == "__main__":
    main()
