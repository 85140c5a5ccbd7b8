#!/usr/bin/python3
"""Element partitions of the shipped meshes: which partitioner (issue 20, docs/parallel.md).

For each mesh (a case with --set options), method and part count N, runs

    fdem partition CASE --parts N --method M [--set ...] --out TMP

and keeps from TMP/partition.json: elements, interfaces, interfaces cut (each cut interface needs a
ghost element and an exchange per step: the exchange volume), ghost elements, load imbalance
(max/mean - 1 of elements + side-A interfaces) and the partition's wall time (the partitioner
alone, not the mesh). Every run meshes anew (Gmsh, deterministic); one thread.

    perf/partition_study.py [--fdem build/openmp/fdem] [--parts 2,4,8,16,64] \
        [--methods metis,rcb,block] [--out perf/results/partition.json] [--quick] \
        [--rebalance RUN_DIR]
    perf/partition_study.py --markdown [--out perf/results/partition.json]   # the tables of docs/parallel.md

Methods: metis (METIS k-way on the interface graph), rcb and block (plain baselines written here:
coordinate bisection; contiguous ranges of the Morton-ordered elements); zoltan-rcb, zoltan-rib,
zoltan-hsfc where fdem was configured with -DFDEM_ENABLE_MPI=ON (a method the build lacks is
skipped with a note). --quick: the two coarse meshes only.

--rebalance RUN_DIR: RUN_DIR holds a run of the 3D impact at its defaults
(`fdem run cases/particle_impact_3d/case.json --out RUN_DIR`); for that mesh each partition is also
made again at the last frame of RUN_DIR/snapshots.h5 (moved nodes, failed interfaces dropped:
`fdem partition --snapshot`), and the rows get the elements a rebalance moves and the cut without
and with it.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

MESHES = [
    ("brazilian_disc", "cases/brazilian_disc/case.json", []),
    ("impact_3d_h3mm", "cases/particle_impact_3d/case.json", []),
    ("impact_3d_h1.5mm", "cases/particle_impact_3d/case.json", ["parameters.h=0.0015"]),
]


def uptime():
    try:
        return open("/proc/loadavg").read().split()[:3]
    except OSError:
        return []


def markdown(path):
    """The tables of docs/parallel.md from a results file: interfaces cut, then imbalance and time."""
    with open(path) as f:
        d = json.load(f)
    rows = d["rows"]
    methods = list(dict.fromkeys(r["method"] for r in rows))
    meshes = list(dict.fromkeys(r["mesh"] for r in rows))
    by = {(r["mesh"], r["method"], r["parts"]): r for r in rows}
    out = []
    for title, cell in (
            ("interfaces cut (% of the mesh's interfaces)",
             lambda r: f"{r['interfaces_cut']} ({100 * r['cut_fraction']:.1f} %)"),
            ("ghost nodes (the positions exchanged per step, all parts) / ghost elements",
             lambda r: f"{r['ghost_nodes']} / {r['ghosts']}"),
            ("load imbalance (max/mean - 1, %) / the same with the cut interfaces computed twice (%) / "
             "partition time (ms)",
             lambda r: f"{100 * r['imbalance']:.1f} / {100 * r['work_imbalance']:.1f} / "
                       f"{1000 * r['partition_seconds']:.1f}")):
        out.append(f"{title}:\n")
        out.append("| mesh | N | " + " | ".join(methods) + " |")
        out.append("|---|---|" + "---|" * len(methods))
        for mesh in meshes:
            ns = sorted({r["parts"] for r in rows if r["mesh"] == mesh})
            for n in ns:
                first = next(r for r in rows if r["mesh"] == mesh)
                label = f"{mesh} ({first['elements']} el., {first['interfaces']} if.)" if n == ns[0] else ""
                cells = [cell(by[(mesh, m, n)]) if (mesh, m, n) in by else "—" for m in methods]
                out.append(f"| {label} | {n} | " + " | ".join(cells) + " |")
        out.append("")
    rb = [r for r in rows if "rebalance" in r]
    if rb:
        t = rb[0]["rebalance"]
        out.append(f"rebalance of {rb[0]['mesh']} at t = {1e6 * t['time']:.0f} us ({t['failed_interfaces']} "
                   "interfaces failed):\nelements moved (%) / interfaces cut without rebalance -> with:\n")
        out.append("| N | " + " | ".join(m for m in methods if any(r["method"] == m for r in rb)) + " |")
        out.append("|---|" + "---|" * len({r["method"] for r in rb}))
        for n in sorted({r["parts"] for r in rb}):
            cells = []
            for m in methods:
                r = next((r for r in rb if r["method"] == m and r["parts"] == n), None)
                if r is None:
                    continue
                b = r["rebalance"]
                cells.append(f"{100 * b['migrated_fraction']:.1f} % / {b['kept_interfaces_cut']} -> "
                             f"{b['interfaces_cut']}")
            out.append(f"| {n} | " + " | ".join(cells) + " |")
        out.append("")
    out.append(f"Load average before / after: {' '.join(d['load_before'])} / {' '.join(d['load_after'])} "
               f"(2 cores);\none thread; command: `{d['command']}`")
    print("\n".join(out))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--fdem", default="build/openmp/fdem")
    ap.add_argument("--parts", default="2,4,8,16,64")
    ap.add_argument("--methods", default="metis,rcb,block")
    ap.add_argument("--out", default="perf/results/partition.json")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--rebalance", default="", help="folder of a run of the 3D impact at its defaults")
    ap.add_argument("--markdown", action="store_true", help="print the tables of an existing --out file")
    a = ap.parse_args()
    if a.markdown:
        markdown(a.out)
        return
    parts = [int(p) for p in a.parts.split(",")]
    methods = a.methods.split(",")
    meshes = MESHES[:2] if a.quick else MESHES
    env = dict(os.environ, OMP_NUM_THREADS="1")
    rows, notes = [], []
    load_before = uptime()
    with tempfile.TemporaryDirectory() as tmp:
        for label, case, sets in meshes:
            for m in methods:
                for n in parts:
                    cmd = [a.fdem, "partition", case, "--parts", str(n), "--method", m, "--out", tmp]
                    for s in sets:
                        cmd += ["--set", s]
                    rebalance = a.rebalance and label == "impact_3d_h3mm"
                    if rebalance:
                        cmd += ["--snapshot", os.path.join(a.rebalance, "snapshots.h5")]
                    t0 = time.time()
                    r = subprocess.run(cmd, env=env, capture_output=True, text=True)
                    if r.returncode != 0:
                        note = f"{label} {m} N={n}: exit {r.returncode}: {r.stderr.strip()[-300:]}"
                        print(note, file=sys.stderr)
                        notes.append(note)
                        if "built without" in r.stderr:
                            break  # the method is not in this build: skip its other part counts
                        continue
                    with open(os.path.join(tmp, "partition.json")) as f:
                        d = json.load(f)
                    row = {"mesh": label, "case": case, "set": sets, "method": m, "parts": n,
                           "elements": d["elements"], "interfaces": d["interfaces"],
                           "interfaces_cut": d["interfaces_cut"],
                           "cut_fraction": d["interfaces_cut"] / max(1, d["interfaces"]),
                           "ghosts": d["ghosts"], "max_ghosts_per_part": max(d["ghosts_per_part"]),
                           "ghost_nodes": d["ghost_nodes"],
                           "max_ghost_nodes_per_part": max(d["ghost_nodes_per_part"]),
                           "imbalance": d["imbalance"], "element_imbalance": d["element_imbalance"],
                           "work_imbalance": d["work_imbalance"],
                           "partition_seconds": d["seconds"], "command_seconds": time.time() - t0}
                    if rebalance:
                        rb = d["rebalance"]
                        row["rebalance"] = {
                            "time": rb["time"], "failed_interfaces": rb["failed_interfaces"],
                            "migrated_fraction": rb["migrated_fraction"],
                            "kept_interfaces_cut": rb["kept"]["interfaces_cut"],
                            "kept_ghost_nodes": rb["kept"]["ghost_nodes"],
                            "kept_imbalance": rb["kept"]["imbalance"],
                            "interfaces_cut": rb["rebalanced"]["interfaces_cut"],
                            "ghost_nodes": rb["rebalanced"]["ghost_nodes"],
                            "imbalance": rb["rebalanced"]["imbalance"]}
                    rows.append(row)
                    print(f"{label:18s} {m:11s} N={n:3d}  cut {row['interfaces_cut']:7d} "
                          f"({100 * row['cut_fraction']:5.2f} %)  imbalance {100 * row['imbalance']:5.2f} %  "
                          f"{row['partition_seconds']:.4f} s", flush=True)
    out = {"command": " ".join([sys.argv[0]] + sys.argv[1:]), "load_before": load_before,
           "load_after": uptime(), "threads": 1, "rows": rows, "notes": notes}
    os.makedirs(os.path.dirname(a.out) or ".", exist_ok=True)
    with open(a.out, "w") as f:
        json.dump(out, f, indent=1)
        f.write("\n")
    print("wrote", a.out)


if __name__ == "__main__":
    main()
