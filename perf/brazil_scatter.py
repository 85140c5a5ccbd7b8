#!/usr/bin/python3
"""Brazilian disc: scatter of the computed strength over mesh realisations (issue 23).

One mesh does not decide the strength: at each resolution the disc is meshed N times with element
sizes spread evenly over +-SPREAD around the nominal size (Gmsh's Delaunay mesher gives a different
mesh for each size), and the script reports the mean and standard deviation of

  - the tensile strength 2 P_max / (pi D t) (summary.json results.tensile_strength_Pa), as error
    against the input f_t;
  - the load at the first failed interface (the top platen load of the first history row with
    interfaces_failed > 0), as the same stress 2 P / (pi D t) against f_t;
  - the split's distance from the loaded diameter: the mean |x| of the midpoints of the failed
    interfaces (damage 1 in the last snapshot) with |y| < R/2 (the central half of the diameter,
    away from the platens); it counts every failure there, wing cracks from the platens after the
    peak included;
  - the loaded diameter's own failure (with mesh.embedded_diameter): the share of the diameter's
    interfaces with |y| < R/2 that failed (1: split on the diameter through the central half);
  - the damage under the platens: failed interfaces with |y| > 0.8 R.

    perf/brazil_scatter.py --sizes 0.00417:10,0.003:10,0.00167:10 --out DIR [--spread 0.05] \
        [--jobs 2] [--set KEY=VALUE ...] [--case cases/brazilian_disc/case.json] [--label NAME]

Each run: `fdem run CASE --set mesh.element_size=H --set output.snapshot_count=1 [--set ...]`,
kept in DIR/runs/<label>_h<H>/. Writes DIR/<label>.json (runs and per-size statistics; rewritten
after every run). Threads: OMP_NUM_THREADS of the environment (1 for a study: the cost of a run is
then core-seconds); --jobs runs that many at once.
"""
import argparse
import concurrent.futures as cf
import csv
import json
import math
import os
import subprocess
import sys
import threading
import time


def stats(xs):
    xs = [x for x in xs if x is not None]
    if not xs:
        return {"n": 0}
    m = sum(xs) / len(xs)
    sd = math.sqrt(sum((x - m) ** 2 for x in xs) / (len(xs) - 1)) if len(xs) > 1 else 0.0
    return {"n": len(xs), "mean": m, "std": sd, "min": min(xs), "max": max(xs)}


def first_failure(history):
    """Top platen load, time and row of the first history row with a failed interface."""
    with open(history) as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        if float(r["interfaces_failed"]) > 0:
            return float(r["top_load [N]"]), float(r["time [s]"])
    return None, None


def split_measure(h5path, R):
    import h5py
    with h5py.File(h5path, "r") as f:
        X = f["/mesh/reference_coordinates"][()]
        I = f["/mesh/interfaces"][()]
        frames = sorted(k for k in f if k.startswith("step_"))
        dmg = f["/" + frames[-1] + "/damage"][()]
        first = None  # the failed interfaces of the first snapshot that has any (--frames > 1)
        for k in frames[1:-1]:
            d = f["/" + k + "/damage"][()]
            if (d >= 1.0).any():
                first = (k, f["/" + k].attrs["time"], [q for q in range(len(d)) if d[q] >= 1.0])
                break
    mid = lambda q: (0.5 * (X[I[q][0]][0] + X[I[q][1]][0]), 0.5 * (X[I[q][0]][1] + X[I[q][1]][1]))
    out = {}
    if first:
        pts = [mid(q) for q in first[2]]
        out["first_failed_frame"] = {"time_s": float(first[1]), "count": len(pts),
                                     "mean_abs_x_m": sum(abs(p[0]) for p in pts) / len(pts),
                                     "max_abs_y_m": max(abs(p[1]) for p in pts),
                                     "under_platens": sum(1 for p in pts if abs(p[1]) > 0.8 * R)}
    xs, ys = [], []
    for q, d in enumerate(dmg):
        if d < 1.0:
            continue
        a, b = I[q][0], I[q][1]
        xs.append(0.5 * (X[a][0] + X[b][0]))
        ys.append(0.5 * (X[a][1] + X[b][1]))
    central = [abs(x) for x, y in zip(xs, ys) if abs(y) < R / 2]
    out.update({"failed": len(xs), "failed_central": len(central),
           "failed_under_platens": sum(1 for y in ys if abs(y) > 0.8 * R)})
    # the loaded diameter's own failure (mesh.embedded_diameter: interfaces with both ends on x = 0):
    # the share of its interfaces with |y| < R/2 that failed. split_offset_m also counts every other
    # failure of the central band, e.g. wing cracks from the platens after the peak.
    on = [q for q in range(len(I)) if abs(X[I[q][0]][0]) < 1e-6 * R and abs(X[I[q][1]][0]) < 1e-6 * R
          and abs(0.5 * (X[I[q][0]][1] + X[I[q][1]][1])) < R / 2]
    if on:
        out["diameter_failed_fraction"] = sum(1 for q in on if dmg[q] >= 1.0) / len(on)
    if central:
        out["split_offset_m"] = sum(central) / len(central)
        cy = [y for y in ys if abs(y) < R / 2]
        out["central_y_range_m"] = [min(cy), max(cy)]
    return out


def run_one(a, h, label, extra):
    out = os.path.join(a.out, "runs", f"{label}_h{h * 1000:.4f}")
    cmd = [a.fdem, "run", a.case, "--out", out, "--quiet", "--set", f"mesh.element_size={h:.6g}",
           "--set", f"output.snapshot_count={a.frames}"]
    for s in extra:
        cmd += ["--set", s]
    t0 = time.time()
    if a.reuse and os.path.exists(os.path.join(out, "record.json")):
        with open(os.path.join(out, "record.json")) as f:
            return json.load(f)
    if a.reuse and os.path.exists(os.path.join(out, "summary.json")):
        p = subprocess.CompletedProcess(cmd, 0, "")
    else:
        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    rec = {"element_size_m": h, "command": " ".join(cmd), "exit_status": p.returncode,
           "process_wall_seconds": time.time() - t0, "threads": os.environ.get("OMP_NUM_THREADS", "")}
    if p.returncode != 0:
        rec["error_text"] = p.stdout[-2000:]
        return rec
    with open(os.path.join(out, "summary.json")) as f:
        s = json.load(f)
    res = s["results"]
    st = res["tensile_strength_Pa"]
    scale = st / res["peak_load_N"]  # 2 / (pi D t)
    P1, t1 = first_failure(os.path.join(out, "history.csv"))
    rec.update({"elements": s["counts"]["elements"], "steps": s["steps"], "wall_seconds": s["wall_seconds"],
                "stop_reason": s["stop_reason"], "peak_load_N": res["peak_load_N"],
                "tensile_strength_Pa": st, "error": (st - a.ft) / a.ft,
                "first_failure_load_N": P1, "first_failure_time_s": t1,
                "first_failure_error": None if P1 is None else (scale * P1 - a.ft) / a.ft,
                "max_relative_balance_error": s["energy"]["max_relative_balance_error"]})
    rec.update(split_measure(os.path.join(out, "snapshots.h5"), a.radius))
    with open(os.path.join(out, "record.json"), "w") as f:  # for --reuse once the snapshots are gone
        json.dump(rec, f, indent=1)
    if not a.keep:
        for fn in ("snapshots.h5", "snapshots.xdmf", "fragments.csv"):
            try:
                os.remove(os.path.join(out, fn))
            except OSError:
                pass
    return rec


def summarise(runs):
    by = {}
    for r in runs:
        by.setdefault(r["nominal_size_m"], []).append(r)
    out = []
    for h0 in sorted(by, reverse=True):
        rr = [r for r in by[h0] if r["exit_status"] == 0]
        out.append({"nominal_size_m": h0, "runs": len(by[h0]), "failed_runs": len(by[h0]) - len(rr),
                    "elements": stats([r["elements"] for r in rr]),
                    "error": stats([r["error"] for r in rr]),
                    "first_failure_error": stats([r["first_failure_error"] for r in rr]),
                    "split_offset_m": stats([r.get("split_offset_m") for r in rr]),
                    "diameter_failed_fraction": stats([r.get("diameter_failed_fraction") for r in rr]),
                    "failed_under_platens": stats([r["failed_under_platens"] for r in rr]),
                    "wall_seconds": stats([r["wall_seconds"] for r in rr]),
                    "steps": stats([r["steps"] for r in rr])})
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--fdem", default="build/openmp/fdem")
    ap.add_argument("--case", default="cases/brazilian_disc/case.json")
    ap.add_argument("--sizes", required=True, help="nominal element sizes in m with their realisation counts, "
                    "SIZE:N comma separated (e.g. 0.003:10)")
    ap.add_argument("--spread", type=float, default=0.05, help="relative spread of the sizes around each nominal")
    ap.add_argument("--set", action="append", default=[], help="extra --set KEY=VALUE for every run")
    ap.add_argument("--label", default="brazil_scatter")
    ap.add_argument("--out", required=True)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--ft", type=float, default=8e6, help="input tensile strength (Pa)")
    ap.add_argument("--radius", type=float, default=0.05, help="disc radius (m)")
    ap.add_argument("--frames", type=int, default=1, help="snapshots per run (1: the last only; more: also "
                    "where the first failed interfaces are, at the snapshot resolution)")
    ap.add_argument("--reuse", action="store_true", help="take a run whose folder has its record.json "
                    "(or a summary.json and snapshots) instead of running it again")
    ap.add_argument("--keep", action="store_true", help="keep the snapshots of each run")
    a = ap.parse_args()
    plan = []
    for item in a.sizes.split(","):
        h0, n = item.split(":") if ":" in item else (item, "1")
        h0, n = float(h0), int(n)
        for k in range(n):
            f = 1.0 + (a.spread * (2.0 * k / (n - 1) - 1.0) if n > 1 else 0.0)
            plan.append((h0, h0 * f))
    os.makedirs(os.path.join(a.out, "runs"), exist_ok=True)
    runs, lock = [], threading.Lock()
    path = os.path.join(a.out, a.label + ".json")

    def write():
        doc = {"ft_Pa": a.ft, "radius_m": a.radius, "case": a.case, "sets": a.set, "spread": a.spread,
               "label": a.label, "runs": sorted(runs, key=lambda r: (-r["nominal_size_m"], r["element_size_m"])),
               "statistics": summarise(runs)}
        with open(path, "w") as f:
            json.dump(doc, f, indent=1)

    def task(h0, h):
        rec = run_one(a, h, a.label, a.set)
        rec["nominal_size_m"] = h0
        with lock:
            runs.append(rec)
            write()
            if rec["exit_status"] != 0:
                print(f"{a.label}: h = {h:.5g}: exit status {rec['exit_status']}", flush=True)
            else:
                print(f"{a.label}: h = {1000 * h:.4f} mm: {rec['elements']} elements, sigma_t "
                      f"{100 * rec['error']:+.2f} %, first failure {100 * rec['first_failure_error']:+.2f} %, "
                      f"split offset {1000 * rec.get('split_offset_m', float('nan')):.1f} mm, "
                      f"diameter failed {rec.get('diameter_failed_fraction', float('nan')):.2f}, "
                      f"{rec['wall_seconds']:.0f} s", flush=True)

    with cf.ThreadPoolExecutor(max_workers=max(1, a.jobs)) as ex:
        for fut in [ex.submit(task, h0, h) for h0, h in plan]:
            fut.result()
    write()
    for s in summarise(runs):
        e, e1, off = s["error"], s["first_failure_error"], s["split_offset_m"]
        if e["n"]:
            print(f"{a.label}: h0 = {1000 * s['nominal_size_m']:g} mm, {e['n']} runs: strength "
                  f"{100 * e['mean']:+.2f} % +- {100 * e['std']:.2f} %, first failure {100 * e1['mean']:+.2f} % +- "
                  f"{100 * e1['std']:.2f} %, split offset {1000 * off.get('mean', float('nan')):.1f} mm", flush=True)
    return 0 if all(r["exit_status"] == 0 for r in runs) else 1


if __name__ == "__main__":
    sys.exit(main())
