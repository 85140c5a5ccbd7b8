#!/usr/bin/env python3
"""Strong and weak scaling of runs over several processes (docs/performance.md section 10).

    perf/mpi_scaling.py FDEM_MPI [--steps N] [--h H] [--procs 1,2,3,4] [--reps R] [--out FILE]
    perf/mpi_scaling.py FDEM_MPI --migrations-only [--mh H] [--msteps N] [--reps R] [--out FILE]
    perf/mpi_scaling.py FDEM_MPI --snapshots-only [--sh H] [--ssteps N] [--reps R] [--out FILE]
    perf/mpi_scaling.py --markdown [--out FILE]

FDEM_MPI: fdem built with -DFDEM_ENABLE_MPI=ON (scripts/mpi_check builds build/mpi/fdem). The 3D
impact with contact off (the bulk and its exchange; contact over processes: docs/parallel.md), N steps (default 1000:
the flight and the first impact), one thread per process, the process counts interleaved R times
(default 3: medians) so that the machine's load falls on all alike:
  strong: element size H (default 2.5 mm, about 21 000 tetrahedra) on every count;
  weak:   element size 3 mm / n^(1/3) on n processes: about 12 600 tetrahedra per process
          (efficiency: the time per step at one process's share, against the single process's).
From summary.json: the time loop's wall time, the exchange's bytes per step (all processes, and
the most one process sends) and its seconds on the slowest process. A machine with 2 cores shows
no speed-up beyond 2 processes: the figures above 2 say what oversubscription costs, not scaling.
Cutting the parts anew (migration; docs/parallel.md "Rebalancing"): the 3D impact at 40 m/s with
contact (it fragments; element size --mh, default 4 mm, --msteps steps, default 4000) on 2 processes,
R times interleaved: without rebalancing, with the default rebalancing, and with the test hook that
cuts every 100 steps and moves every element to the other process (FDEM_TEST_RECUT=100): the cuts,
their wall time (summary.json processes.cut_seconds: the state gathered, the partition, the parts
sent, the new parts set up and checked), the modelled work's largest excess over the mean and each
process's loop time outside the exchange (busy_seconds: the measured balance).
Snapshots over processes (docs/parallel.md "Output"): the same impact without contact (element size
--sh, default 2.5 mm; at most --ssteps steps, default 600, a frame every 30 steps; shorter runs a
fifth of their steps) on 2 and 4 processes, R
times interleaved: without snapshots, each process writing its own rows (parallel HDF5), and gathered
on process 0 (FDEM_GATHER_OUTPUT=1): the run's wall time, the frames, the seconds per frame
against the run without snapshots, and the peak memory of process 0 and of the largest other; and a
checkpoint every 100 steps (shorter runs: a quarter of their steps) written both ways (summary.json's
checkpoint.write_seconds per checkpoint).
Also the exchange of larger decompositions without running them: `fdem partition` of the 3D
impact at h = 1.5 mm (90 150 tetrahedra) into 2, 8 and 64 parts (METIS): the bytes each part
would send per step, the input of the weak-scaling model in docs/performance.md section 10.
"""
import json
import os
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CASE = os.path.join(ROOT, "cases/particle_impact_3d/case.json")
SETS = ['contact={"enabled": false}', "output.snapshot_count=0", "output.fragments=false"]


def arg(name, default):
    return sys.argv[sys.argv.index(name) + 1] if name in sys.argv else default


def run_summary(fdem, n, sets, env_more=None):
    with tempfile.TemporaryDirectory() as out:
        cmd = [fdem, "run", CASE, "--out", out, "--quiet"]
        for s in sets:
            cmd += ["--set", s]
        if n > 1:
            cmd = ["mpirun", "--oversubscribe", "-n", str(n)] + [x for k in (env_more or {}) for x in ("-x", k)] + cmd
            if os.geteuid() == 0:
                cmd.insert(1, "--allow-run-as-root")
        env = dict(os.environ, OMP_NUM_THREADS="1", OMP_PROC_BIND="false", GOMP_SPINCOUNT="1000", **(env_more or {}))
        r = subprocess.run(cmd, env=env, capture_output=True, text=True)
        if r.returncode != 0:
            raise SystemExit(f"{' '.join(cmd)}: exit {r.returncode}\n{r.stderr[-2000:]}")
        with open(os.path.join(out, "summary.json")) as f:
            return json.load(f)


MIGRATIONS = [("no rebalancing", ['parallel={"rebalance_above": 1000}'], None),
              ("rebalancing (default)", [], None),
              ("every element moved every 100 steps", ['parallel={"rebalance_above": 1000}'], {"FDEM_TEST_RECUT": "100"})]


def migrations(fdem, reps):
    h, steps = float(arg("--mh", "0.004")), int(arg("--msteps", "4000"))
    sets = [f"parameters.h={h}", "parameters.speed=40", f"time.max_steps={steps}", "output.snapshot_count=0"]
    got = {name: [] for name, _, _ in MIGRATIONS}
    for _ in range(reps):
        for name, more, env in MIGRATIONS:
            got[name].append(run_summary(fdem, 2, sets + more, env))
    rows = []
    for name, ss in got.items():
        med = lambda f: statistics.median(f(s) for s in ss)
        p = lambda s: s["processes"]
        rows.append({"what": name, "processes": 2, "h": h, "elements": ss[0]["counts"]["elements"],
                     "steps": ss[0]["steps"], "loop_s": med(lambda s: s["loop_wall_seconds"]),
                     "loop_s_all": [s["loop_wall_seconds"] for s in ss],
                     "cuts": p(ss[0])["contact_recuts"], "rebalances": p(ss[0])["rebalances"],
                     "cut_s": med(lambda s: p(s)["cut_seconds"]),
                     "work_excess_largest": p(ss[0]).get("work_excess_largest", 0.0),
                     "busy_s": [statistics.median(p(s)["busy_seconds"][k] for s in ss) for k in range(2)],
                     "fragments": ss[0].get("fragments", {}).get("count")})
    return rows


SNAPSHOT_WAYS = [("no snapshots", None, None), ("every process its rows", "frames", None),
                 ("gathered on process 0", "frames", {"FDEM_GATHER_OUTPUT": "1"}),
                 ("checkpoints, every process its rows", "checkpoints", None),
                 ("checkpoints gathered on process 0", "checkpoints", {"FDEM_GATHER_OUTPUT": "1"})]


def snapshots(fdem, reps):
    h, steps = float(arg("--sh", "0.0025")), int(arg("--ssteps", "600"))
    base_sets = [SETS[0], SETS[2], f"parameters.h={h}"]
    first = run_summary(fdem, 1, base_sets + ["time.max_steps=1", "output.snapshot_count=0"])
    dt = first["time_step"]["dt_s"]
    got = {}
    for _ in range(reps):
        for n in (2, 4):
            for name, frames, env in SNAPSHOT_WAYS:
                # a frame every 30 steps (and one at the start and at the end), or a checkpoint every 100
                # (in shorter runs: 5 frames, 4 checkpoints)
                every_frame, every_ck = min(30, steps // 5) + 0.5, min(100, steps // 4) + 0.5
                out_set = {
                    "frames": f'output={{"history_rows": 200, "snapshot_interval": {every_frame * dt:.9e}}}',
                    "checkpoints": f'output={{"history_rows": 200, "checkpoint_every": {every_ck * dt:.9e}}}',
                    None: "output.snapshot_count=0"}[frames]
                with tempfile.TemporaryDirectory() as out:
                    cmd = [fdem, "run", CASE, "--out", out, "--quiet"]
                    for v in base_sets + [f"time.max_steps={steps}", out_set]:
                        cmd += ["--set", v]
                    cmd = (["mpirun", "--oversubscribe", "-n", str(n)] +
                           [x for k in (env or {}) for x in ("-x", k)] + cmd)
                    if os.geteuid() == 0:
                        cmd.insert(1, "--allow-run-as-root")
                    e = dict(os.environ, OMP_NUM_THREADS="1", OMP_PROC_BIND="false", GOMP_SPINCOUNT="1000",
                             **(env or {}))
                    r = subprocess.run(cmd, env=e, capture_output=True, text=True)
                    if r.returncode != 0:
                        raise SystemExit(f"{' '.join(cmd)}: exit {r.returncode}\n{r.stderr[-2000:]}")
                    with open(os.path.join(out, "summary.json")) as f:
                        summ = json.load(f)
                    xdmf, h5 = os.path.join(out, "snapshots.xdmf"), os.path.join(out, "snapshots.h5")
                    with open(xdmf) if os.path.exists(xdmf) else open(os.devnull) as f:
                        nf = f.read().count('<Grid Name="step_')
                    ck = summ.get("checkpoint") or {}
                    got.setdefault((n, name), []).append({
                        "wall_s": summ["wall_seconds"], "frames": nf, "elements": summ["counts"]["elements"],
                        "checkpoints": ck.get("written", 0), "checkpoint_s": ck.get("write_seconds", 0.0),
                        "file_bytes": os.path.getsize(h5) if os.path.exists(h5) else 0,
                        "rss": summ["processes"]["peak_rss_bytes"]})
    rows = []
    for n in (2, 4):
        base = statistics.median(x["wall_s"] for x in got[(n, SNAPSHOT_WAYS[0][0])])
        for name, _, _ in SNAPSHOT_WAYS:
            xs = got[(n, name)]
            wall = statistics.median(x["wall_s"] for x in xs)
            nf = xs[-1]["frames"]
            nc = xs[-1]["checkpoints"]
            rows.append({"what": name, "processes": n, "h": h, "elements": xs[-1]["elements"], "steps": steps,
                         "frames": nf, "wall_s": wall, "wall_s_all": [x["wall_s"] for x in xs],
                         "per_frame_s": (wall - base) / nf if nf else 0.0, "file_bytes": xs[-1]["file_bytes"],
                         "checkpoints": nc,
                         "per_checkpoint_s": (statistics.median(x["checkpoint_s"] for x in xs) / nc
                                              if nc else 0.0),
                         "rss0_mb": statistics.median(x["rss"][0] for x in xs) / 1e6,
                         "rss_other_mb": statistics.median(max(x["rss"][1:]) for x in xs) / 1e6})
    return rows


def run(fdem, n, h, steps):
    with tempfile.TemporaryDirectory() as out:
        cmd = [fdem, "run", CASE, "--out", out, "--quiet", "--set", f"parameters.h={h}",
               "--set", f"time.max_steps={steps}"]
        for s in SETS:
            cmd += ["--set", s]
        if n > 1:
            cmd = ["mpirun", "--oversubscribe", "-n", str(n)] + cmd
            if os.geteuid() == 0:
                cmd.insert(1, "--allow-run-as-root")
        env = dict(os.environ, OMP_NUM_THREADS="1", OMP_PROC_BIND="false", GOMP_SPINCOUNT="1000")
        r = subprocess.run(cmd, env=env, capture_output=True, text=True)
        if r.returncode != 0:
            raise SystemExit(f"{' '.join(cmd)}: exit {r.returncode}\n{r.stderr[-2000:]}")
        with open(os.path.join(out, "summary.json")) as f:
            s = json.load(f)
    p = s.get("processes", {})
    return {"elements": s["counts"]["elements"], "steps": s["steps"], "loop_s": s["loop_wall_seconds"],
            "bytes_per_step": p.get("exchange_bytes_per_step", 0.0),
            "bytes_per_step_most": p.get("exchange_bytes_per_step_most", 0.0),
            "exchange_s_most": p.get("exchange_seconds_most", 0.0)}


def measure(fdem):
    steps = int(arg("--steps", "1000"))
    h = float(arg("--h", "0.0025"))
    procs = [int(x) for x in arg("--procs", "1,2,3,4").split(",")]
    reps = int(arg("--reps", "3"))
    configs = [("strong", n, h) for n in procs] + [("weak", n, round(0.003 / n ** (1 / 3), 6)) for n in procs]
    got = {c: [] for c in configs}
    for _ in range(reps):
        for c in configs:
            got[c].append(run(fdem, c[1], c[2], steps))
    rows = []
    for (kind, n, hh), rs in got.items():
        med = lambda k: statistics.median(r[k] for r in rs)
        rows.append({"kind": kind, "processes": n, "h": hh, "elements": rs[0]["elements"], "steps": rs[0]["steps"],
                     "loop_s": med("loop_s"), "loop_s_all": [r["loop_s"] for r in rs],
                     "bytes_per_step": rs[0]["bytes_per_step"], "bytes_per_step_most": rs[0]["bytes_per_step_most"],
                     "exchange_s_most": med("exchange_s_most")})
    load = os.getloadavg()
    return {"machine": f"{os.cpu_count()} cores; load average at the end {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}",
            "command": " ".join(["perf/mpi_scaling.py"] + sys.argv[1:]), "rows": rows,
            "migrations": migrations(fdem, reps), "snapshots": snapshots(fdem, reps),
            "decompositions": decompositions(fdem)}


def decompositions(fdem, h=0.0015, parts=(2, 8, 64)):
    out = []
    for n in parts:
        with tempfile.TemporaryDirectory() as d:
            r = subprocess.run([fdem, "partition", CASE, "--parts", str(n), "--set", f"parameters.h={h}", "--out", d],
                               capture_output=True, text=True, env=dict(os.environ, OMP_NUM_THREADS="2"))
            if r.returncode != 0:
                raise SystemExit(f"fdem partition: exit {r.returncode}\n{r.stderr[-2000:]}")
            with open(os.path.join(d, "partition.json")) as f:
                p = json.load(f)
        dec = p["decomposition"]
        out.append({"parts": n, "h": h, "method": p["method"], "elements": p["elements"],
                    "send_bytes_per_step": dec["send_bytes_per_step"],
                    "send_bytes_per_step_most": dec["send_bytes_per_step_most"],
                    "neighbours_most": dec["neighbours_most"], "ghost_nodes": dec["ghost_nodes"],
                    "ghost_nodes_needed": dec["ghost_nodes_needed"]})
    return out


def markdown(res):
    lines = ["| scaling | processes | h (mm) | tetrahedra | loop (s, median) | ns per element-step | "
             "speed-up / efficiency | bytes exchanged per step (all; most into one process) | exchange (s, slowest) |",
             "|---|---|---|---|---|---|---|---|---|"]
    base = {}
    for r in res["rows"]:
        ns = r["loop_s"] / (r["steps"] * r["elements"]) * 1e9
        if r["processes"] == 1:
            base[r["kind"]] = r
        b = base.get(r["kind"])
        if r["kind"] == "strong":
            su = f"{b['loop_s'] / r['loop_s']:.2f} x" if b else ""
        else:  # weak: time per step at the same elements per process
            su = f"{b['loop_s'] / r['loop_s'] * (r['elements'] / r['processes']) / b['elements']:.2f}" if b else ""
        lines.append(f"| {r['kind']} | {r['processes']} | {r['h'] * 1e3:.2f} | {r['elements']} | {r['loop_s']:.2f} | "
                     f"{ns:.0f} | {su} | {r['bytes_per_step']:.0f}; {r['bytes_per_step_most']:.0f} | "
                     f"{r['exchange_s_most']:.2f} |")
    text = "\n".join(lines) + f"\n\n{res['machine']}; `{res['command']}`\n"
    mig = res.get("migrations") or []
    if mig:
        text += ("\n| 2 processes, fragmenting | cuts (rebalances) | loop (s) | cuts (s; per cut) | "
                 "work excess (largest) | busy s (process 0; 1) |\n|---|---|---|---|---|---|\n")
        for m in mig:
            per = f"{m['cut_s'] / m['cuts']:.3f}" if m["cuts"] else "-"
            text += (f"| {m['what']} | {m['cuts']} ({m['rebalances']}) | {m['loop_s']:.2f} | {m['cut_s']:.2f}; {per} | "
                     f"{m['work_excess_largest']:.3f} | {m['busy_s'][0]:.2f}; {m['busy_s'][1]:.2f} |\n")
    snap = res.get("snapshots") or []
    if snap:
        text += ("\n| output | processes | tetrahedra | frames (checkpoints) | wall (s, median) | "
                 "s per frame (per checkpoint) | snapshots.h5 (MB) | "
                 "peak memory, process 0; largest other (MB) |\n"
                 "|---|---|---|---|---|---|---|---|\n")
        for m in snap:
            if m.get("checkpoints"):
                what, per = f"({m['checkpoints']})", f"({m['per_checkpoint_s']:.3f})"
            else:
                what, per = f"{m['frames']}", f"{m['per_frame_s']:.3f}"
            text += (f"| {m['what']} | {m['processes']} | {m['elements']} | {what} | {m['wall_s']:.2f} | "
                     f"{per} | {m['file_bytes'] / 1e6:.1f} | {m['rss0_mb']:.0f}; {m['rss_other_mb']:.0f} |\n")
        if res.get("snapshots_command"):
            text += f"\n`{res['snapshots_command']}`\n"
    return text


def main():
    out = arg("--out", os.path.join(ROOT, "perf/results/mpi_scaling.json"))
    if "--markdown" in sys.argv:
        with open(out) as f:
            print(markdown(json.load(f)))
        return 0
    if len(sys.argv) < 2 or sys.argv[1].startswith("--"):
        print(__doc__)
        return 2
    if "--migrations-only" in sys.argv:  # (the other rows kept from FILE)
        with open(out) as f:
            res = json.load(f)
        res["migrations"] = migrations(os.path.abspath(sys.argv[1]), int(arg("--reps", "3")))
        res["migrations_command"] = " ".join(["perf/mpi_scaling.py"] + sys.argv[1:])
    elif "--snapshots-only" in sys.argv:
        with open(out) as f:
            res = json.load(f)
        res["snapshots"] = snapshots(os.path.abspath(sys.argv[1]), int(arg("--reps", "3")))
        res["snapshots_command"] = " ".join(["perf/mpi_scaling.py"] + sys.argv[1:])
    else:
        res = measure(os.path.abspath(sys.argv[1]))
    with open(out, "w") as f:
        json.dump(res, f, indent=1)
    print(markdown(res))
    return 0


if __name__ == "__main__":
    sys.exit(main())
