#!/usr/bin/python3
"""Mesh convergence of the 3D impact's ensemble means (docs/ensembles.md, "Mesh convergence").

For each element size h of the list, one ensemble of the case at its default speed and safety
factor:

    fdem ensemble CASE -n N --out RUNS/h<h> --vary orientation,velocity --seed 1 --jobs J --threads 1 \\
        --set parameters.h=<h> --set output.snapshot_count=0 [--set ...]

(an ensemble already done in RUNS is not run again; a larger N adds realisations). Then, for each
result a user reads, the mean and its 95 % interval at each size, the change of the mean between
neighbouring sizes against the intervals (a change inside the sum of the two half-widths is not
resolved by the ensembles), and, where both changes of the three finest sizes are resolved and
of one sign, the observed order p of m(h) = m0 + C h^p through them (observed_order; p < 0: the
mean grows with refinement).

    perf/mesh_convergence.py --sizes 0.006,0.0045,0.003 -n 16 --runs /work/runs/conv \\
        --out perf/results/mesh_convergence_3d.json --plot docs/img/mesh_convergence_3d.png \\
        [--use 0.003=/work/runs/ens_ts/particle_impact_3d_s0.3]

--use H=DIR takes the ensemble of size H from DIR (the same realisations, made by another study:
the time-step study's ensemble at the case's factor is the default size's). --report-only reads what
is there without running anything.
"""
import argparse
import json
import math
import os
import subprocess
import sys
import time

QUANTITIES = [  # (key in ensemble.json results, label, scale for the table)
    ("fragments.largest_fraction", "largest fragment", 1.0),
    ("fragments.count_at_least_1pct", "fragments >= 1 %", 1.0),
    ("fragments.count", "fragments", 1.0),
    ("energy.fracture_J", "fracture energy [J]", 1.0),
    ("energy.friction_J", "friction [J]", 1.0),
    ("interfaces_failed", "failed interfaces", 1.0),
    ("results.peak_load_N", "peak plate load [kN]", 1e-3),
]


def run_ensemble(a, h, out):
    cmd = [a.fdem, "ensemble", a.case, "-n", str(a.n), "--out", out, "--vary", "orientation,velocity",
           "--seed", "1", "--jobs", str(a.jobs), "--threads", "1", "--set", f"parameters.h={h:g}",
           "--set", "output.snapshot_count=0"]
    for s in a.set:
        cmd += ["--set", s]
    if not a.report_only:
        t0 = time.time()
        rc = subprocess.call(cmd, stdout=sys.stderr if a.verbose else subprocess.DEVNULL)
        print(f"h = {h:g}: exit {rc}, {time.time() - t0:.0f} s", file=sys.stderr)
    return cmd


def fmt(v):
    return f"{v:.3g}"


def observed_order(sizes, means, resolved):
    """The observed order p of the three finest sizes: the means m(h) = m0 + C h^p through the three
    points, (m1 - m2) / (m2 - m3) = (h1^p - h2^p) / (h2^p - h3^p), solved for p by bisection (the
    right side grows with p; its limit at p = 0 is ln(h1 / h2) / ln(h2 / h3)). Only where both
    changes are resolved by the ensembles and of one sign; None otherwise. p < 0: the mean grows
    with refinement (no limit at this rate)."""
    if len(sizes) < 3 or not all(resolved[-2:]):
        return None
    (h1, h2, h3), (m1, m2, m3) = sizes[-3:], means[-3:]
    d12, d23 = m2 - m1, m3 - m2
    if d12 == 0 or d23 == 0 or (d12 > 0) != (d23 > 0):
        return None
    target = d12 / d23

    def f(q):
        if abs(q) < 1e-9:
            return math.log(h1 / h2) / math.log(h2 / h3)
        return (h1 ** q - h2 ** q) / (h2 ** q - h3 ** q)

    lo, hi = -20.0, 20.0
    if not f(lo) < target < f(hi):
        return None
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if f(mid) < target else (lo, mid)
    return 0.5 * (lo + hi)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--fdem", default=os.path.join(os.path.dirname(__file__), "..", "build", "openmp", "fdem"))
    p.add_argument("--case", default="cases/particle_impact_3d/case.json")
    p.add_argument("--sizes", default="0.006,0.0045,0.003")
    p.add_argument("-n", type=int, default=16)
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--runs", required=True)
    p.add_argument("--use", action="append", default=[], help="H=DIR: the ensemble of size H is in DIR")
    p.add_argument("--set", action="append", default=[])
    p.add_argument("--out")
    p.add_argument("--plot")
    p.add_argument("--report-only", action="store_true")
    p.add_argument("--verbose", action="store_true")
    a = p.parse_args()
    sizes = sorted((float(x) for x in a.sizes.split(",")), reverse=True)
    use = {float(u.split("=", 1)[0]): u.split("=", 1)[1] for u in a.use}
    rows = []
    for h in sizes:
        out = use.get(h) or os.path.join(a.runs, f"h{h:g}")
        cmd = None if h in use else run_ensemble(a, h, out)
        rep = json.load(open(os.path.join(out, "ensemble.json")))
        rows.append({"h": h, "folder": out, "command": " ".join(cmd) if cmd else None, "done": rep["done"],
                     "failed": rep["failed"], "results": rep["results"]})
    report = {"case": a.case, "sizes": sizes, "n": a.n, "sets": a.set, "rows": rows, "changes": {}}
    head = ["h [mm]", "n", "tetrahedra"] + [q[1] for q in QUANTITIES]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for r in rows:
        cells = [f"{1e3 * r['h']:g}", str(r["done"]), f"{r['results']['counts.elements']['mean']:.0f}"]
        for key, _, scale in QUANTITIES:
            s = r["results"].get(key)
            cells.append(f"{fmt(s['mean'] * scale)} [{fmt(s['ci95'][0] * scale)}, {fmt(s['ci95'][1] * scale)}]"
                         if s else "-")
        print("| " + " | ".join(cells) + " |")
    print()
    print("| result | " + " | ".join(f"{1e3 * x['h']:g} -> {1e3 * y['h']:g} mm" for x, y in zip(rows, rows[1:]))
          + " | observed order |")
    print("|" + "---|" * (len(rows) + 1))
    for key, label, scale in QUANTITIES:
        if not all(key in r["results"] for r in rows):
            continue
        cells, changes = [], []
        for x, y in zip(rows, rows[1:]):
            sx, sy = x["results"][key], y["results"][key]
            d = sy["mean"] - sx["mean"]
            half = (sx["ci95"][1] - sx["ci95"][0]) / 2 + (sy["ci95"][1] - sy["ci95"][0]) / 2
            changes.append({"change": d, "resolved": abs(d) > half, "half_widths": half})
            cells.append(f"{d * scale:+.3g} ({'resolved' if abs(d) > half else 'within'} +-{half * scale:.2g})")
        order = observed_order([r["h"] for r in rows], [r["results"][key]["mean"] for r in rows],
                               [c["resolved"] for c in changes])
        report["changes"][key] = {"steps": changes, "observed_order": order}
        print(f"| {label} | " + " | ".join(cells) + f" | {'-' if order is None else f'{order:.2g}'} |")
    if a.out:
        with open(a.out, "w") as f:
            json.dump(report, f, indent=1)
    if a.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, axes = plt.subplots(2, 4, figsize=(15, 6.5))
        hs = [1e3 * r["h"] for r in rows]
        for ax, (key, label, scale) in zip(axes.flat, QUANTITIES):
            m = [r["results"][key]["mean"] * scale for r in rows]
            lo = [m[i] - r["results"][key]["ci95"][0] * scale for i, r in enumerate(rows)]
            hi = [r["results"][key]["ci95"][1] * scale - m[i] for i, r in enumerate(rows)]
            ax.errorbar(hs, m, yerr=[lo, hi], fmt="o-", capsize=4)
            ax.set_xlabel("element size h [mm]")
            ax.set_title(label)
            ax.invert_xaxis()
            ax.grid(alpha=0.3)
        axes.flat[-1].axis("off")
        fig.suptitle(f"{os.path.basename(os.path.dirname(os.path.abspath(a.case)))}: ensemble means and 95 % "
                     f"intervals against the element size ({rows[0]['done']} realisations at {hs[0]:g} mm)")
        fig.tight_layout()
        fig.savefig(a.plot, dpi=90)
    return 0


if __name__ == "__main__":
    sys.exit(main())
