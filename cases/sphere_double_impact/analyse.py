#!/usr/bin/python3
"""The measures of Wu, Chau and Yu's double impact test, read from runs of this case.

    cases/sphere_double_impact/analyse.py RUN_OR_ENSEMBLE_DIR ... [--json FILE]

Each argument is a run's output folder (summary.json, snapshots.h5) or an ensemble's (its
realisations r0000, r0001, ...). Per run it prints, and with --json writes:
  energy_J        the drop weight's kinetic energy at the start (mass and speed of case.json)
  pattern         "intact" (largest fragment >= 0.9 of the mass, no split), "ends crushed" (no
                  meridian split, largest >= 0.7), "split k" (k meridian pieces), "shattered"
  meridian        meridian pieces: fragments of >= 5 % of the mass whose material spanned the
                  sphere's height (from below -R/2 to above R/2 in the reference configuration):
                  what is left of the primary fractures through the loading axis
  crushed_mm      diameter of the crushed zones at the two ends: twice the 90th percentile of the
                  distance from the loading axis of the crushed material (fragments of < 1 % of
                  the mass) within R/5 of either pole, in the reference configuration; the mean of
                  the two ends
  n_small,        the Gates-Gaudin-Schuhmann exponents: slope of log P(d) against log d, P the mass
  n_large         share of fragments smaller than d, d their equivalent size (d / D = (m / M)^(1/3)),
                  fitted over the small fragments (2 to 30 elements: what the mesh resolves of
                  the secondary fragments) and over the large ones (5 % of the mass and up: the
                  primary pieces), as the paper fits two slopes
For an ensemble: the mean and the 95 % interval of the mean (t distribution) of each number, and
how often each pattern occurred. Uses Debian's python3-numpy and python3-h5py (/usr/bin/python3).
"""
import argparse
import glob
import json
import math
import os
import sys

import numpy as np

T95 = {1: 12.71, 2: 4.30, 3: 3.18, 4: 2.78, 5: 2.57, 6: 2.45, 7: 2.36, 8: 2.31, 9: 2.26, 10: 2.23, 15: 2.13, 20: 2.09}


def t95(dof):
    keys = sorted(k for k in T95 if k <= dof)
    return T95[keys[-1]] if keys else float("nan")


def case_numbers(out):
    with open(os.path.join(out, "case.json")) as f:
        case = json.load(f)
    R = float(case["mesh"]["radius"])
    weight = [p for p in case["platens"] if p.get("mass", 0) > 0]
    energy = 0.0
    if weight:
        v = np.array(weight[0]["velocity"], float)
        energy = 0.5 * float(weight[0]["mass"]) * float(np.dot(v, v))
    return R, energy, float(case["mesh"]["element_size"])


def crushed_diameter(out, R, small):
    """Twice the 90th percentile distance from the axis of crushed elements near either pole."""
    import h5py

    path = os.path.join(out, "snapshots.h5")
    if not os.path.exists(path):
        return float("nan")
    with h5py.File(path, "r") as f:
        frames = sorted(k for k in f.keys() if k.startswith("step_"))
        X = f["mesh/reference_coordinates"][()]
        E = f["mesh/elements"][()]
        frag = f[frames[-1] + "/fragment"][()]
    c = X[E].mean(axis=1)
    vol = np.abs(np.einsum("ij,ij->i", np.cross(X[E[:, 1]] - X[E[:, 0]], X[E[:, 2]] - X[E[:, 0]]), X[E[:, 3]] - X[E[:, 0]])) / 6
    mass = np.bincount(frag, weights=vol)
    crushed = mass[frag] < small * vol.sum()
    rho = np.hypot(c[:, 0], c[:, 1])
    out_d = []
    for top in (True, False):
        near = (c[:, 2] > R - R / 5) if top else (c[:, 2] < -R + R / 5)
        sel = rho[near & crushed]
        out_d.append(2 * np.percentile(sel, 90) if sel.size >= 3 else 0.0)
    return float(np.mean(out_d))


def ggs_exponent(summary, elements, lo, hi):
    """Slope of log P(d) against log d over fragments of lo to hi of the mass (fractions)."""
    cm = summary["fragments"]["cumulative_mass"]
    x = np.array(cm["fragment_fraction_at_least"], float)
    finer = 1.0 - np.array(cm["mass_fraction"], float)  # mass share of fragments smaller than x M
    sel = (x >= lo) & (x <= hi) & (finer > 1e-6) & (finer < 1 - 1e-9)
    if sel.sum() < 2:
        return float("nan")
    return float(np.polyfit(np.log(x[sel] ** (1.0 / 3.0)), np.log(finer[sel]), 1)[0])


def analyse_run(out):
    with open(os.path.join(out, "summary.json")) as f:
        s = json.load(f)
    R, energy, h = case_numbers(out)
    elements = s["counts"]["elements"]
    largest = s["fragments"].get("largest", [])
    meridian = sum(
        1
        for g in largest
        if g["fraction"] >= 0.05 and g["reference_box_min"][2] < -R / 2 and g["reference_box_max"][2] > R / 2
    )
    big = s["fragments"]["largest_fraction"]
    if meridian >= 2:
        pattern = "split %d" % meridian
    elif big >= 0.9:
        pattern = "intact"
    elif big >= 0.7:
        pattern = "ends crushed"
    else:
        pattern = "shattered"
    return {
        "run": out,
        "energy_J": energy,
        "h_m": h,
        "pattern": pattern,
        "meridian": meridian,
        "largest_fraction": big,
        "crushed_mm": 1e3 * crushed_diameter(out, R, 0.01),
        "n_small": ggs_exponent(s, elements, 2.0 / elements, 30.0 / elements),
        "n_large": ggs_exponent(s, elements, 0.05, 1.0),
        "fracture_J": s["energy"]["fracture_J"],
        "fragments": s["fragments"]["count"],
    }


def summarise(rows):
    res = {"runs": len(rows), "energy_J": rows[0]["energy_J"], "h_m": rows[0]["h_m"], "patterns": {}}
    for r in rows:
        res["patterns"][r["pattern"]] = res["patterns"].get(r["pattern"], 0) + 1
    for key in ("meridian", "largest_fraction", "crushed_mm", "n_small", "n_large", "fracture_J", "fragments"):
        v = np.array([r[key] for r in rows], float)
        v = v[np.isfinite(v)]
        if v.size == 0:
            continue
        half = t95(v.size - 1) * v.std(ddof=1) / math.sqrt(v.size) if v.size > 1 else float("nan")
        res[key] = {"mean": float(v.mean()), "ci95": [float(v.mean() - half), float(v.mean() + half)],
                    "min": float(v.min()), "max": float(v.max())}
    return res


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("dirs", nargs="+")
    ap.add_argument("--json", help="write the results here")
    a = ap.parse_args()
    report = []
    for d in a.dirs:
        runs = sorted(glob.glob(os.path.join(d, "r[0-9][0-9][0-9][0-9]")))
        if runs:
            rows = [analyse_run(r) for r in runs if os.path.exists(os.path.join(r, "summary.json"))]
            if not rows:
                print(f"{d}: no finished realisation", file=sys.stderr)
                continue
            s = summarise(rows)
            s["ensemble"] = d
            s["realisations"] = rows
            report.append(s)
            fmt = lambda k: "%.3g [%.3g, %.3g]" % (s[k]["mean"], *s[k]["ci95"]) if k in s else "-"
            print(f"{d}: {len(rows)} runs, {s['energy_J']:.1f} J, h {1e3 * s['h_m']:.1f} mm: patterns {s['patterns']}; "
                  f"meridian {fmt('meridian')}, crushed {fmt('crushed_mm')} mm, n small {fmt('n_small')}, "
                  f"n large {fmt('n_large')}, "
                  f"largest {fmt('largest_fraction')}, fracture {fmt('fracture_J')} J")
        else:
            r = analyse_run(d)
            report.append(r)
            print(f"{d}: {r['energy_J']:.1f} J, h {1e3 * r['h_m']:.1f} mm: {r['pattern']}, meridian {r['meridian']}, "
                  f"crushed {r['crushed_mm']:.1f} mm, n small {r['n_small']:.2f}, n large {r['n_large']:.2f}, largest {r['largest_fraction']:.3f}, "
                  f"fracture {r['fracture_J']:.3f} J, {r['fragments']} fragments")
    if a.json:
        with open(a.json, "w") as f:
            json.dump(report, f, indent=1)


if __name__ == "__main__":
    main()
