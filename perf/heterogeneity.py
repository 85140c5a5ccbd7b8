#!/usr/bin/python3
"""Strength against heterogeneity (issue 21): the Brazilian disc and the uniaxial compression test
with a Weibull scatter of the interface strength (fracture.scatter) at several moduli m and seeds.

For each case and each m (and the homogeneous material, one run) the script runs

    fdem run CASE --set 'fracture.scatter={"distribution": "weibull", "modulus": m, "seed": s}' \
        --set output.snapshot_count=0 [case sets]

and reports the strength (Brazilian: 2 P / (pi D t) from summary.json; uniaxial: peak load over
the specimen's width), its mean and standard deviation over the seeds, relative to the homogeneous
run. Writes OUT/heterogeneity.json (rewritten after every run) and prints a table.

    perf/heterogeneity.py --out DIR [--moduli 2,5,10] [--seeds 5] [--jobs 2] [--fdem build/openmp/fdem]

Threads: OMP_NUM_THREADS of the environment (1 for a study); --jobs runs that many at once.
"""
import argparse
import concurrent.futures as cf
import json
import math
import os
import subprocess
import sys
import threading

# name, case file, extra --set options, strength from summary.json
CASES = [
    ("brazilian_disc", "cases/brazilian_disc/case.json", [],
     lambda s: s["results"]["tensile_strength_Pa"]),
    # the reduced uniaxial run of perf/identity_check (d = 5 mm, 0.1 m/s): 800 elements
    ("uniaxial_compression", "cases/uniaxial_compression/case.json",
     ["parameters.cell=0.005", "parameters.rate=0.1"],
     lambda s: s["results"]["peak_load_N"] / 0.05),
]


def stats(xs):
    m = sum(xs) / len(xs)
    sd = math.sqrt(sum((x - m) ** 2 for x in xs) / (len(xs) - 1)) if len(xs) > 1 else 0.0
    return m, sd


def run(fdem, case, sets, out):
    cmd = [fdem, "run", case, "--out", out, "--quiet", "--set", "output.snapshot_count=0"]
    for s in sets:
        cmd += ["--set", s]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        return None, " ".join(cmd) + "\n" + p.stderr[-2000:]
    with open(os.path.join(out, "summary.json")) as f:
        return json.load(f), " ".join(cmd)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", required=True)
    ap.add_argument("--moduli", default="2,5,10")
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--fdem", default="build/openmp/fdem")
    a = ap.parse_args()
    moduli = [float(m) for m in a.moduli.split(",")]
    os.makedirs(a.out, exist_ok=True)
    jobs = []
    for name, case, sets, _ in CASES:
        jobs.append((name, None, None, case, sets))
        for m in moduli:
            for seed in range(1, a.seeds + 1):
                sc = json.dumps({"distribution": "weibull", "modulus": m, "seed": seed})
                jobs.append((name, m, seed, case, sets + ["fracture.scatter=" + sc]))
    records, lock = [], threading.Lock()
    path = os.path.join(a.out, "heterogeneity.json")

    def one(j):
        name, m, seed, case, sets = j
        tag = f"{name}_m{m:g}_s{seed}" if m else f"{name}_homogeneous"
        summary, cmd = run(a.fdem, case, sets, os.path.join(a.out, "runs", tag))
        strength = dict((c[0], c[3]) for c in CASES)[name](summary) if summary else None
        rec = {"case": name, "modulus": m, "seed": seed, "command": cmd, "strength_Pa": strength,
               "wall_seconds": summary["wall_seconds"] if summary else None}
        with lock:
            records.append(rec)
            with open(path, "w") as f:
                json.dump({"runs": records}, f, indent=1)
        print(f"{tag}: {strength / 1e6 if strength else float('nan'):.3f} MPa", flush=True)

    with cf.ThreadPoolExecutor(max_workers=a.jobs) as ex:
        list(ex.map(one, jobs))
    table = []
    for name, _, _, _ in CASES:
        homo = [r["strength_Pa"] for r in records if r["case"] == name and r["modulus"] is None]
        h = homo[0] if homo and homo[0] else float("nan")
        table.append({"case": name, "modulus": None, "n": 1, "mean_Pa": h, "std_Pa": 0.0, "mean_over_homogeneous": 1.0})
        for m in moduli:
            xs = [r["strength_Pa"] for r in records if r["case"] == name and r["modulus"] == m and r["strength_Pa"]]
            if not xs:
                continue
            mean, sd = stats(xs)
            table.append({"case": name, "modulus": m, "n": len(xs), "mean_Pa": mean, "std_Pa": sd,
                          "mean_over_homogeneous": mean / h, "cov": sd / mean, "min_Pa": min(xs), "max_Pa": max(xs)})
    with open(path, "w") as f:
        json.dump({"runs": records, "statistics": table}, f, indent=1)
    print("| case | Weibull m | runs | mean strength [MPa] | std [MPa] | mean / homogeneous |")
    print("|---|---|---|---|---|---|")
    for t in table:
        print(f"| {t['case']} | {t['modulus'] if t['modulus'] else 'homogeneous'} | {t['n']} | {t['mean_Pa'] / 1e6:.2f} "
              f"| {t['std_Pa'] / 1e6:.2f} | {t['mean_over_homogeneous']:.3f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
