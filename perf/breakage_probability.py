#!/usr/bin/python3
"""Breakage probability of the 3D impact against the mass-specific impact energy, from ensembles
(docs/ensembles.md, "Breakage probability").

At each speed v of the list, one ensemble of cases/particle_impact_3d with a strength scatter:

    fdem ensemble cases/particle_impact_3d/case.json -n N --out RUNS/breakage_v<v> --vary strength
        --jobs J --threads 1 --set parameters.speed=v --set 'fracture.scatter=SCATTER'
        --set output.snapshot_count=0 [--set ...]

A realisation is broken when its largest fragment holds less than --broken-below of the mass.
P(broken) against W = v^2 / 2 (J/kg, the kinetic energy per unit mass) is fitted to Vogel and
Peukert's form for one impact (k = 1),

    P = 1 - exp(-fmat (W - Wmin))   for W > Wmin, else 0,

by maximum likelihood over the realisations' outcomes (binomial at each speed); the 95 %
intervals of fmat and Wmin are the percentiles of a bootstrap over the realisations (resampled
within each speed, 500 times). Writes OUT (counts per speed, the fit, its intervals, each
ensemble's command) and, with --plot, the points with their Wilson 95 % intervals and the fitted
curve.

    perf/breakage_probability.py --speeds 5,10,15,20,30,40 -n 12 --runs /work/runs/breakage \\
        --out perf/results/breakage_probability.json --plot docs/img/breakage_probability.png \\
        [--set parameters.h=0.006] [--broken-below 0.8] [--jobs 2]
"""
import argparse
import json
import math
import os
import random
import subprocess
import sys
import time

DEFAULT_SCATTER = '{"distribution": "weibull", "modulus": 5}'


def run_speed(a, v):
    out = os.path.join(a.runs, f"breakage_v{v:g}")
    cmd = [a.fdem, "ensemble", a.case, "-n", str(a.n), "--out", out, "--vary", a.vary, "--seed", str(a.seed),
           "--jobs", str(a.jobs), "--threads", "1", "--set", f"parameters.speed={v:g}",
           "--set", "output.snapshot_count=0"]
    if a.scatter != "case":
        cmd += ["--set", "fracture.scatter=" + a.scatter]
    for s in a.set:
        cmd += ["--set", s]
    t0 = time.time()
    rc = subprocess.call(cmd, stdout=subprocess.DEVNULL)
    if rc not in (0, 3):
        sys.exit(f"breakage_probability: {' '.join(cmd)} ended with exit status {rc}")
    largest, masses = [], []
    for i in range(a.n):
        rec = os.path.join(out, f"r{i:04d}", "realisation.json")
        if os.path.exists(rec) and json.load(open(rec))["status"] == "done":
            s = json.load(open(os.path.join(out, f"r{i:04d}", "summary.json")))
            largest.append(s["fragments"]["largest_fraction"])
            masses.append(s["fragments"]["total_mass_kg"])
    rep = json.load(open(os.path.join(out, "ensemble.json")))
    # W: the kinetic energy per unit mass of the particle: its own speed's, or a striker's of the given
    # mass over the particle's mass (a drop weight's test)
    W = 0.5 * v * v if not a.striker_mass else 0.5 * a.striker_mass * v * v / (sum(masses) / max(1, len(masses)))
    return {"speed": v, "W_J_per_kg": W, "command": " ".join(cmd), "wall_seconds": time.time() - t0,
            "largest_fractions": largest, "broken": sum(1 for x in largest if x < a.broken_below),
            "n": len(largest), "failed": rep["failed"],
            "largest_fraction": rep["results"].get("fragments.largest_fraction"),
            "count_at_least_1pct": rep["results"].get("fragments.count_at_least_1pct"),
            "fracture_J": rep["results"].get("energy.fracture_J")}


def probability(W, f, wmin):
    return 1 - math.exp(-f * (W - wmin)) if W > wmin else 0.0


def log_likelihood(points, f, wmin):
    ll = 0.0
    for W, k, n in points:
        p = min(max(probability(W, f, wmin), 1e-12), 1 - 1e-12)
        ll += k * math.log(p) + (n - k) * math.log(1 - p)
    return ll


def fit(points):
    """Maximum likelihood (f, Wmin): Wmin on a grid below the lowest energy with a broken
    realisation, f by golden-section search in log f for each, then refined on a finer grid."""
    Ws = sorted(W for W, _, _ in points)
    broken_W = [W for W, k, _ in points if k > 0]
    if not broken_W:
        return None
    hi = min(broken_W)
    # f is searched up to 1e4 / (the largest energy): P would rise from 0 to 1 within 1e-4 of the
    # energies' scale there; an f at that bound means the outcomes are separated
    f_top = 1e4 / Ws[-1]

    def best_f(wmin):
        lo_l, hi_l = math.log(1e-7), math.log(f_top)
        g = (math.sqrt(5) - 1) / 2
        for _ in range(50):
            a = hi_l - g * (hi_l - lo_l)
            b = lo_l + g * (hi_l - lo_l)
            if log_likelihood(points, math.exp(a), wmin) < log_likelihood(points, math.exp(b), wmin):
                lo_l = a
            else:
                hi_l = b
        f = math.exp(0.5 * (lo_l + hi_l))
        return f, log_likelihood(points, f, wmin)

    best = None
    for j in range(101):
        wmin = hi * j / 100 * (1 - 1e-9)
        f, ll = best_f(wmin)
        if best is None or ll > best[2]:
            best = (f, wmin, ll)
    # At the search's upper end the outcomes are separated (every realisation below some energy
    # whole, every one above broken): the data bound fmat from below only.
    return {"fmat_kg_per_J": best[0], "Wmin_J_per_kg": best[1], "log_likelihood": best[2], "W_range": [Ws[0], Ws[-1]],
            "fmat_at_search_bound": best[0] > 0.99 * f_top}


def bootstrap(rows, reps, seed):
    rng = random.Random(seed)
    fs, ws = [], []
    for _ in range(reps):
        pts = []
        for r in rows:
            xs = [rng.choice(r["outcomes"]) for _ in r["outcomes"]] if r["outcomes"] else []
            pts.append((r["W_J_per_kg"], sum(xs), len(xs)))
        b = fit(pts)
        if b:
            fs.append(b["fmat_kg_per_J"])
            ws.append(b["Wmin_J_per_kg"])
    fs.sort()
    ws.sort()
    pick = lambda xs, q: xs[min(len(xs) - 1, int(q * len(xs)))] if xs else None
    return {"fmat_kg_per_J_ci95": [pick(fs, 0.025), pick(fs, 0.975)],
            "Wmin_J_per_kg_ci95": [pick(ws, 0.025), pick(ws, 0.975)], "replicates": len(fs)}


def wilson(k, n):
    if n == 0:
        return (0, 1)
    z = 1.959963985
    p = k / n
    c = (p + z * z / (2 * n)) / (1 + z * z / n)
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return (max(0.0, c - h), min(1.0, c + h))


def plot(rows, f, path, title, xlabel):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 4))
    for r in rows:
        p = r["broken"] / r["n"] if r["n"] else 0
        lo, hi = wilson(r["broken"], r["n"])
        ax.errorbar([r["W_J_per_kg"]], [p], yerr=[[p - lo], [hi - p]], fmt="ko", capsize=3)
    if f:
        Wmax = max(r["W_J_per_kg"] for r in rows) * 1.05
        xs = [Wmax * i / 300 for i in range(301)]
        ax.plot(xs, [probability(x, f["fmat_kg_per_J"], f["Wmin_J_per_kg"]) for x in xs], "b-",
                label=f"1 - exp(-{f['fmat_kg_per_J']:.3g} (W - {f['Wmin_J_per_kg']:.3g}))")
        ax.legend(fontsize=8)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("P(broken)")
    ax.set_ylim(-0.03, 1.03)
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--case", default="cases/particle_impact_3d/case.json")
    p.add_argument("--speeds", required=True)
    p.add_argument("-n", type=int, default=12)
    p.add_argument("--runs", required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--fdem", default="build/openmp/fdem")
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--scatter", default=DEFAULT_SCATTER, help="fracture.scatter for every run, or 'case': the case's own")
    p.add_argument("--vary", default="strength", help="fdem ensemble --vary (default: strength)")
    p.add_argument("--striker-mass", type=float, default=0.0,
                   help="the speed is a striker's of this mass (kg; a drop weight): W = M v^2 / (2 m), m the "
                        "particle's mass (summary.json fragments.total_mass_kg); default: the particle's own speed, W = v^2 / 2")
    p.add_argument("--broken-below", type=float, default=0.8)
    p.add_argument("--set", action="append", default=[])
    p.add_argument("--plot")
    p.add_argument("--report-only", action="store_true", help="the fit, table and plot from OUT as written before")
    a = p.parse_args()
    meta = {}
    if a.report_only:
        old = json.load(open(a.out))
        rows, meta = old["rows"], {k: old[k] for k in ("commit", "date", "load_average")}
        # (as the runs were made)
        a.n, a.case, a.broken_below, a.scatter, a.set = old["n"], old["case"], old["broken_below"], old["scatter"], old["sets"]
        a.striker_mass = old.get("striker_mass_kg", a.striker_mass)
        a.vary = old.get("vary", "strength")
    else:
        os.makedirs(a.runs, exist_ok=True)
        rows = []
        for v in [float(x) for x in a.speeds.split(",") if x.strip()]:
            r = run_speed(a, v)
            r["outcomes"] = [1 if x < a.broken_below else 0 for x in r["largest_fractions"]]
            rows.append(r)
            print(f"v = {v:g} m/s: {r['broken']} of {r['n']} broken ({r['wall_seconds']:.0f} s)", file=sys.stderr)
    points = [(r["W_J_per_kg"], r["broken"], r["n"]) for r in rows]
    f = fit(points)
    boot = bootstrap(rows, 500, a.seed) if f else None
    git = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    doc = {"case": a.case, "n": a.n, "scatter": a.scatter, "vary": a.vary, "striker_mass_kg": a.striker_mass,
           "sets": a.set, "broken_below": a.broken_below,
           "commit": git, "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
           "load_average": os.getloadavg(), "rows": rows, "fit": f, "bootstrap": boot}
    doc.update(meta)
    json.dump(doc, open(a.out, "w"), indent=1)
    print("| v [m/s] | W [J/kg] | broken / n | P (Wilson 95 %) | largest fragment (mean, 95 % interval) | fragments >= 1 % | fracture energy [J] |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        lo, hi = wilson(r["broken"], r["n"])
        lf, c1, fr = r["largest_fraction"], r["count_at_least_1pct"], r["fracture_J"]
        fmt = lambda s, d=3: f"{s['mean']:.{d}g} [{s['ci95'][0]:.{d}g}, {s['ci95'][1]:.{d}g}]" if s else ""
        print(f"| {r['speed']:g} | {r['W_J_per_kg']:.4g} | {r['broken']} / {r['n']} | "
              f"{r['broken'] / max(1, r['n']):.2f} [{lo:.2f}, {hi:.2f}] | {fmt(lf)} | {fmt(c1)} | {fmt(fr)} |")
    if f and f["fmat_at_search_bound"]:
        print("\nfit: the outcomes are separated (no speed with some broken and some whole realisations): "
              "fmat is not bounded above by these speeds; add speeds inside the transition")
    if f:
        print(f"\nfit: fmat = {f['fmat_kg_per_J']:.4g} kg/J {boot['fmat_kg_per_J_ci95']}, "
              f"Wmin = {f['Wmin_J_per_kg']:.4g} J/kg {boot['Wmin_J_per_kg_ci95']} (bootstrap 95 %)")
    if a.plot:
        xlabel = ("mass-specific impact energy W = M v^2 / (2 m) [J/kg]" if a.striker_mass
                  else "mass-specific impact energy W = v^2 / 2 [J/kg]")
        plot(rows, f, a.plot, f"{a.case}, {a.n} realisations per speed, broken: largest < {a.broken_below:g}",
             xlabel)


if __name__ == "__main__":
    main()
