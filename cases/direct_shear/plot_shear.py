#!/usr/bin/python3
"""Shear and normal stress of the direct shear case against the slip, from its runs' output.

    cases/direct_shear/plot_shear.py OUT_DIR [OUT_DIR ...] [--png FILE]

Each OUT_DIR is a run of cases/direct_shear/case.json (e.g. one with the default law and one with
--set interface_materials.joint_if.law=paper). Stresses are the lower block's reactions over the
joint's area (0.1 m x 1 m), the slip the upper block's mean x displacement. Writes FILE (default
shear.png in the first OUT_DIR) with tau and sigma_n tan(phi_r) against the slip, and prints per
run the peak, the lowest tau / sigma_n after it and the last one.
Uses Debian's python3-matplotlib.
"""
import argparse
import csv
import json
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

AREA = 0.1


def load(out):
    rows = list(csv.DictReader(open(os.path.join(out, "history.csv"))))
    tau = [abs(float(r["region.lower_reaction_x [N]"])) / AREA for r in rows]
    sig = [abs(float(r["region.lower_reaction_y [N]"])) / AREA for r in rows]
    slip = [float(r["region.upper_ux [m]"]) for r in rows]
    err = max(abs(float(r["energy_error [J]"])) for r in rows) / max(abs(float(r["W_external [J]"])) for r in rows)
    resolved = json.load(open(os.path.join(out, "case_resolved.json"))) if os.path.exists(
        os.path.join(out, "case_resolved.json")) else None
    return tau, sig, slip, err, resolved


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("outs", nargs="+")
    ap.add_argument("--png")
    a = ap.parse_args()
    fig, (ax, ar) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    for out in a.outs:
        tau, sig, slip, err, _ = load(out)
        ip = max(range(len(tau)), key=lambda i: tau[i])
        ratios = [tau[i] / sig[i] for i in range(ip, len(tau)) if sig[i] > 0]
        print("%s: peak %.4g MPa at %.3g mm (sigma_n %.4g MPa), tau / sigma_n after the peak lowest %.4f, last %.4f; "
              "worst balance error %.3g %% of the work" % (out, tau[ip] / 1e6, slip[ip] * 1e3, sig[ip] / 1e6,
                                                           min(ratios), ratios[-1], 100 * err))
        name = os.path.basename(out.rstrip("/"))
        ax.plot([s * 1e3 for s in slip], [t / 1e6 for t in tau], lw=1.2, label=name)
        big = [i for i in range(len(sig)) if sig[i] > 0.2 * max(sig)]  # once the normal load is on
        ar.plot([slip[i] * 1e3 for i in big], [tau[i] / sig[i] for i in big], lw=1.2, label=name)
    ar.set_xlabel("slip [mm]")
    ax.set_ylabel("shear stress tau [MPa]")
    ar.set_ylabel("tau / sigma_n")
    ar.set_ylim(0, 1.3)
    for a_ in (ax, ar):
        a_.grid(alpha=0.3)
        a_.legend(fontsize=8)
    fig.tight_layout()
    png = a.png or os.path.join(a.outs[0], "shear.png")
    fig.savefig(png, dpi=130)
    print("wrote", png)


if __name__ == "__main__":
    main()
