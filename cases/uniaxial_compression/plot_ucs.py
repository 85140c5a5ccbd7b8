#!/usr/bin/python3
"""Pictures and numbers of a uniaxial_compression run, from its own output.

    cases/uniaxial_compression/plot_ucs.py OUT_DIR [--magnify M]

Writes into OUT_DIR:
  ucs_curves.png    axial stress (= deviatoric stress sigma_1 - sigma_3, sigma_3 = 0) against
                    axial strain and against lateral strain, with the line of slope E_eff of
                    the crossed-diagonal mesh (below);
  ucs_cracks.png    the specimen at six instants (on the rising branch, at the peak, and after
                    it): displacement magnitude (the paper's "nephograms"), damaged interfaces
                    in white, failed ones in black, deformation magnified M times (default 20);
  ucs_results.json  peak stress and strain, the measured slope of the linear part (10 - 50 % of the
                    peak) and E_eff.

Axial strain: the platens' approach over the height; axial stress: the top platen's load over
width x thickness; lateral strain: the mean x displacement of the right side minus the left side,
over the width.

E_eff of the crossed-diagonal mesh (4 triangles per square cell of size d, interfaces on the cell
edges and on both diagonals): under uniaxial stress sigma the stress is the same in every triangle
(traction continuity holds on every interface, and the interface openings close around every
node), so the strain is the bulk strain plus the openings (normal 1/k_n, shear 1/k_s times the
traction) summed over the interfaces of a cell, divided by its area:

    1 / E_eff = (1 - nu^2) / E + (1 / d) (1 / k_n + (1 / k_n + 1 / k_s) / sqrt(2))   (plane strain)

(the horizontal edge opens by sigma / k_n; each of the four half-diagonals, length d / sqrt(2),
carries sigma / 2 normal and sigma / 2 shear), and the lateral strain over the axial one is
E_eff (nu (1 + nu) / E + (1 / k_s - 1 / k_n) / (sqrt(2) d)). the paper's E / (1.1 (1 - nu^2)) is that of blocks
in series with one interface per d along the load (alpha = E / (k_n d) = 0.1).
Uses Debian's python3-matplotlib, python3-h5py and python3-numpy.
"""
import argparse
import csv
import json
import math
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import LineCollection, PolyCollection  # noqa: E402


def e_eff_crossed(E, nu, kn, ks, d, plane_strain=True):
    bulk = (1 - nu * nu) / E if plane_strain else 1 / E
    return 1 / (bulk + (1 / kn + (1 / kn + 1 / ks) / math.sqrt(2)) / d)


def nu_eff_crossed(E, nu, kn, ks, d, plane_strain=True):
    """Lateral over axial strain under uniaxial stress (the diagonals' shear opening widens)."""
    bulk = nu * (1 + nu) / E if plane_strain else nu / E
    return e_eff_crossed(E, nu, kn, ks, d, plane_strain) * (bulk + (1 / ks - 1 / kn) / (math.sqrt(2) * d))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out")
    ap.add_argument("--magnify", type=float, default=20)
    a = ap.parse_args()
    out = a.out
    with open(os.path.join(out, "case.json")) as f:
        case = json.load(f)
    W, H = case["mesh"]["size"]
    d = case["mesh"].get("element_size") or W / case["mesh"]["cells"][0]
    if "cells" in case["mesh"] and case["mesh"]["cells"]:
        d = W / case["mesh"]["cells"][0]
    t = case["analysis"]["thickness"]
    ps = case["analysis"]["plane"] == "strain"
    mat = next(iter(case["materials"].values()))
    im = next(iter(case["interface_materials"].values()))
    E, nu = mat["E"], mat["nu"]
    Eeff = e_eff_crossed(E, nu, im["kn"], im["ks"], d, ps)
    Enaive = (E / (1 - nu * nu) if ps else E) / (1 + E / (im["kn"] * d))

    with open(os.path.join(out, "history.csv")) as f:
        rows = list(csv.DictReader(f))
    h = {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}
    eps = (h["top_displacement [m]"] + h["bottom_displacement [m]"]) / H
    sig = h["top_load [N]"] / (W * t)
    lat = (h["right_ux [m]"] - h["left_ux [m]"]) / W
    ip = int(np.argmax(sig))
    peak = sig[ip]
    rise = np.arange(ip + 1)
    sel = rise[(sig[rise] > 0.1 * peak) & (sig[rise] < 0.5 * peak)]
    slope = np.polyfit(eps[sel], sig[sel], 1)[0] if len(sel) > 2 else float("nan")
    slope_lat = np.polyfit(lat[sel], sig[sel], 1)[0] if len(sel) > 2 else float("nan")
    res = {"peak_stress_Pa": float(peak), "strain_at_peak": float(eps[ip]), "slope_10_50_Pa": float(slope),
           "E_eff_crossed_mesh_Pa": Eeff, "E_eff_blocks_in_series_Pa": Enaive,
           "slope_over_E_eff_crossed": float(slope / Eeff), "lateral_over_axial_strain": float(slope / slope_lat),
           "lateral_over_axial_strain_crossed_mesh": nu_eff_crossed(E, nu, im["kn"], im["ks"], d, ps),
           "final_strain": float(eps[-1]), "final_stress_Pa": float(sig[-1]),
           "cell_m": d, "interfaces_failed": int(h["interfaces_failed"][-1])}

    fig, axes = plt.subplots(1, 2, figsize=(12, 4.6))
    ax = axes[0]
    ax.plot(eps * 100, sig / 1e6, "k-", lw=1.5, label="axial (= deviatoric) stress")
    x = np.linspace(0, eps[ip] * 1.05, 10)
    ax.plot(x * 100, Eeff * x / 1e6, "b--", lw=1, label="E_eff of the crossed mesh %.1f GPa" % (Eeff / 1e9))
    ax.plot(x * 100, Enaive * x / 1e6, ":", color="gray", lw=1,
            label="E/(1.1 (1-nu^2)) %.1f GPa" % (Enaive / 1e9))
    ax.plot(eps[ip] * 100, peak / 1e6, "ro")
    ax.set_xlabel("axial strain [%]")
    ax.set_ylabel("axial stress [MPa]")
    ax.set_title("peak %.1f MPa at %.3f %%; slope %.1f GPa" % (peak / 1e6, eps[ip] * 100, slope / 1e9))
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax = axes[1]
    r = slice(0, ip + 1)  # up to the peak (after it the sides are broken pieces)
    ax.plot(-lat[r] * 100, sig[r] / 1e6, "g-", lw=1.5, label="lateral strain")
    ax.plot(eps[r] * 100, sig[r] / 1e6, "k-", lw=1, alpha=0.5, label="axial strain")
    ax.plot((eps[r] - lat[r]) * 100, sig[r] / 1e6, "m-", lw=1, alpha=0.7, label="volumetric strain (plane strain)")
    ax.axvline(0, color="k", lw=0.5)
    lo = min(-lat[: ip + 1].max(), 0) * 100
    ax.set_xlim(1.2 * lo, 1.1 * eps[ip] * 100)
    ax.set_xlabel("strain [%] (compression positive: lateral expansion to the left)")
    ax.set_ylabel("axial stress [MPa]")
    ax.set_title("lateral and volumetric strain up to the peak")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "ucs_curves.png"), dpi=110)
    plt.close(fig)

    import h5py

    with h5py.File(os.path.join(out, "snapshots.h5"), "r") as f:
        Em = f["mesh/elements"][()]
        I = f["mesh/interfaces"][()]
        X = f["mesh/reference_coordinates"][()][:, :2]
        steps = sorted(k for k in f.keys() if k.startswith("step_"))
        times = np.array([float(f[s].attrs["time"]) for s in steps])
        ht = h["time [s]"]
        # instants: 90 % of the peak on the rising branch, the peak, then 90, 70, 50 % after it, and the end
        targets = []
        j = int(np.argmax(sig > 0.9 * peak))
        targets.append(("%.0f %% of the peak, before it" % 90, ht[j]))
        targets.append(("peak", ht[ip]))
        for frac in (0.9, 0.7, 0.5):
            after = np.nonzero((np.arange(len(sig)) > ip) & (sig < frac * peak))[0]
            if len(after):
                targets.append(("%.0f %% of the peak, after it" % (frac * 100), ht[after[0]]))
        targets.append(("end", ht[-1]))
        fig, axes = plt.subplots(1, len(targets), figsize=(2.6 * len(targets), 5.2))
        for ax, (lab, tt) in zip(np.atleast_1d(axes), targets):
            k = int(np.argmin(np.abs(times - tt)))
            g = f[steps[k]]
            u = g["displacement"][()][:, :2]
            dmg = g["damage"][()]
            x = X + a.magnify * u
            um = np.linalg.norm(u, axis=1)[Em].mean(axis=1) * 1e3
            pc = PolyCollection(x[Em], array=um, cmap="jet", edgecolors="none")
            ax.add_collection(pc)
            ax.add_collection(LineCollection(x[I][(dmg > 0) & (dmg < 1)], colors="w", linewidths=0.5))
            ax.add_collection(LineCollection(x[I][dmg >= 1], colors="k", linewidths=0.8))
            ax.set_xlim(X[:, 0].min() - 0.15 * W, X[:, 0].max() + 0.15 * W)
            ax.set_ylim(-0.05 * H, 1.05 * H)
            ax.set_aspect("equal")
            ax.set_xticks([])
            ax.set_yticks([])
            ek = float(np.interp(times[k], ht, eps)) * 100
            sk = float(np.interp(times[k], ht, sig)) / 1e6
            ax.set_title("%s\nstrain %.3f %%, %.0f MPa\n%d damaged, %d failed"
                         % (lab, ek, sk, int(((dmg > 0) & (dmg < 1)).sum()), int((dmg >= 1).sum())), fontsize=8)
            fig.colorbar(pc, ax=ax, orientation="horizontal", pad=0.02, shrink=0.9, label="|u| [mm]")
        fig.suptitle("damaged (white) and failed (black) interfaces over the displacement magnitude; deformation x%g"
                     % a.magnify, fontsize=9)
        fig.savefig(os.path.join(out, "ucs_cracks.png"), dpi=110, bbox_inches="tight")
        plt.close(fig)
    with open(os.path.join(out, "ucs_results.json"), "w") as f:
        json.dump(res, f, indent=2)
    print(json.dumps(res, indent=2))
    for p in ("ucs_curves.png", "ucs_cracks.png", "ucs_results.json"):
        print(os.path.join(out, p))


if __name__ == "__main__":
    main()
