#!/usr/bin/python3
"""Pictures and numbers of a slope_failure run, from its own output.

    cases/slope_failure/plot_slope.py OUT_DIR [--frames SRF,SRF,...]

Writes into OUT_DIR:
  slope_history.png   crest displacement and kinetic energy against the strength reduction
                      factor (log scales), with the limit-equilibrium factors of safety;
  slope_stages.png    the slope at the snapshots nearest the given factors (default
                      1.5, 1.75, 2.0 and the last), true scale: elements coloured by their
                      displacement, damaged interfaces orange, failed ones red;
  slope_results.json  the factor at which the crest has moved 1 mm, 1 cm, 10 cm and 1 m since the
                      reduction began, at which the kinetic energy first exceeds 1 J and 1 kJ,
                      between which top-surface nodes the back (tension) crack runs at SRF 2, and the
                      limit-equilibrium factors (limit_equilibrium.py).
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
from matplotlib.colors import LogNorm  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import limit_equilibrium  # noqa: E402


def history(out):
    with open(os.path.join(out, "history.csv")) as f:
        rows = list(csv.DictReader(f))
    h = {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}
    srf = h["strength_reduction_factor"]
    i0 = int(np.argmax(srf > srf[0]))  # first row of the reduction
    du = np.hypot(h["wedge_top_ux [m]"] - h["wedge_top_ux [m]"][i0], h["wedge_top_uy [m]"] - h["wedge_top_uy [m]"][i0])
    return h, srf, du, i0


def first(srf, values, threshold, i0):
    j = np.nonzero(values[i0:] > threshold)[0]
    return float(srf[i0 + j[0]]) if len(j) else None


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out")
    ap.add_argument("--frames", default="1.5,1.75,2.0,last")
    a = ap.parse_args()
    out = a.out
    h, srf, du, i0 = history(out)
    ek = h["E_kinetic [J]"]
    le = limit_equilibrium.factors(os.path.join(out, "case.json") if os.path.exists(os.path.join(out, "case.json")) else
                                   os.path.join(os.path.dirname(os.path.abspath(__file__)), "case.json"))
    res = {"limit_equilibrium": {"FS": le["FS"], "FS_tension_crack": le["FS_tension_crack"],
                                 "x_tension_crack_m": le["x_tension_crack"], "crest_x_m": le["xf"]}}
    res["srf_at_crest_displacement"] = {"%g m" % t: first(srf, du, t, i0) for t in (1e-3, 1e-2, 1e-1, 1.0)}
    res["srf_at_kinetic_energy"] = {"%g J" % t: first(srf, ek, t, i0) for t in (1.0, 1e3)}
    res["final"] = {"srf": float(srf[-1]), "crest_displacement_m": float(du[-1]), "kinetic_energy_J": float(ek[-1]),
                    "interfaces_failed": int(h["interfaces_failed"][-1])}

    # ---- curves ----
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.6))
    red = srf >= srf[0] + 1e-12
    for ax, y, lab in ((axes[0], np.maximum(du, 1e-7), "crest displacement since the reduction began [m]"),
                       (axes[1], np.maximum(ek, 1e-9), "kinetic energy [J]")):
        ax.semilogy(srf[red], y[red], "k-", lw=1.5)
        ax.axvline(le["FS"], color="tab:blue", ls="--", label="limit equilibrium, planar: FS %.3f" % le["FS"])
        ax.axvline(le["FS_tension_crack"], color="tab:green", ls=":",
                   label="with critical tension crack: FS %.3f" % le["FS_tension_crack"])
        ax.set_xlabel("strength reduction factor")
        ax.set_ylabel(lab)
        ax.grid(alpha=0.3, which="both")
    s1 = res["srf_at_crest_displacement"]["0.01 m"]
    if s1:
        axes[0].axvline(s1, color="tab:red", lw=1, label="crest moved 1 cm: SRF %.3f" % s1)
    axes[0].legend(fontsize=8, loc="upper left")
    axes[0].set_title("slope failure: crest displacement")
    axes[1].set_title("kinetic energy")
    axes[1].legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "slope_history.png"), dpi=110)
    plt.close(fig)

    # ---- stages ----
    import h5py

    with h5py.File(os.path.join(out, "snapshots.h5"), "r") as f:
        E = f["mesh/elements"][()]
        I = f["mesh/interfaces"][()]
        X = f["mesh/reference_coordinates"][()][:, :2]
        region = f["mesh/region"][()]
        names = [n.decode() if isinstance(n, bytes) else n for n in f["mesh/region_names"][()]]
        wedge = region == names.index("weathered")
        steps = sorted(k for k in f.keys() if k.startswith("step_"))
        times = np.array([float(f[s].attrs["time"]) for s in steps])
        srf_t = np.interp(times, h["time [s]"], srf)
        want = [float(x) if x != "last" else srf_t[-1] for x in a.frames.split(",")]
        pick = [int(np.argmin(np.abs(srf_t - w))) for w in want]
        fig, axes = plt.subplots(1, len(pick), figsize=(4.6 * len(pick), 3.9))
        norm = LogNorm(1e-4, 10)
        for ax, i in zip(np.atleast_1d(axes), pick):
            g = f[steps[i]]
            u = g["displacement"][()][:, :2]
            x = X + u
            dmg = g["damage"][()]
            umag = np.linalg.norm(u, axis=1)[E].mean(axis=1)
            pc = PolyCollection(x[E], array=np.maximum(umag, 1e-4), cmap="viridis", norm=norm, edgecolors="none")
            ax.add_collection(pc)
            seg = x[I]
            ax.add_collection(LineCollection(seg[(dmg > 0) & (dmg < 1)], colors="orange", linewidths=0.5))
            ax.add_collection(LineCollection(seg[dmg >= 1], colors="red", linewidths=1.2))
            ax.set_xlim(12, 50)
            ax.set_ylim(-2, 22)
            ax.set_aspect("equal")
            ax.set_xticks([])
            ax.set_yticks([])
            ax.set_title("SRF %.2f (t = %.2f s): %d damaged, %d failed" % (srf_t[i], times[i], ((dmg > 0) & (dmg < 1)).sum(),
                                                                        (dmg >= 1).sum()), fontsize=9)
        fig.colorbar(pc, ax=axes, label="displacement [m] (true scale)", shrink=0.8)
        fig.savefig(os.path.join(out, "slope_stages.png"), dpi=110, bbox_inches="tight")
        plt.close(fig)

        # back crack: on the top surface of the wedge, the boundary between what slid and what
        # stayed, at the snapshot nearest SRF 2 (later the rest follows)
        k = int(np.argmin(np.abs(srf_t - 2.0)))
        u = f[steps[k]]["displacement"][()][:, :2]
        wn = np.unique(E[wedge])
        top = wn[X[wn, 1] > le["H"] - 1e-3]
        moved = np.linalg.norm(u[top], axis=1)
        big, small = top[moved > 0.5 * moved.max()], top[moved < 0.1 * moved.max()]
        if len(big) and len(small):
            res["back_crack"] = {"srf": float(srf_t[k]), "x_m": [float(X[big, 0].max()), float(X[small, 0].min())]}
    with open(os.path.join(out, "slope_results.json"), "w") as f:
        json.dump(res, f, indent=2)
    print(json.dumps(res, indent=2))
    for p in ("slope_history.png", "slope_stages.png", "slope_results.json"):
        print(os.path.join(out, p))


if __name__ == "__main__":
    main()
