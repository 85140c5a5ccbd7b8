#!/usr/bin/python3
"""Time step study of the particle impacts (issue 19, target 3): run time against error over the
safety factor and the element size. Runs

    fdem run cases/particle_impact_{2d,3d}/case.json --set time.safety_factor=S \\
        --set parameters.h=H --set output.snapshot_count=0 --quiet

for every (S, H) of the grid and collects summary.json. The element size is set through
`parameters.h` (not `mesh.element_size`): the cases derive the interface stiffness from it
(k_n = E / (0.1 h)), so a finer mesh keeps the case's alpha = 0.1.

    perf/timestep_study.py --out perf/results [--fdem build/openmp/fdem] [--jobs 2] \\
        [--grid2d "0.1,0.2,0.3:0.005,0.0025"] [--grid3d "0.1,0.2:0.006"] [--reference2d S:H] [--timeout 3600]

A grid is "FACTORS:SIZES" (comma separated; several grids joined by ";" add their runs, e.g.
"0.1,0.2:0.003;0.1:0.002" runs the finest size at 0.1 only); "" leaves the case out. Runs whose
summary.json exists from an earlier call with the same command are not repeated (--rerun repeats
them). Writes OUT/timestep.json and keeps each run's outputs in OUT/timestep_runs/<case>_s<S>_h<H>/.
Threads: OMP_NUM_THREADS of the environment (1 thread and --jobs 2 on a 2-core machine).

Error measures of a run, against the case's reference run (the finest size at its smallest
factor, or --reference2d / --reference3d):
  - energy: |balance error| at the end over the initial kinetic energy (0.5 M v^2 with the run's
    own fragment mass M), and the worst relative balance error over the run (summary.json
    energy.max_relative_balance_error);
  - fragments: the earth mover's (Wasserstein-1) distance between the mass distributions over
    log10 of the fragment mass fraction, in decades (fragment_distance below): how far, on
    average, the mass would have to move in fragment size to turn one distribution into the
    other. summary.json gives the ten largest fragments exactly and the rest in decades of mass
    fraction (spread evenly over each decade here). It weighs pieces by their mass, so it reads
    first how the mass is split among the big pieces (what a user of an impact reads first) and
    is not fooled by the count of single-element chips, which grows with every refinement; the
    count and the largest fraction are recorded as well;
  - fracture: the fracture dissipation's relative difference from the reference.
The cost of a run: its wall time and its work, element-steps (elements x steps): on a machine
shared with other jobs the wall time measures the load as much as the run.
"""
import argparse
import concurrent.futures as cf
import json
import math
import os
import subprocess
import sys
import time

CASES = {"2d": "cases/particle_impact_2d/case.json", "3d": "cases/particle_impact_3d/case.json"}
EDGES = [1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7]  # the decade bins of summary.json fragments


def parse_grid(text):
    pairs = []
    for part in [p for p in text.split(";") if p.strip()]:
        if ":" not in part:
            raise SystemExit(f"timestep_study: grid '{part}' is not FACTORS:SIZES")
        fs, hs = part.split(":", 1)
        for s in [float(x) for x in fs.split(",") if x.strip()]:
            for h in [float(x) for x in hs.split(",") if x.strip()]:
                if (s, h) not in pairs:
                    pairs.append((s, h))
    return pairs


def case_defaults(path):
    with open(path) as f:
        c = json.load(f)
    return {"safety_factor": c["time"]["safety_factor"], "h": c["parameters"]["h"],
            "speed": c["parameters"]["speed"]}


def run_one(fdem, key, case, s, h, out_root, timeout, rerun, extra):
    out = os.path.join(out_root, f"{key}_s{s:g}_h{h:g}")
    cmd = [fdem, "run", case, "--out", out, "--quiet", "--set", f"time.safety_factor={s:g}",
           "--set", f"parameters.h={h:g}", "--set", "output.snapshot_count=0"] + extra
    rec = {"case": key, "safety_factor": s, "h_m": h, "command": " ".join(cmd),
           "threads": os.environ.get("OMP_NUM_THREADS", "")}
    done = os.path.join(out, "study.json")
    if not rerun and os.path.exists(done):
        with open(done) as f:
            old = json.load(f)
        if old.get("command") == rec["command"]:
            old["reused"] = True
            return old
    t0 = time.time()
    try:
        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=timeout)
        rc, text = p.returncode, p.stdout
    except subprocess.TimeoutExpired as e:
        so = e.stdout or b""
        rc, text = 124, so.decode(errors="replace") if isinstance(so, bytes) else so
    rec["exit_status"] = rc
    rec["process_wall_seconds"] = time.time() - t0
    try:
        rec["uptime_load"] = os.getloadavg()[0]
    except OSError:
        pass
    summ = os.path.join(out, "summary.json")
    if rc == 0 and os.path.exists(summ):
        with open(summ) as f:
            sm = json.load(f)
        fr = sm.get("fragments", {})
        mass = fr.get("total_mass_kg", 0.0)
        rec.update({
            "elements": sm["counts"]["elements"], "interfaces": sm["counts"]["interfaces"],
            "steps": sm["steps"], "element_steps": sm["steps"] * sm["counts"]["elements"],
            "dt_s": sm["time_step"]["dt_s"], "dt_critical_s": sm["time_step"]["dt_critical_s"],
            "dt_bulk_s": sm["time_step"]["dt_bulk_s"], "dt_springs_s": sm["time_step"]["dt_springs_s"],
            "dt_before_contact_s": sm["time_step"].get("dt_before_contact_s"),
            "wall_seconds": sm["wall_seconds"], "loop_wall_seconds": sm["loop_wall_seconds"],
            "stop_reason": sm["stop_reason"],
            "balance_error_J": sm["energy"]["balance_error_J"],
            "max_relative_balance_error": sm["energy"]["max_relative_balance_error"],
            "fracture_J": sm["energy"]["fracture_J"], "friction_J": sm["energy"]["friction_J"],
            "interfaces_failed": sm.get("interfaces_failed"),
            "total_mass_kg": mass, "fragment_count": fr.get("count"),
            "largest_fraction": fr.get("largest_fraction"),
            "largest_fractions": fr.get("largest_fractions", []),
            "single_element_fragments": fr.get("single_element_fragments"),
            "bin_mass_fraction": fr.get("distribution", {}).get("mass_fraction", []),
        })
        rec["phases"] = {k: v.get("share") for k, v in sm.get("phases", {}).items() if isinstance(v, dict)}
    else:
        rec["failure"] = text[-1500:]
    with open(done, "w") as f:
        json.dump(rec, f, indent=1)
    return rec


def cum_curve(r):
    """G(x), the share of the mass held by fragments of mass fraction >= x, as a function. The
    summary gives the ten largest fractions exactly (G is exact above the tenth, everywhere if
    there are fewer than ten) and the rest in decades: below the tenth largest, G is interpolated
    linearly in log10(x) between the decade edges (the mass of a decade spread evenly over it)."""
    top = sorted(r.get("largest_fractions") or [], reverse=True)
    bins = r.get("bin_mass_fraction") or []
    floor = 0.0 if len(top) < 10 else top[-1]
    known = [(floor, sum(top))] if floor > 0 else []
    acc = 0.0
    for i, e in enumerate(EDGES):
        acc += bins[i] if i < len(bins) else 0.0
        if e < floor:
            known.append((e, acc))
    known.sort(reverse=True)  # decreasing x

    def g(x):
        if x >= floor:
            return sum(f for f in top if f >= x)
        for (x0, g0), (x1, g1) in zip(known, known[1:]):
            if x1 <= x <= x0:
                t = (math.log10(x0) - math.log10(x)) / (math.log10(x0) - math.log10(x1))
                return g0 + t * (g1 - g0)
        return known[-1][1] if known else 0.0
    return g


def fragment_distance(a, b, decades=7, per_decade=400):
    """The earth mover's (Wasserstein-1) distance between the mass distributions of two runs over
    log10 of the fragment mass fraction: the integral of |G_a - G_b| d(log10 x) from 1e-7 to 1. In
    decades: 0.1 means the mass would have to move by a tenth of a decade (26 %) in fragment size on
    average to turn one distribution into the other; a whole body against two halves gives 0.30
    (log10 2), the largest piece at 0.753 against 0.765 gives 0.005. Unlike a Kolmogorov-Smirnov
    distance it does not jump from 0 to the largest piece's whole mass when two nearly equal
    pieces are ordered differently."""
    ga, gb = cum_curve(a), cum_curve(b)
    n = decades * per_decade
    dl = 1.0 / per_decade
    return sum(abs(ga(10 ** (-(i + 0.5) * dl)) - gb(10 ** (-(i + 0.5) * dl))) for i in range(n)) * dl


def measures(runs, ref_choice, speed):
    ok = [r for r in runs if r.get("exit_status") == 0 and "steps" in r]
    if not ok:
        return None
    if ref_choice:
        s, h = ref_choice
        cand = [r for r in ok if abs(r["safety_factor"] - s) < 1e-12 and abs(r["h_m"] - h) < 1e-12]
        ref = cand[0] if cand else None
    else:
        hmin = min(r["h_m"] for r in ok)
        ref = min([r for r in ok if r["h_m"] == hmin], key=lambda r: r["safety_factor"])
    if ref is None:
        return None
    for r in runs:
        if r not in ok:
            continue
        ke0 = 0.5 * r["total_mass_kg"] * speed ** 2
        r["initial_kinetic_J"] = ke0
        r["energy_error"] = abs(r["balance_error_J"]) / ke0 if ke0 > 0 else None
        r["energy_error_signed"] = r["balance_error_J"] / ke0 if ke0 > 0 else None
        r["fragment_distance"] = fragment_distance(r, ref)
        r["largest_fraction_difference"] = r["largest_fraction"] - ref["largest_fraction"]
        r["fracture_difference"] = ((r["fracture_J"] - ref["fracture_J"]) / ref["fracture_J"]
                                    if ref["fracture_J"] else None)
        r["is_reference"] = r is ref
    return {"safety_factor": ref["safety_factor"], "h_m": ref["h_m"]}


def twins(runs):
    """Pairs of runs at one size whose factors differ by less than 2 % (0.2 and 0.202): the same
    discretisation, rounded differently. Their distance is the scatter of the fragmentation
    itself (the path the cracks take), the floor under which an error measure says nothing."""
    ok = [r for r in runs if r.get("exit_status") == 0 and "steps" in r]
    out = []
    for i, a in enumerate(ok):
        for b in ok[i + 1:]:
            if a["h_m"] == b["h_m"] and abs(a["safety_factor"] / b["safety_factor"] - 1) < 0.02:
                out.append({"h_m": a["h_m"], "safety_factors": [a["safety_factor"], b["safety_factor"]],
                            "fragment_distance": fragment_distance(a, b),
                            "energy_errors": [a.get("energy_error"), b.get("energy_error")],
                            "largest_fractions": [a["largest_fraction"], b["largest_fraction"]],
                            "fragment_counts": [a["fragment_count"], b["fragment_count"]],
                            "fracture_J": [a["fracture_J"], b["fracture_J"]]})
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--fdem", default="build/openmp/fdem")
    ap.add_argument("--out", required=True, help="results folder (timestep.json, timestep_runs/)")
    ap.add_argument("--grid2d", default="0.1,0.2,0.3,0.45,0.6,0.8:0.005,0.0035,0.0025;0.1,0.2,0.3:0.00175")
    ap.add_argument("--grid3d", default="0.1,0.2,0.3,0.45,0.6,0.8:0.006,0.0045;0.1,0.2,0.3:0.003")
    ap.add_argument("--reference2d", default="",
                    help="S:H of the reference run (default: finest, smallest S)")
    ap.add_argument("--reference3d", default="")
    ap.add_argument("--jobs", type=int, default=1, help="runs at once")
    ap.add_argument("--timeout", type=float, default=3600, help="seconds per run (then counted as failed)")
    ap.add_argument("--rerun", action="store_true", help="repeat runs that have results already")
    ap.add_argument("--set", action="append", default=[],
                    help="extra --set for every run (e.g. parameters.speed=20)")
    a = ap.parse_args()
    extra = [x for s in a.set for x in ("--set", s)]
    root = os.path.join(a.out, "timestep_runs")
    os.makedirs(root, exist_ok=True)
    grids = {"2d": parse_grid(a.grid2d), "3d": parse_grid(a.grid3d)}
    refs = {}
    for k, txt in (("2d", a.reference2d), ("3d", a.reference3d)):
        refs[k] = tuple(float(x) for x in txt.split(":")) if txt else None
    # the most expensive runs first, so that the parallel jobs end together
    jobs = [(k, s, h) for k in ("2d", "3d") for (s, h) in grids[k]]
    jobs.sort(key=lambda j: -(1 / j[1]) * (1 / j[2]) ** (3 if j[0] == "2d" else 4))
    records = []
    t0 = time.time()
    with cf.ThreadPoolExecutor(max_workers=max(1, a.jobs)) as ex:
        futs = {ex.submit(run_one, a.fdem, k, CASES[k], s, h, root, a.timeout, a.rerun, extra): (k, s, h)
                for (k, s, h) in jobs}
        for fu in cf.as_completed(futs):
            r = fu.result()
            records.append(r)
            msg = (f"{r['elements']} elements, {r['steps']} steps, balance {r['balance_error_J']:+.3g} J, "
                   f"{r['fragment_count']} fragments (largest {r['largest_fraction']:.3f}), "
                   f"wall {r['wall_seconds']:.0f} s" if "steps" in r
                   else f"FAILED (exit status {r['exit_status']})")
            print(f"timestep_study: {r['case']} S = {r['safety_factor']:g}, h = {1000 * r['h_m']:g} mm: {msg}"
                  f"{' (reused)' if r.get('reused') else ''}", flush=True)
    out = {"command": " ".join([os.path.relpath(sys.argv[0])] + sys.argv[1:]),
           "date_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
           "study_wall_seconds": time.time() - t0, "jobs": a.jobs,
           "threads": os.environ.get("OMP_NUM_THREADS", ""), "extra_set": a.set, "cases": {}}
    try:
        out["load_average"] = list(os.getloadavg())
    except OSError:
        pass
    try:
        out["commit"] = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                                       text=True).stdout.strip()
    except OSError:
        pass
    for k in ("2d", "3d"):
        runs = sorted([r for r in records if r["case"] == k], key=lambda r: (r["h_m"], r["safety_factor"]))
        if not runs:
            continue
        dflt = case_defaults(CASES[k])
        speed = dflt["speed"]
        for s in a.set:
            if s.startswith("parameters.speed="):
                speed = float(s.split("=", 1)[1])
        ref = measures(runs, refs[k], speed)
        out["cases"][k] = {"case": CASES[k], "default": dflt, "speed_m_per_s": speed, "reference": ref,
                           "twins": twins(runs), "runs": runs}
    path = os.path.join(a.out, "timestep.json")
    with open(path, "w") as f:
        json.dump(out, f, indent=1)
    print(f"timestep_study: wrote {path}")
    return 0 if all(r.get("exit_status") == 0 for r in records) else 1


if __name__ == "__main__":
    sys.exit(main())
