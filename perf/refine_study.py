#!/usr/bin/python3
"""Refined against directly meshed (issue 49 item 2): tables for docs/validation.md, "Refined meshes".

Brazilian disc series (perf/brazil_scatter.py, one JSON per label):

    perf/refine_study.py brazil DIR/direct.json DIR/refine1.json ...

prints per series the number of runs, elements, the strength error against f_t (mean, standard
deviation, 95 % interval of the mean) and, against the first series, the difference of the means
with Welch's t. Ensembles of the 3D impact (fdem ensemble folders):

    perf/refine_study.py ensemble DIR_DIRECT DIR_REFINED ... [--keys k1,k2]

prints each result's mean and 95 % interval per ensemble and the difference against the first.
"""
import json
import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scripts"))
from plot_ensemble import t_quantile  # noqa: E402 (Student's t, as fdem ensemble's)


def stats(xs):
    n = len(xs)
    m = sum(xs) / n
    sd = math.sqrt(sum((x - m) ** 2 for x in xs) / (n - 1)) if n > 1 else 0.0
    return n, m, sd


def welch(a, b):
    """Difference of the means b - a and Welch's t."""
    na, ma, sa = stats(a)
    nb, mb, sb = stats(b)
    se = math.sqrt(sa * sa / na + sb * sb / nb)
    return mb - ma, (mb - ma) / se if se > 0 else float("inf")


def brazil(paths):
    rows, base = [], None
    print("| series | runs | elements | strength error [%] mean | sd | 95 % interval of the mean | "
          "against the first: difference [%], Welch t |")
    print("|---|---|---|---|---|---|---|")
    for p in paths:
        with open(p) as f:
            j = json.load(f)
        runs = [r for r in j["runs"] if r.get("exit_status") == 0 and r.get("error") is not None]
        err = [100 * r["error"] for r in runs]
        els = [r["elements"] for r in runs]
        n, m, sd = stats(err)
        half = t_quantile(0.975, n - 1) * sd / math.sqrt(n)
        label = j["label"] + " (" + " ".join(j["sets"]) + ")" if j["sets"] else j["label"]
        against = ""
        if base is None:
            base = err
        else:
            d, t = welch(base, err)
            against = f"{d:+.2f}, t = {t:+.1f}"
        print(f"| {label} | {n} | {min(els)}-{max(els)} | {m:+.2f} | {sd:.2f} | "
              f"[{m - half:+.2f}, {m + half:+.2f}] | {against} |")
        rows.append((label, err))
    return rows


def ensemble(dirs, keys):
    data = []
    for d in dirs:
        with open(os.path.join(d, "ensemble.json")) as f:
            data.append(json.load(f))
    print("| result | " + " | ".join(os.path.basename(d.rstrip("/")) for d in dirs) + " | difference against the first |")
    print("|---|" + "---|" * (len(dirs) + 1))
    for k in keys:
        cells, diffs = [], []
        for j in data:
            r = j["results"].get(k) if "results" in j else j.get(k)
            if not r:
                cells.append("-")
                continue
            cells.append(f"{r['mean']:.4g} [{r['ci95'][0]:.4g}, {r['ci95'][1]:.4g}]")
        r0 = (data[0]["results"] if "results" in data[0] else data[0]).get(k)
        for j in data[1:]:
            r = (j["results"] if "results" in j else j).get(k)
            if r and r0:
                h = (r0["ci95"][1] - r0["ci95"][0]) / 2 + (r["ci95"][1] - r["ci95"][0]) / 2
                d = r["mean"] - r0["mean"]
                diffs.append(f"{d:+.3g} ({'within' if abs(d) <= h else 'beyond'} +-{h:.2g})")
        print(f"| {k} | " + " | ".join(cells) + " | " + "; ".join(diffs) + " |")


def main():
    if len(sys.argv) < 3 or sys.argv[1] not in ("brazil", "ensemble"):
        print(__doc__)
        return 2
    if sys.argv[1] == "brazil":
        brazil(sys.argv[2:])
        return 0
    args = [a for a in sys.argv[2:] if not a.startswith("--keys")]
    keys = ["fragments.largest_fraction", "fragments.count_at_least_1pct", "fragments.count",
            "energy.fracture_J", "energy.friction_J", "interfaces_failed", "results.peak_load_N"]
    for a in sys.argv[2:]:
        if a.startswith("--keys="):
            keys = a.split("=", 1)[1].split(",")
    ensemble(args, keys)
    return 0


if __name__ == "__main__":
    sys.exit(main())
