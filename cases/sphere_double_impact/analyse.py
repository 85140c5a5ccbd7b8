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
  travel_mm,      the weight's largest travel, the diameter of the cap it flattens, 2 (2 R travel)^(1/2),
  flat_mm,        and whether it stopped (its speed fell to zero) within the run: the paper's crushed
  stopped         ends are those of a weight that has stopped, d ~ (E R / p)^(1/4) for a constant
                  crushing pressure p, i.e. ~ v^(1/2) at a fixed mass
  n_small, n_all  the Gates-Gaudin-Schuhmann exponent: slope of log P(d) against log d, P the mass
                  share of fragments smaller than d, d their equivalent size (d / D = (m / M)^(1/3)),
                  on summary.json's grid of four points per decade of mass: fitted over the small
                  fragments (2 to 30 elements: what the mesh resolves of the secondary fragments),
                  and over every fragment of 2 elements and more (the gap between the small
                  fragments and the two to four primary pieces, which the runs leave empty, is in
                  it: a slope of the primary pieces alone is not defined by so few)
For an ensemble: the mean and the 95 % interval of the mean (t distribution) of each number, and
how often each pattern occurred; over the ensembles of one element size at several speeds, the
exponent b of the crushed ends' diameter ~ v^b (every realisation a point) and, over the runs whose
weight stopped, that of the flattened cap, each with its 95 % interval. Uses Debian's python3-numpy and python3-h5py (/usr/bin/python3).
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
    return R, energy, float(case["mesh"]["element_size"]), float(weight[0]["mass"]) if weight else 0.0


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


def weight_travel(out, R):
    """The drop weight's largest travel (history.csv) and the diameter of the cap it flattens,
    2 (2 R delta)^(1/2); whether it stopped (its speed fell to zero or below) within the run."""
    import csv

    path = os.path.join(out, "history.csv")
    with open(os.path.join(out, "case.json")) as f:
        names = [p["name"] for p in json.load(f)["platens"] if p.get("mass", 0) > 0]
    if not names or not os.path.exists(path):
        return float("nan"), float("nan"), False
    with open(path) as f:
        rows = list(csv.DictReader(f))
    disp = [float(r[names[0] + "_displacement [m]"]) for r in rows]
    speed = [float(r[names[0] + "_speed [m/s]"]) for r in rows]
    d = max(disp)
    return 1e3 * d, 2e3 * math.sqrt(2 * R * d), min(speed) <= 0


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
    R, energy, h, mass = case_numbers(out)
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
    travel, flat, stopped = weight_travel(out, R)
    return {
        "run": out,
        "travel_mm": travel,
        "flat_mm": flat,
        "stopped": stopped,
        "energy_J": energy,
        "mass_kg": mass,
        "h_m": h,
        "pattern": pattern,
        "meridian": meridian,
        "largest_fraction": big,
        "crushed_mm": 1e3 * crushed_diameter(out, R, 0.01),
        "n_small": ggs_exponent(s, elements, 2.0 / elements, 30.0 / elements),
        "n_all": ggs_exponent(s, elements, 2.0 / elements, 1.0),
        "fracture_J": s["energy"]["fracture_J"],
        "fragments": s["fragments"]["count"],
    }


def summarise(rows):
    res = {"runs": len(rows), "energy_J": rows[0]["energy_J"], "mass_kg": rows[0]["mass_kg"], "h_m": rows[0]["h_m"],
           "patterns": {}}
    for r in rows:
        res["patterns"][r["pattern"]] = res["patterns"].get(r["pattern"], 0) + 1
    res["stopped"] = sum(1 for r in rows if r["stopped"])
    for key in ("meridian", "largest_fraction", "crushed_mm", "travel_mm", "flat_mm", "n_small", "n_all", "fracture_J",
                "fragments"):
        v = np.array([r[key] for r in rows], float)
        v = v[np.isfinite(v)]
        if v.size == 0:
            continue
        half = t95(v.size - 1) * v.std(ddof=1) / math.sqrt(v.size) if v.size > 1 else float("nan")
        res[key] = {"mean": float(v.mean()), "ci95": [float(v.mean() - half), float(v.mean() + half)],
                    "min": float(v.min()), "max": float(v.max())}
    return res


def fit_power(x, y):
    """y = a x^b by least squares in logs over the points: b and its 95 % interval."""
    lx, ly = np.log(np.asarray(x, float)), np.log(np.asarray(y, float))
    n = lx.size
    A = np.vstack([lx, np.ones(n)]).T
    coef, res, _, _ = np.linalg.lstsq(A, ly, rcond=None)
    if n <= 2:
        return float(coef[0]), [float("nan"), float("nan")]
    s2 = float(np.sum((ly - A @ coef) ** 2)) / (n - 2)
    se = math.sqrt(s2 / np.sum((lx - lx.mean()) ** 2))
    half = t95(n - 2) * se
    return float(coef[0]), [float(coef[0] - half), float(coef[0] + half)]


def speeds_report(ensembles):
    """Over the ensembles of one element size at several speeds: the crushed zone's exponent of v
    (fitted to every realisation's diameter against its speed)."""
    pts = [(math.sqrt(2 * r["energy_J"] / e["mass_kg"]), r["crushed_mm"]) for e in ensembles
           for r in e["realisations"] if r["crushed_mm"] > 0]
    if len({round(v, 6) for v, _ in pts}) < 2:
        return None
    b, ci = fit_power([v for v, _ in pts], [d for _, d in pts])
    out = {"crushed_exponent_of_v": b, "ci95": ci, "points": len(pts)}
    # the runs whose weight stopped: the flattened cap's diameter against v
    st = [(math.sqrt(2 * r["energy_J"] / e["mass_kg"]), r["flat_mm"]) for e in ensembles for r in e["realisations"]
          if r["stopped"]]
    if len({round(v, 6) for v, _ in st}) >= 2:
        bf, cf = fit_power([v for v, _ in st], [d for _, d in st])
        out.update({"flat_exponent_of_v": bf, "flat_ci95": cf, "stopped_points": len(st)})
    return out


def plot(ensembles, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    by_h = {}
    for e in ensembles:
        by_h.setdefault(round(1e3 * e["h_m"], 2), []).append(e)
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.6))
    for h, es in sorted(by_h.items()):
        es = sorted(es, key=lambda e: e["energy_J"])
        E = [e["energy_J"] for e in es]
        for k, key, lab in ((0, "n_small", "n, 2-30 elements"), (0, "n_all", "n, all fragments")):
            m = [e[key]["mean"] for e in es]
            lo = [e[key]["mean"] - e[key]["ci95"][0] for e in es]
            hi = [e[key]["ci95"][1] - e[key]["mean"] for e in es]
            ax[k].errorbar(E, m, yerr=[lo, hi], marker="o" if key == "n_small" else "s", capsize=3,
                           label=f"{lab}, h = {h:g} mm")
        v = [math.sqrt(2 * e["energy_J"] / e["mass_kg"]) for e in es]
        m = [e["crushed_mm"]["mean"] for e in es]
        err = [[e["crushed_mm"]["mean"] - e["crushed_mm"]["ci95"][0] for e in es],
               [e["crushed_mm"]["ci95"][1] - e["crushed_mm"]["mean"] for e in es]]
        ax[1].errorbar(v, m, yerr=err, marker="o", capsize=3, label=f"h = {h:g} mm")
        names = sorted({p for e in es for p in e["patterns"]})
        bottom = np.zeros(len(es))
        for p in names:
            share = np.array([e["patterns"].get(p, 0) / e["runs"] for e in es])
            ax[2].bar([f"{x:.0f} J\nh {h:g}" for x in E], share, bottom=bottom, label=p)
            bottom += share
    ax[0].axhspan(0.8, 1.6, color="0.85", label="Wu et al.: n from 0.8 to 1.6")
    ax[0].set_xlabel("impact energy [J]")
    ax[0].set_ylabel("GGS exponent n")
    ax[0].legend(fontsize=7)
    vs = np.linspace(1.5, 10, 20)
    ref = by_h[min(by_h)] if by_h else []
    if ref:
        e0 = sorted(ref, key=lambda e: e["energy_J"])[len(ref) // 2]
        v0 = math.sqrt(2 * e0["energy_J"] / e0["mass_kg"])
        ax[1].plot(vs, e0["crushed_mm"]["mean"] * np.sqrt(vs / v0), "k--", label="v^(1/2) (Wu et al.)")
    ax[1].set_xscale("log")
    ax[1].set_yscale("log")
    ax[1].set_xlabel("weight's speed [m/s]")
    ax[1].set_ylabel("crushed zone diameter [mm]")
    ax[1].legend(fontsize=7)
    ax[2].set_ylabel("share of the realisations")
    ax[2].set_title("failure patterns", fontsize=9)
    ax[2].legend(fontsize=7)
    ax[2].tick_params(axis="x", labelsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=100)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("dirs", nargs="+")
    ap.add_argument("--json", help="write the results here")
    ap.add_argument("--plot", help="ensembles: draw n and the crushed zone against the energy, and the patterns")
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
                  f"n all {fmt('n_all')}, "
                  f"largest {fmt('largest_fraction')}, fracture {fmt('fracture_J')} J; weight stopped in {s['stopped']}, "
                  f"travel {fmt('travel_mm')} mm, flattened cap {fmt('flat_mm')} mm")
        else:
            r = analyse_run(d)
            report.append(r)
            print(f"{d}: {r['energy_J']:.1f} J, h {1e3 * r['h_m']:.1f} mm: {r['pattern']}, meridian {r['meridian']}, "
                  f"crushed {r['crushed_mm']:.1f} mm, n small {r['n_small']:.2f}, n all {r['n_all']:.2f}, largest {r['largest_fraction']:.3f}, "
                  f"fracture {r['fracture_J']:.3f} J, {r['fragments']} fragments")
    ens = [r for r in report if "ensemble" in r]
    by_h = {}
    for e in ens:
        by_h.setdefault(e["h_m"], []).append(e)
    for h, es in sorted(by_h.items()):
        sp = speeds_report(es)
        if sp:
            print(f"h {1e3 * h:g} mm: crushed zone diameter ~ v^b, b = {sp['crushed_exponent_of_v']:.2f} "
                  f"[{sp['ci95'][0]:.2f}, {sp['ci95'][1]:.2f}] over {sp['points']} realisations")
            if "flat_exponent_of_v" in sp:
                print(f"  weights that stopped: flattened cap 2 (2 R travel)^(1/2) ~ v^b, b = {sp['flat_exponent_of_v']:.2f} "
                      f"[{sp['flat_ci95'][0]:.2f}, {sp['flat_ci95'][1]:.2f}] over {sp['stopped_points']} realisations")
            report.append({"h_m": h, "speeds": sp})
    if a.plot and ens:
        plot(ens, a.plot)
    if a.json:
        with open(a.json, "w") as f:
            json.dump(report, f, indent=1)


if __name__ == "__main__":
    main()
