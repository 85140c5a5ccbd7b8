#!/usr/bin/python3
"""Strength and crack composition of granite_brazilian runs (cases/granite_brazilian/README.md).

    cases/granite_brazilian/analyse.py OUT_DIR [OUT_DIR ...] [--json FILE]

For each output folder: the tensile strength 2 P_max / (pi D t) (summary.json), and from the last
snapshot the failed interfaces (damage 1) per interface material: how much of the crack runs along
grain boundaries (intergranular) and how much through grains (transgranular), by length; and the
mean |x| of the failed interfaces in the central half of the loaded diameter (|y| < R/2), which is
how far the split lies from the diameter. With several folders (seeds) also the mean and the
standard deviation. Uses Debian's python3-h5py and python3-numpy.
"""
import argparse
import json
import os
import statistics

import h5py
import numpy as np


def analyse(out):
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    res = summary["results"]
    row = {"out": out, "strength_MPa": res["tensile_strength_Pa"] / 1e6}
    with h5py.File(os.path.join(out, "snapshots.h5"), "r") as f:
        mesh = f["mesh"]
        X = mesh["reference_coordinates"][()][:, :2]
        ifaces = mesh["interfaces"][()]
        names = [n.decode() if isinstance(n, bytes) else str(n) for n in mesh["interface_material_names"][()]]
        mat = mesh["interface_material"][()]
        last = sorted(k for k in f.keys() if k.startswith("step_"))[-1]
        dmg = f[last]["damage"][()]
    seg = X[ifaces]  # (n, 2, 2): the A-side nodes of each interface
    length = np.linalg.norm(seg[:, 1] - seg[:, 0], axis=1)
    failed = dmg >= 1
    total = length[failed].sum()
    row["failed_interfaces"] = int(failed.sum())
    row["failed_length_mm"] = float(total * 1e3)
    row["crack_share_by_material"] = {
        n: float(length[failed & (mat == i)].sum() / total) if total > 0 else 0.0 for i, n in enumerate(names)}
    row["interface_share_by_material"] = {
        n: float(length[mat == i].sum() / length.sum()) for i, n in enumerate(names)}
    mid = seg.mean(axis=1)
    R = np.abs(X).max()
    central = failed & (np.abs(mid[:, 1]) < 0.5 * R)
    row["split_mean_abs_x_mm"] = float(np.abs(mid[central, 0]).mean() * 1e3) if central.any() else None
    return row


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("outs", nargs="+")
    ap.add_argument("--json", help="write the rows and the statistics to this file")
    a = ap.parse_args()
    rows = [analyse(o) for o in a.outs]
    for r in rows:
        share = ", ".join("%s %.0f %%" % (k, 100 * v) for k, v in r["crack_share_by_material"].items())
        print("%s: strength %.2f MPa, %d failed interfaces (%.0f mm): %s; split |x| %s mm"
              % (r["out"], r["strength_MPa"], r["failed_interfaces"], r["failed_length_mm"], share,
                 "%.1f" % r["split_mean_abs_x_mm"] if r["split_mean_abs_x_mm"] is not None else "-"))
    stats = {}
    if len(rows) > 1:
        s = [r["strength_MPa"] for r in rows]
        gb = [r["crack_share_by_material"].get("grain_boundary_if", 0.0) for r in rows]
        stats = {"runs": len(rows), "strength_mean_MPa": statistics.mean(s),
                 "strength_std_MPa": statistics.stdev(s), "grain_boundary_share_mean": statistics.mean(gb)}
        print("mean strength %.2f MPa, std %.2f MPa (%.1f %%); grain-boundary share of the crack %.0f %%"
              % (stats["strength_mean_MPa"], stats["strength_std_MPa"],
                 100 * stats["strength_std_MPa"] / stats["strength_mean_MPa"], 100 * stats["grain_boundary_share_mean"]))
    if a.json:
        with open(a.json, "w") as f:
            json.dump({"rows": rows, "statistics": stats}, f, indent=1)


if __name__ == "__main__":
    main()
