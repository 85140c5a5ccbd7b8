#!/usr/bin/python3
"""A weak-scaling model of the 3D impact to 1e9 tetrahedra (issue 49; docs/parallel.md "Scale"):
each term of a run over processes (the set-up, a step, the exchange, a fragment labelling, a
checkpoint, a cut of the parts anew) from what was measured per process at 962 688 tetrahedra on
this machine, extrapolated to N tetrahedra on P processes (64 GPUs, 64 CPU nodes) with the
assumptions written below, beside today's code path (the set-up and the cut through process 0)
and the local set-up of docs/parallel.md (fdem run's for refined cases: no process holds the whole
mesh).

    perf/scale_model.py [--inputs FILE] [--runs PLAIN CHECKPOINT CUT] [--json OUT]

--runs reads the measured inputs from three run folders of the 962 688-tetrahedron impact on 2
processes of one thread (their summary.json: `setup.phases`, `processes.setup_wall_seconds`, the
loop's time per step, `fragment_labelling`, `checkpoint`, `processes.cut_seconds`):

    OMP_NUM_THREADS=1 mpirun -n 2 build/mpi/fdem run cases/particle_impact_3d/case.json --out PLAIN \\
        --quiet --set parameters.h=0.0028 --set mesh.refine=2 --set time.max_steps=20 \\
        --set output.snapshot_count=0 --set output.history_rows=1000000
    ... --out CHECKPOINT ... --checkpoint-every 9e-8
    FDEM_TEST_RECUT=40 mpirun -x FDEM_TEST_RECUT -n 2 ... --out CUT ... --set time.max_steps=130

Without --runs (or --inputs) it uses MEASURED below: the figures of docs/parallel.md "Scale"
(2026-12-06, the 2-core machine quiet but for those runs). Host only; prints a Markdown table.
"""
import argparse
import json
import math
import os

# Measured at 962 688 tetrahedra (the 3D impact, h = 2.8 mm refined twice from 15 042), 2 processes
# of one thread each, the 2-core machine (docs/parallel.md "Scale", 2026-12-06).
MEASURED = {
    "tetrahedra": 962688,
    "processes": 2,
    "coarse_tetrahedra": 15042,
    "step_s": 0.24,                 # a step of the intact run (each process 481 344 tetrahedra)
    "setup_s": 8.0,                 # from mpirun to the first step
    # process 0's serial set-up phases (s): Gmsh's coarse mesh, refinement, insertion, decomposition,
    # the whole mesh written for the cuts, the parts sent
    "p0_phases_s": {"gmsh_coarse": 0.7, "refinement": 0.38, "interface_insertion": 1.5,
                    "decomposition": 2.35, "mesh_kept": 1.16, "parts_sent": 0.4},
    "p0_mesh_bytes_per_tet": 380,   # the whole mesh after insertion on process 0
    "p0_maps_bytes_per_tet": 250,   # the decomposition's maps and contact zones on process 0
    "label_s": 0.165,               # a fragment labelling (0.15 - 0.18 s)
    "label_gathered_bytes": 128,    # to process 0, intact
    "checkpoint_s": 8.8,
    "checkpoint_bytes": 895e6,
    "cut_s": 27.1,                  # every element moved (the test hook)
    "state_bytes_per_tet": 930,     # the whole state a cut gathers on process 0
    # the device's Views per tetrahedron, intact (one thread, which since 2026-12-07 holds no scatter
    # copy: the same as a GPU's; one process, summary.json memory.views; thirty-second session)
    "views_bytes_per_tet": 1204,
    # each process's peak resident memory (0.895 GB for 481 344; 2026-12-07, thirty-second session)
    "peak_bytes_per_own_tet": 1860,
    # each process's local set-up (summary.json's local_parts with local_sizes, local_part and
    # local_whole_facts: its coarse elements refined, its neighbourhood refined with its interfaces,
    # the part cut, the whole mesh's facts summed), per own tetrahedron: the median of four runs of
    # 10 255 360 tetrahedra on 2 processes (2026-12-08, thirty-third session), with huge pages
    # (docs/parallel.md, "1e7 tetrahedra on this machine": the slower process's 15.9, 11.4, 9.1,
    # 8.9 s for 5 127 680 own)
    "local_part_s_per_own_tet": 10.24 / 5127680,
    # process 0 building the whole mesh from the coarse one (a local set-up's first cut; 2026-12-08,
    # fdem run on 2 processes with FDEM_TEST_RECUT=20, summary.json processes.setup_phase_wall_seconds
    # `whole_mesh_rebuilt`, 0.94 s; docs/parallel.md, "The part's mesh let go"), per tetrahedron
    "rebuild_s_per_tet": 0.94 / 962688,
}

# Assumptions (none measured here): the machines of the target.
GPU = {"name": "H200 GPUs (4.8 TB/s, 8 a node)", "bytes_per_tet_step": 840, "bandwidth": 4.8e12,
       "pcie": 25e9, "memory": 141e9}
CPU = {"name": "CPU nodes (64 cores each)", "cores": 64, "efficiency": 0.7, "memory": 512e9}
FILESYSTEM_BPS = 100e9   # a parallel file system's aggregate write rate
GMSH_S_PER_TET = 33.4 / 708314  # Gmsh's 3D meshing on one thread here (docs/case-format.md, mesh.refine)


def from_runs(plain, checkpoint, cut):
    """The measured inputs from three run folders (see the module's docstring)."""
    m = dict(MEASURED)
    s = json.load(open(os.path.join(plain, "summary.json")))
    m["tetrahedra"] = s["counts"]["elements"]
    m["processes"] = s["processes"]["count"]
    m["step_s"] = s["loop_wall_seconds"] / max(1, s["steps"])
    m["peak_bytes_per_own_tet"] = max(s["processes"]["peak_rss_bytes"]) / (m["tetrahedra"] / m["processes"])
    m["setup_s"] = max(s["processes"]["setup_wall_seconds"])
    phases = {p["name"]: p["wall_seconds"] for p in s["setup"]["phases"]}
    gmsh = sum(v for k, v in phases.items() if k.startswith("gmsh"))
    m["p0_phases_s"] = {"gmsh_coarse": gmsh, **{k: phases.get(k, 0.0) for k in
                        ("refinement", "interface_insertion", "decomposition", "mesh_kept", "parts_sent")}}
    rss = {p["name"]: p["rss_bytes"] for p in s["setup"]["phases"]}
    n = m["tetrahedra"]
    m["p0_mesh_bytes_per_tet"] = (rss.get("interface_insertion", 0) - rss.get("renumbering", 0)) / n
    m["p0_maps_bytes_per_tet"] = (rss.get("decomposition", 0) - rss.get("interface_insertion", 0)) / n
    lab = s["fragment_labelling"]
    m["label_s"] = lab["wall_seconds"] / max(1, lab["count"])
    m["label_gathered_bytes"] = lab["gathered_bytes_last"]
    c = json.load(open(os.path.join(checkpoint, "summary.json")))["checkpoint"]
    m["checkpoint_s"] = c["write_seconds"] / max(1, c["written"])
    m["checkpoint_bytes"] = os.path.getsize(c["file"])
    k = json.load(open(os.path.join(cut, "summary.json")))["processes"]
    m["cut_s"] = k["cut_seconds"] / max(1, k["contact_recuts"])
    return m


def fmt_time(t):
    return (f"{1e3 * t:.1f} ms" if t < 1 else f"{t:.1f} s" if t < 10 else f"{t:.0f} s" if t < 600
            else f"{t / 3600:.1f} h")


def model(m, total, procs, refine):
    """Each term for `total` tetrahedra on `procs` GPUs and on `procs` CPU nodes, the coarse mesh
    refined `refine` times."""
    per = total / procs
    per_tet_thread = m["step_s"] / (m["tetrahedra"] / m["processes"])  # s per tetrahedron-step, one thread
    cpu_threads = CPU["cores"] * CPU["efficiency"]
    ph = m["p0_phases_s"]
    n = m["tetrahedra"]
    serial_per_tet = sum(v for k, v in ph.items() if k != "gmsh_coarse") / n
    coarse = total / 8 ** refine  # the coarse mesh Gmsh makes, refined `refine` times
    local_per_tet = m["local_part_s_per_own_tet"]  # what each process does (measured, local_part)
    # each process's own set-up after its part arrives (the model, contact, outputs): the set-up's
    # wall time less process 0's serial phases, per own tetrahedron
    own_per_tet = max(0.0, m["setup_s"] - sum(ph.values())) / (n / m["processes"])
    rows = []
    rows.append(("step (intact)", fmt_time(per * GPU['bytes_per_tet_step'] / GPU['bandwidth']),
                 fmt_time(per * per_tet_thread / cpu_threads), fmt_time(per * per_tet_thread),
                 "GPU: the force pass's compulsory bytes at the memory bandwidth (docs/performance.md section 10); "
                 f"CPU: this core's {1e9 * per_tet_thread:.0f} ns per tetrahedron-step on {CPU['cores']} cores at "
                 f"efficiency {CPU['efficiency']}"))
    label_dev = per * 16 / GPU["pcie"]  # the node labels copied to the host, 4 B a node, 4 nodes a tetrahedron
    rows.append(("fragment labelling", fmt_time(label_dev + per * 76 / GPU['bandwidth']) + " + join",
                 fmt_time(per * (m['label_s'] / (n / m['processes'])) / cpu_threads) + " + join",
                 fmt_time(per * (m['label_s'] / (n / m['processes']))) + " + join",
                 f"each process its part (measured {m['label_s']:.3f} s per {n / m['processes']:.0f} tetrahedra, one "
                 f"thread); process 0 joins {m['label_gathered_bytes']:.0f} B per process intact "
                 f"({procs * m['label_gathered_bytes'] / 1e3:.0f} kB); GPU: the node labels to the host over PCIe and "
                 "one pass over the labelling's 76 B per tetrahedron at the bandwidth (its rounds not counted: "
                 "a lower bound)"))
    ck_bytes = total * m["checkpoint_bytes"] / n
    here_bps = m["checkpoint_bytes"] / m["checkpoint_s"]
    rows.append(("checkpoint", fmt_time(ck_bytes / FILESYSTEM_BPS), fmt_time(ck_bytes / FILESYSTEM_BPS),
                 fmt_time(ck_bytes / here_bps),
                 f"{ck_bytes / 1e9:.0f} GB ({m['checkpoint_bytes'] / n:.0f} B per tetrahedron) at an assumed "
                 f"{FILESYSTEM_BPS / 1e9:.0f} GB/s parallel file system; here the {here_bps / 1e6:.0f} MB/s measured"))
    setup_today = coarse * GMSH_S_PER_TET + total * serial_per_tet + per * own_per_tet
    p0_mem = total * (m["p0_mesh_bytes_per_tet"] + m["p0_maps_bytes_per_tet"])
    fits = "fits" if p0_mem < min(GPU["memory"] * 8, CPU["memory"]) else "does not fit a node"
    rows.append(("set-up, whole (process 0: a case not refined, FDEM_WHOLE_SETUP=1)", fmt_time(setup_today), fmt_time(setup_today), fmt_time(setup_today),
                 f"Gmsh's coarse mesh ({coarse:.2e} tetrahedra at {1e6 * GMSH_S_PER_TET:.0f} us each), then refinement, "
                 f"insertion, decomposition, the kept mesh and the parts sent at {1e6 * serial_per_tet:.1f} us per "
                 f"tetrahedron on process 0, then each part's own set-up ({1e6 * own_per_tet:.1f} us per own "
                 f"tetrahedron); process 0's memory {p0_mem / 1e9:.0f} GB ({fits})"))
    setup_local = coarse * GMSH_S_PER_TET + per * (local_per_tet + own_per_tet)
    rebuild = total * m["rebuild_s_per_tet"]
    rows.append(("set-up, local (fdem run today)", fmt_time(setup_local), fmt_time(setup_local),
                 fmt_time(setup_local),
                 f"the coarse mesh on process 0, then each process builds its part from its coarse elements and "
                 f"their halo (local_parts: {1e6 * local_per_tet:.1f} us per own tetrahedron, the median of four runs of "
                 f"1e7 on this machine with huge pages) and sets its part up; no process holds the whole mesh (its hash, report and the "
                 f"snapshots' /mesh come from every process's rows)"))
    views = per * m["views_bytes_per_tet"]
    rows.append(("memory per process (intact)", f"{views / 1e9:.0f} GB of {GPU['memory'] / 1e9:.0f}",
                 f"{views / 1e9:.0f} GB of {CPU['memory'] / 1e9:.0f}",
                 f"{per * m['peak_bytes_per_own_tet'] / 1e9:.1f} GB a process (the measured peak, "
                 f"{m['peak_bytes_per_own_tet']:.0f} B per own tetrahedron)",
                 f"the Views' {m['views_bytes_per_tet']:.0f} B per tetrahedron (docs/parallel.md); a fragmenting "
                 "run's contact lists grow about 2.5 times"))
    cut_today = total * m["cut_s"] / n
    state = total * m["state_bytes_per_tet"]
    rows.append(("a cut today (process 0)", fmt_time(cut_today), fmt_time(cut_today), fmt_time(cut_today),
                 f"the whole state ({state / 1e9:.0f} GB) gathered on process 0 and broadcast "
                 f"({1e6 * m['cut_s'] / n:.0f} us per tetrahedron measured), and at a locally set-up run's first "
                 f"cut the whole mesh built there from the coarse one ({1e6 * m['rebuild_s_per_tet']:.1f} us per "
                 f"tetrahedron, {fmt_time(rebuild)}): a run this size must not cut (a contact zone wide enough for the run) "
                 "until the distributed cut exists"))
    return per, rows


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--inputs", help="a JSON file of measured inputs (the keys of MEASURED)")
    ap.add_argument("--runs", nargs=3, metavar=("PLAIN", "CHECKPOINT", "CUT"))
    ap.add_argument("--total", type=float, default=1e9)
    ap.add_argument("--procs", type=int, default=64)
    ap.add_argument("--refine", type=int, default=3, help="mesh.refine: the coarse mesh has total / 8^k tetrahedra")
    ap.add_argument("--json", help="write the inputs and the rows here")
    a = ap.parse_args()
    m = dict(MEASURED)
    if a.inputs:
        m.update(json.load(open(a.inputs)))
    if a.runs:
        m = from_runs(*a.runs)
    per, rows = model(m, a.total, a.procs, a.refine)
    print(f"{a.total:.0e} tetrahedra (a coarse mesh refined {a.refine} times) on {a.procs} processes ({per:.3g} each); GPU: {GPU['name']}; CPU: {CPU['name']}\n")
    print("| term | per GPU | per CPU node | this machine, one thread a process | from |")
    print("|---|---|---|---|---|")
    for r in rows:
        print("| " + " | ".join(r) + " |")
    if a.json:
        json.dump({"inputs": m, "gpu": GPU, "cpu": CPU, "filesystem_bps": FILESYSTEM_BPS, "total": a.total,
                   "procs": a.procs, "refine": a.refine, "rows": rows}, open(a.json, "w"), indent=1)


if __name__ == "__main__":
    main()
