#!/usr/bin/python3
"""The impacts' time step chosen from ensembles (docs/ensembles.md, "The impacts' safety factor").

For each safety factor S of the list, one ensemble of the case:

    fdem ensemble CASE -n N --out RUNS/<case>_s<S> --vary orientation,velocity --jobs J --threads 1 \\
        --set time.safety_factor=S --set output.snapshot_count=0 [--set ...]

(the same seed at every factor: realisation i has the same mesh orientation and speed factor at
every S, so that only the step differs). Then, for the quantities a user of an impact reads
(largest fragment, number of fragments of at least 1 % of the mass, fracture energy), each
factor's ensemble mean against the 95 % interval of the smallest factor's ensemble. The energy
balance error is no scattering quantity: it is the integrator's error, which grows with the step
(about as S^3 here) and has almost no spread at S = 0.1 to compare with, so it gets a tolerance
instead: the worst relative balance error (summary.json energy.max_relative_balance_error, relative
to the energy in play, here the impact's kinetic energy) of every realisation at most 1 %. The chosen
factor is the largest one up to which every factor passes; a factor with a failed realisation
(numerical failure) is unstable. The table also says where the balance error's mean leaves the
reference interval (the rule taken literally).

    perf/ensemble_timestep.py --case cases/particle_impact_2d/case.json --factors 0.1,0.2,0.3,0.45,0.6,0.8 \\
        -n 16 --runs /work/runs/ens_ts --out perf/results/ensemble_timestep_2d.json [--jobs 2] [--set K=V]

Writes OUT (the statistics per factor, the command of each ensemble, the verdict) and prints a
Markdown table; --plot FILE draws each quantity's mean and interval against S. An ensemble already
done in RUNS is not run again (fdem ensemble goes on where it stopped).
"""
import argparse
import json
import os
import subprocess
import sys
import time

BALANCE_TOLERANCE = 0.01  # the worst relative energy balance error of any realisation
QUANTITIES = [  # (key in ensemble.json results, label, scale for the table)
    ("fragments.largest_fraction", "largest fragment", 1.0),
    ("fragments.count_at_least_1pct", "fragments >= 1 %", 1.0),
    ("energy.fracture_J", "fracture energy [J]", 1.0),
    ("energy.max_relative_balance_error", "worst balance error", 100.0),
]


def ensemble_dir(a, factor):
    """RUNS/<case folder's name>_s<S>: the ensemble of one factor."""
    return os.path.join(a.runs, f"{os.path.basename(os.path.dirname(os.path.abspath(a.case)))}_s{factor:g}")


def run_ensemble(a, factor):
    out = ensemble_dir(a, factor)
    cmd = [a.fdem, "ensemble", a.case, "-n", str(a.n), "--out", out, "--vary", a.vary, "--seed", str(a.seed),
           "--jobs", str(a.jobs), "--threads", "1", "--set", f"time.safety_factor={factor:g}",
           "--set", "output.snapshot_count=0"]
    for s in a.set:
        cmd += ["--set", s]
    t0 = time.time()
    rc = subprocess.call(cmd, stdout=sys.stderr if a.verbose else subprocess.DEVNULL)
    wall = time.time() - t0
    report = json.load(open(os.path.join(out, "ensemble.json")))
    return {"factor": factor, "command": " ".join(cmd), "exit_status": rc, "wall_seconds_this_call": wall,
            "done": report["done"], "failed": report["failed"], "results": report["results"],
            "distribution": report.get("fragment_mass_distribution")}


def within(mean, ci):
    return ci[0] <= mean <= ci[1]


def verdict(rows):
    ref = rows[0]
    chosen, reasons = ref["factor"], {}
    broken = False
    for r in rows[1:]:
        why = []
        if r["failed"] > 0 or r["done"] == 0:
            why.append(f"{r['failed']} of {r['done'] + r['failed']} realisations failed numerically")
        else:
            for key, label, _ in QUANTITIES[:3]:
                if key not in r["results"] or key not in ref["results"]:
                    continue
                m, ci = r["results"][key]["mean"], ref["results"][key]["ci95"]
                if not within(m, ci):
                    why.append(f"{label}: mean {m:.4g} outside [{ci[0]:.4g}, {ci[1]:.4g}]")
            b = r["results"]["energy.max_relative_balance_error"]["max"]
            if b > BALANCE_TOLERANCE:
                why.append(f"worst balance error {100 * b:.2g} % > {100 * BALANCE_TOLERANCE:g} % in a realisation")
        reasons[f"{r['factor']:g}"] = why
        if not why and not broken:
            chosen = r["factor"]
        broken = broken or bool(why)
    return chosen, reasons


def table(rows, reasons):
    head = "| S | done | failed | steps | " + " | ".join(q[1] + " (mean, 95 % interval)" for q in QUANTITIES)
    head += " | largest worst balance error | wall per realisation [s] | fails |"
    lines = [head, "|" + "---|" * (len(QUANTITIES) + 7)]
    for r in rows:
        cells = [f"{r['factor']:g}", str(r["done"]), str(r["failed"])]
        st = r["results"].get("steps")
        cells.append(f"{st['mean']:.0f}" if st else "")
        for key, _, scale in QUANTITIES:
            s = r["results"].get(key)
            if not s:
                cells.append("")
                continue
            pct = " %" if scale == 100.0 else ""
            cells.append(f"{s['mean'] * scale:.4g}{pct} [{s['ci95'][0] * scale:.4g}, {s['ci95'][1] * scale:.4g}]")
        cells.append(f"{100 * r['results']['energy.max_relative_balance_error']['max']:.2g} %" if r["done"] else "")
        cells.append(f"{r.get('wall_per_realisation', float('nan')):.1f}")
        why = reasons.get(f"{r['factor']:g}")
        cells.append("(reference)" if why is None else ("; ".join(why) if why else "none"))
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def wall_per_realisation(row, a):
    out = ensemble_dir(a, row["factor"])
    walls = []
    for i in range(a.n):
        p = os.path.join(out, f"r{i:04d}", "realisation.json")
        if os.path.exists(p):
            walls.append(json.load(open(p)).get("wall_seconds", 0))
    walls.sort()
    return walls[len(walls) // 2] if walls else float("nan")


def plot(rows, path, title):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, len(QUANTITIES), figsize=(4 * len(QUANTITIES), 3.4))
    for ax, (key, label, scale) in zip(axes, QUANTITIES):
        xs, ms, lo, hi = [], [], [], []
        for r in rows:
            s = r["results"].get(key)
            if s and r["done"] > 0:
                xs.append(r["factor"])
                ms.append(s["mean"] * scale)
                lo.append((s["mean"] - s["ci95"][0]) * scale)
                hi.append((s["ci95"][1] - s["mean"]) * scale)
        ax.errorbar(xs, ms, yerr=[lo, hi], fmt="o-", capsize=3)
        ref = rows[0]["results"].get(key)
        if ref and scale != 100.0:
            ax.axhspan(ref["ci95"][0] * scale, ref["ci95"][1] * scale, color="tab:green", alpha=0.2,
                       label=f"S = {rows[0]['factor']:g}: 95 % interval")
        if scale == 100.0:  # (the balance error grows by orders of magnitude)
            ax.set_yscale("log")
        ax.set_xlabel("safety factor S")
        ax.set_title(label + (" [%]" if scale == 100.0 else ""), fontsize=10)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=7)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--case", required=True)
    p.add_argument("--factors", required=True, help="comma separated; the first is the reference")
    p.add_argument("-n", type=int, default=16)
    p.add_argument("--runs", required=True, help="folder for the ensembles' run folders")
    p.add_argument("--out", required=True, help="the JSON written")
    p.add_argument("--fdem", default="build/openmp/fdem")
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--vary", default="orientation,velocity")
    p.add_argument("--set", action="append", default=[])
    p.add_argument("--plot")
    p.add_argument("--verbose", action="store_true")
    p.add_argument("--report-only", action="store_true", help="the table and plot from OUT as written before")
    a = p.parse_args()
    factors = [float(x) for x in a.factors.split(",") if x.strip()]
    if a.report_only:
        old = json.load(open(a.out))
        report(old["rows"], factors, a, {k: old[k] for k in ("commit", "date", "load_average") if k in old})
        return
    os.makedirs(a.runs, exist_ok=True)
    rows = []
    for f in factors:
        r = run_ensemble(a, f)
        r["wall_per_realisation"] = wall_per_realisation(r, a)
        rows.append(r)
        print(f"S = {f:g}: {r['done']} done, {r['failed']} failed, {r['wall_seconds_this_call']:.0f} s", file=sys.stderr)
    report(rows, factors, a)


def report(rows, factors, a, meta=None):
    """Writes OUT and prints the table; `meta` (commit, date, load) of the runs when remade from OUT."""
    chosen, reasons = verdict(rows)
    git = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    doc = {"case": a.case, "n": a.n, "vary": a.vary, "seed": a.seed, "sets": a.set, "commit": git,
           "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), "load_average": os.getloadavg()}
    doc.update(meta or {})
    doc.update({"rows": rows, "chosen_factor": chosen, "outside": reasons})
    os.makedirs(os.path.dirname(os.path.abspath(a.out)), exist_ok=True)
    json.dump(doc, open(a.out, "w"), indent=1)
    print(table(rows, reasons))
    print(f"\nchosen: {chosen:g} (the largest factor up to which every factor passes)")
    ref = rows[0]["results"]["energy.max_relative_balance_error"]["ci95"]
    lit = [r["factor"] for r in rows[1:] if not within(r["results"]["energy.max_relative_balance_error"]["mean"], ref)]
    print(f"the worst relative balance error's mean outside the S = {factors[0]:g} interval (the literal rule) at S = "
          + (", ".join(f"{x:g}" for x in lit) or "none"))
    if a.plot:
        plot(rows, a.plot, f"{a.case}: ensembles of {a.n} ({a.vary})")


if __name__ == "__main__":
    main()
