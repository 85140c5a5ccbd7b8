#!/usr/bin/python3
"""Pictures of an ensemble (fdem ensemble, docs/ensembles.md):

    scripts/plot_ensemble.py DIR [--keys k1,k2,...] [--out PREFIX]

writes, from DIR/ensemble.csv and DIR/ensemble.json:
  PREFIX_histograms.png   a histogram of each result over the realisations, with its mean and
                          95 % interval of the mean;
  PREFIX_distribution.png the mean cumulative fragment mass curve (share of the mass in fragments
                          of at least x of it) with its 95 % band and the realisations' curves;
  PREFIX_convergence.png  each mean against the number of realisations taken (in index order),
                          with its 95 % interval: how far the mean still moves with N.
PREFIX defaults to DIR/ensemble. --keys picks the results (default: the largest fragment, the
fragments of at least 1 % of the mass, the fragment count, the fracture and kinetic energies,
the failed interfaces and the worst energy balance error; those the table has).
"""
import argparse
import csv
import json
import math
import os
import sys

DEFAULT_KEYS = ["fragments.largest_fraction", "fragments.count_at_least_1pct", "fragments.count",
                "energy.fracture_J", "energy.kinetic_J", "interfaces_failed", "energy.max_relative_balance_error",
                "results.peak_load_N"]


def t975(nu):
    """Student's t quantile t(0.975, nu)."""
    return t_quantile(0.975, nu)


def t_quantile(p, nu):
    """Student's t quantile t(p, nu), p > 0.5 (bisection on the CDF by the incomplete beta
    function's continued fraction; the same values as fdem's; tests/mpi/check_runs.py uses it)."""
    def betacf(a, b, x):
        c, d = 1.0, 1 - (a + b) * x / (a + 1)
        d = 1 / (d if abs(d) > 1e-300 else 1e-300)
        h = d
        for m in range(1, 1000):
            m2 = 2 * m
            for num in (m * (b - m) * x / ((a + m2 - 1) * (a + m2)), -(a + m) * (a + b + m) * x / ((a + m2) * (a + m2 + 1))):
                d = 1 + num * d
                d = 1 / (d if abs(d) > 1e-300 else 1e-300)
                c = 1 + num / c
                c = c if abs(c) > 1e-300 else 1e-300
                h *= d * c
            if abs(d * c - 1) < 1e-15:
                break
        return h

    def ibeta(a, b, x):
        if x <= 0:
            return 0.0
        if x >= 1:
            return 1.0
        front = math.exp(math.lgamma(a + b) - math.lgamma(a) - math.lgamma(b) + a * math.log(x) + b * math.log1p(-x))
        if x < (a + 1) / (a + b + 2):
            return front * betacf(a, b, x) / a
        return 1 - front * betacf(b, a, 1 - x) / b

    def cdf(t):
        tail = 0.5 * ibeta(nu / 2, 0.5, nu / (nu + t * t))
        return 1 - tail if t >= 0 else tail

    lo, hi = 0.0, 1.0
    while cdf(hi) < p:
        hi *= 2
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if cdf(mid) < p else (lo, mid)
    return 0.5 * (lo + hi)


def read_table(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return [r for r in rows if r["status"] == "done"]


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("dir")
    p.add_argument("--keys")
    p.add_argument("--out")
    a = p.parse_args()
    csv_path, json_path = os.path.join(a.dir, "ensemble.csv"), os.path.join(a.dir, "ensemble.json")
    for f in (csv_path, json_path):
        if not os.path.exists(f):
            sys.exit(f"plot_ensemble: {f} does not exist (run fdem ensemble ... --out {a.dir} first)")
    rows, rep = read_table(csv_path), json.load(open(json_path))
    if not rows:
        sys.exit(f"plot_ensemble: {csv_path} has no realisation that is done")
    keys = a.keys.split(",") if a.keys else [k for k in DEFAULT_KEYS if k in rows[0] and rows[0][k] != ""]
    for k in keys:
        if k not in rows[0]:
            sys.exit(f"plot_ensemble: no column '{k}' in {csv_path} (columns: {', '.join(rows[0].keys())})")
    prefix = a.out or os.path.join(a.dir, "ensemble")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cols = min(4, len(keys))
    nrow = (len(keys) + cols - 1) // cols
    fig, axes = plt.subplots(nrow, cols, figsize=(3.6 * cols, 2.9 * nrow), squeeze=False)
    for ax, k in zip(axes.flat, keys):
        x = [float(r[k]) for r in rows]
        s = rep["results"][k]
        ax.hist(x, bins=max(5, min(30, len(x) // 2)), color="tab:blue", alpha=0.7)
        ax.axvline(s["mean"], color="k", label="mean")
        ax.axvspan(s["ci95"][0], s["ci95"][1], color="tab:orange", alpha=0.3, label="95 % interval of the mean")
        ax.set_title(k, fontsize=9)
    for ax in list(axes.flat)[len(keys):]:
        ax.axis("off")
    axes.flat[0].legend(fontsize=7)
    fig.suptitle(f"{a.dir}: {len(rows)} realisations", fontsize=10)
    fig.tight_layout()
    fig.savefig(prefix + "_histograms.png", dpi=110)

    d = rep.get("fragment_mass_distribution")
    if d:
        fig, ax = plt.subplots(figsize=(5.5, 4))
        x = d["fragment_fraction_at_least"]
        for i in range(len(rows)):
            summ = os.path.join(a.dir, f"r{int(rows[i]['realisation']):04d}", "summary.json")
            if os.path.exists(summ):
                c = json.load(open(summ))["fragments"]["cumulative_mass"]["mass_fraction"]
                ax.plot(x, c, color="0.75", lw=0.7)
        ax.fill_between(x, d["ci95_low"], d["ci95_high"], color="tab:orange", alpha=0.4,
                        label="95 % interval of the mean")
        ax.plot(x, d["mean_mass_fraction"], "k.-", ms=4, label=f"mean of {d['realisations']}")
        ax.set_xscale("log")
        ax.set_xlabel("fragment mass / total mass, at least")
        ax.set_ylabel("share of the mass")
        ax.set_ylim(0, 1.02)
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(prefix + "_distribution.png", dpi=110)

    fig, axes = plt.subplots(nrow, cols, figsize=(3.6 * cols, 2.9 * nrow), squeeze=False)
    for ax, k in zip(axes.flat, keys):
        x = [float(r[k]) for r in rows]
        ns, ms, lo, hi = [], [], [], []
        for n in range(2, len(x) + 1):
            m = sum(x[:n]) / n
            sd = math.sqrt(sum((v - m) ** 2 for v in x[:n]) / (n - 1))
            h = t975(n - 1) * sd / math.sqrt(n)
            ns.append(n)
            ms.append(m)
            lo.append(m - h)
            hi.append(m + h)
        ax.fill_between(ns, lo, hi, color="tab:orange", alpha=0.3)
        ax.plot(ns, ms, "k.-", ms=3)
        ax.set_xlabel("realisations N")
        ax.set_title(k, fontsize=9)
    for ax in list(axes.flat)[len(keys):]:
        ax.axis("off")
    fig.suptitle("the mean against N, with its 95 % interval", fontsize=10)
    fig.tight_layout()
    fig.savefig(prefix + "_convergence.png", dpi=110)
    print("wrote " + ", ".join(prefix + s for s in ("_histograms.png", "_distribution.png", "_convergence.png")))


if __name__ == "__main__":
    main()
