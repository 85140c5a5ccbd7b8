#!/usr/bin/python3
"""Brazilian disc: error of the computed tensile strength against the input f_t, and wall time,
over element sizes and loading rates (issue 7). Runs `fdem run cases/brazilian_disc/case.json
--set mesh.element_size=D --set parameters.rate=V` for each pair and collects summary.json.

    perf/sweep_brazil.py --fdem build/openmp/fdem --sizes 0.005,0.003 --rates 0.1,0.05 \
        --out DIR [--max-cost 30] [--ft 8e6] [--realisations N] [--spread 0.05]

One mesh does not decide the strength (issue 23, cases/brazilian_disc/README.md): with
--realisations N each pair is run on N meshes, element sizes spread evenly over +-SPREAD around D
(record keys nominal_size_m and realisation); perf/report.py plots their mean error with the
standard deviation as error bars.

Pairs whose estimated cost (0.005 / d)^3 * (0.05 / v), relative to d = 5 mm at 0.05 m/s, exceeds
--max-cost are left out (listed in the output). Writes DIR/brazil.json (one record per run) and
keeps each run's outputs in DIR/runs/d<D>_v<V>[_r<K>]/. Threads: OMP_NUM_THREADS of the environment
(1 for a study); --jobs runs that many at once (one-thread runs are not pinned, so each gets a core of
its own: src/app/main.cpp).

With the case as shipped, V is the loading rate after the platens' fast approach (parameters.approach
at parameters.approach_rate = 0.1 m/s; at V = 0.1 m/s there is no change of speed).
"""
import argparse
import json
import os
import subprocess
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--fdem", default="build/openmp/fdem")
    ap.add_argument("--case", default="cases/brazilian_disc/case.json")
    ap.add_argument("--sizes", required=True, help="element sizes in m, comma separated")
    ap.add_argument("--rates", required=True, help="platen speeds in m/s, comma separated")
    ap.add_argument("--out", required=True)
    ap.add_argument("--max-cost", type=float, default=1e9)
    ap.add_argument("--ft", type=float, default=8e6, help="input tensile strength (Pa)")
    ap.add_argument("--realisations", type=int, default=1, help="meshes per pair (sizes spread around D)")
    ap.add_argument("--spread", type=float, default=0.05, help="relative spread of the realisations' sizes")
    ap.add_argument("--jobs", type=int, default=1, help="runs at once")
    a = ap.parse_args()
    n = max(1, a.realisations)
    sizes = [float(s) for s in a.sizes.split(",") if s]
    rates = [float(s) for s in a.rates.split(",") if s]
    os.makedirs(os.path.join(a.out, "runs"), exist_ok=True)
    records, skipped = [], []
    plan = []
    for d0 in sizes:
        for v in rates:
            cost = (0.005 / d0) ** 3 * (0.05 / v)
            if cost > a.max_cost:
                skipped.append({"element_size_m": d0, "rate_m_per_s": v, "cost_units": cost})
                print(f"brazil: d = {d0} m, rate = {v} m/s left out (cost {cost:.1f} > {a.max_cost})", flush=True)
            else:
                plan += [(d0, v, k, cost) for k in range(n)]
    lock = threading.Lock()
    done = [None] * len(plan)

    def run_one(i):
        d0, v, k, cost = plan[i]
        d = d0 * (1.0 + a.spread * (2.0 * k / (n - 1) - 1.0)) if n > 1 else d0
        out = os.path.join(a.out, "runs", f"d{d0:g}_v{v:g}" + (f"_r{k}" if n > 1 else ""))
        cmd = [a.fdem, "run", a.case, "--out", out, "--quiet",
               "--set", f"mesh.element_size={d:.6g}", "--set", f"parameters.rate={v}"]
        t0 = time.time()
        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        wall = time.time() - t0
        rec = {"element_size_m": d, "nominal_size_m": d0, "realisation": k, "rate_m_per_s": v, "cost_units": cost,
               "command": " ".join(cmd), "exit_status": p.returncode, "process_wall_seconds": wall,
               "threads": os.environ.get("OMP_NUM_THREADS", "")}
        if p.returncode != 0:
            rec["error"] = p.stdout[-2000:]
            print(f"brazil: d = {d} v = {v}: exit status {p.returncode}\n{p.stdout[-2000:]}", flush=True)
        else:
            with open(os.path.join(out, "summary.json")) as f:
                s = json.load(f)
            st = s["results"]["tensile_strength_Pa"]
            rec.update({
                "elements": s["counts"]["elements"],
                "interfaces": s["counts"]["interfaces"],
                "steps": s["steps"],
                "dt_s": s["time_step"]["dt_s"],
                "wall_seconds": s["wall_seconds"],
                "loop_wall_seconds": s["loop_wall_seconds"],
                "element_steps_per_second": s["element_steps_per_second"],
                "stop_reason": s["stop_reason"],
                "tensile_strength_Pa": st,
                "error": (st - a.ft) / a.ft,
                "max_relative_balance_error": s["energy"]["max_relative_balance_error"],
            })
            print(f"brazil: d = {d:g} m, rate = {v:g} m/s: {rec['elements']} elements, {rec['steps']} steps, "
                  f"sigma_t = {st / 1e6:.3f} MPa ({100 * rec['error']:+.2f} %), wall {rec['wall_seconds']:.1f} s",
                  flush=True)
        with lock:
            done[i] = rec
            records[:] = [r for r in done if r is not None]
            with open(os.path.join(a.out, "brazil.json"), "w") as f:
                json.dump({"ft_Pa": a.ft, "case": a.case, "runs": records, "left_out": skipped}, f, indent=1)

    with ThreadPoolExecutor(max_workers=max(1, a.jobs)) as ex:
        list(ex.map(run_one, range(len(plan))))
    with open(os.path.join(a.out, "brazil.json"), "w") as f:
        json.dump({"ft_Pa": a.ft, "case": a.case, "runs": records, "left_out": skipped}, f, indent=1)
    return 0 if all(r["exit_status"] == 0 for r in records) else 1


if __name__ == "__main__":
    sys.exit(main())
