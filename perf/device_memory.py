#!/usr/bin/env python3
"""Device memory model of the 3D impact: bytes per tetrahedron of the Kokkos Views a run holds
(model, contact, fragment analysis; the host's per-thread scatter copies left out, as a GPU adds
with atomics), measured through Kokkos' allocation hooks on the host backend (summary.json
memory.views; the same Views a CUDA run allocates), and the largest impact that fits a GPU.

    perf/device_memory.py [--fdem build/openmp/fdem] [--sizes 0.006,0.0045,0.003,0.002]
                          [--steps 30] [--full 0.003] [--out perf/results/device_memory.json]

Each size runs the default 3D impact (cases/particle_impact_3d) for --steps steps: the Views of the
set-up and the first contact lists. --full runs one size to the end, so that the growth of the
contact lists as the sphere fragments is measured too (its peak over the whole run against its
peak after --steps). The model: bytes = a * tetrahedra + b, fitted over the sizes, times the
whole run's growth factor; the largest impact within 90 % of 80 GB (H100) and 141 GB (H200).
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CASE = os.path.join(ROOT, "cases", "particle_impact_3d", "case.json")
GB = 1e9


def run(fdem, h, steps, out):
    cmd = [fdem, "run", CASE, "--out", out, "--quiet", "--set", "parameters.h=%g" % h,
           "--set", "output.snapshot_count=0"]
    if steps:
        cmd += ["--set", "time.max_steps=%d" % steps]
    env = dict(os.environ)
    env.setdefault("OMP_NUM_THREADS", "2")
    subprocess.run(cmd, check=True, env=env, stdout=subprocess.DEVNULL)
    with open(os.path.join(out, "summary.json")) as f:
        s = json.load(f)
    v = s["memory"]["views"]
    kinds = v["peak_by_kind"]
    return dict(h=h, steps=s["steps"], elements=s["counts"]["elements"], interfaces=s["counts"].get("interfaces"),
                peak_bytes=v["peak_bytes"], scatter_bytes=kinds.get("scatter", 0),
                device_bytes=v["peak_bytes"] - kinds.get("scatter", 0), by_kind=kinds,
                largest=v["largest"][:8], rss_bytes=s["memory"]["peak_rss_bytes"])


def fit(xs, ys):
    n = len(xs)
    mx, my = sum(xs) / n, sum(ys) / n
    sxx = sum((x - mx) ** 2 for x in xs)
    a = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx
    return a, my - a * mx


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--fdem", default=os.path.join(ROOT, "build", "openmp", "fdem"))
    ap.add_argument("--sizes", default="0.006,0.0045,0.003,0.002")
    ap.add_argument("--steps", type=int, default=30)
    ap.add_argument("--full", type=float, default=0.003, help="element size of the whole run (0: none)")
    ap.add_argument("--out", default=os.path.join(ROOT, "perf", "results", "device_memory.json"))
    a = ap.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for h in [float(x) for x in a.sizes.split(",")]:
            r = run(a.fdem, h, a.steps, os.path.join(tmp, "h%g" % h))
            rows.append(r)
            print("h %.4g m: %d tetrahedra, %d steps: Views %.1f MB (%.0f B/tet), of which scatter copies %.1f MB; "
                  "device %.0f B/tet; RSS %.0f B/tet" % (h, r["elements"], r["steps"], r["peak_bytes"] / 1e6,
                                                        r["peak_bytes"] / r["elements"], r["scatter_bytes"] / 1e6,
                                                        r["device_bytes"] / r["elements"],
                                                        r["rss_bytes"] / r["elements"]), flush=True)
        full = None
        if a.full > 0:
            full = run(a.fdem, a.full, 0, os.path.join(tmp, "full"))
            print("whole run at h %.4g m: %d steps, device %.0f B/tet" % (a.full, full["steps"],
                                                                         full["device_bytes"] / full["elements"]))
    a_, b_ = fit([r["elements"] for r in rows], [r["device_bytes"] for r in rows])
    growth = 1.0
    if full:
        short = [r for r in rows if abs(r["h"] - a.full) < 1e-12]
        if short:
            growth = full["device_bytes"] / short[0]["device_bytes"]
    per_tet = a_ * growth
    fits = {name: int((0.9 * cap * GB - b_ * growth) / per_tet) for name, cap in (("H100 80 GB", 80), ("H200 141 GB", 141))}
    res = dict(runs=rows, full_run=full, fit_bytes_per_tet=a_, fit_offset_bytes=b_, growth_over_run=growth,
               model_bytes_per_tet=per_tet, largest_tetrahedra_in_90_percent=fits, steps=a.steps)
    print("model: %.0f B per tetrahedron (fit over %d sizes, x %.3f for the whole run's contact growth) + %.1f MB;"
          " largest impact within 90 %% of the card: %s" % (a_, len(rows), growth, b_ / 1e6,
                                                          ", ".join("%s: %.3g tetrahedra" % kv for kv in fits.items())))
    os.makedirs(os.path.dirname(a.out), exist_ok=True)
    with open(a.out, "w") as f:
        json.dump(res, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
