#!/usr/bin/env python3
"""The device resources of every kernel in a CUDA build: registers, spills, stack, how Kokkos
passes the functor (kernel argument below 512 bytes, else a copy to constant memory before each
launch) with its size, and the theoretical occupancy at 128 threads per block. Read from the
build log of a CUDA build with ptxas' report (-DFDEM_CUDA_RESOURCE_REPORT=ON, -Xptxas=-v; no GPU
needed), built with make's --output-sync so that each object's lines stay together.

    scripts/cuda_resources.py BUILD_LOG [--store DIR] [--md FILE] [--json FILE] [--check] [--title TEXT]

--store keeps each object's report in DIR (replacing the object's earlier one) and reads the table
from all of them, so that an incremental build's log, which holds only the recompiled objects,
still gives every kernel.

--md writes the table (docs/cuda_resources.md), --json the rows; --check exits 1 when a kernel of
the project holds more than 128 registers or spills (docs/cuda.md, "Kernel resources"). Kernels
are named by their functor: a class (fdem::ForceKernel<3, false, false>) or, for a lambda, the
function that holds it and the lambda's number there.
"""
import argparse
import json
import os
import re
import subprocess
import sys

# sm_90 (H100 / H200): per multiprocessor
REGS_PER_SM = 65536
MAX_WARPS = 64
MAX_BLOCKS = 32
REG_GRANULE = 256  # registers are allocated per warp in units of 256
WARP_GRANULE = 4
BLOCK = 128
CONSTANT_THRESHOLD = 512  # Kokkos: a functor of 512 B or more is copied to constant memory


def occupancy(regs, block=BLOCK):
    """Theoretical occupancy (0..1) at `block` threads per block limited by registers."""
    warps_per_block = (block + 31) // 32
    per_warp = -(-max(regs, 1) * 32 // REG_GRANULE) * REG_GRANULE
    warps = (REGS_PER_SM // per_warp) // WARP_GRANULE * WARP_GRANULE
    blocks = min(warps // warps_per_block, MAX_BLOCKS, MAX_WARPS // warps_per_block)
    return blocks * warps_per_block / MAX_WARPS


def demangle(names):
    if not names:
        return []
    out = subprocess.run(["c++filt"], input="\n".join(names), capture_output=True, text=True, check=True)
    return out.stdout.split("\n")[: len(names)]


def top_args(s):
    """Splits the template argument list s (without the outer <>) at its top-level commas."""
    parts, depth, cur = [], 0, []
    for ch in s:
        if ch in "<(":
            depth += 1
        elif ch in ">)":
            depth -= 1
        if ch == "," and depth == 0:
            parts.append("".join(cur).strip())
            cur = []
        else:
            cur.append(ch)
    if cur:
        parts.append("".join(cur).strip())
    return parts


def inner(s, start):
    """The text between the '<' at s[start] and its matching '>'."""
    depth = 0
    for i in range(start, len(s)):
        if s[i] == "<":
            depth += 1
        elif s[i] == ">":
            depth -= 1
            if depth == 0:
                return s[start + 1 : i]
    return s[start + 1 :]


def kernel_name(dem):
    """(mechanism, closure, functor name, exec policy) of a Kokkos kernel's demangled name."""
    m = re.search(r"cuda_parallel_launch_(local|constant|global)_memory<", dem)
    if not m:
        return None, None, dem, ""
    mech = m.group(1)
    driver = inner(dem, m.end() - 1)
    m2 = re.match(r"Kokkos::Impl::(ParallelFor|ParallelReduce|ParallelScan\w*)<", driver)
    if not m2:
        return mech, "", driver, ""
    args = top_args(inner(driver, m2.end() - 1))
    closure = m2.group(1)
    functor = args[0] if args else driver
    if closure == "ParallelReduce" and functor.startswith("Kokkos::Impl::CombinedFunctorReducer<"):
        functor = top_args(inner(functor, len("Kokkos::Impl::CombinedFunctorReducer")))[0]
    policy = args[1] if len(args) > 1 else ""
    tag = re.search(r"__nv_dl_tag<[^&]*&([\w:]+(?:<[^>]*>)?)\s*,\s*(\d+)u?>", functor)
    if tag:
        functor = "lambda %s in %s" % (tag.group(2), tag.group(1))
    elif "{lambda" in functor:
        lm = re.search(r"([\w:<>, ]+?)\([^()]*\)(?: const)?::\{lambda\([^)]*\)#(\d+)\}", functor)
        if lm:
            functor = "lambda %s in %s" % (lm.group(2), lm.group(1).strip())
    policy = "Team" if "TeamPolicy" in policy else ("MDRange" if "MDRangePolicy" in policy else "Range")
    return mech, closure, functor, policy


def split_by_object(log):
    """{object: its lines} of a build log (each from its 'Building CXX object' line on)."""
    out, obj, cur = {}, None, []
    for line in log.splitlines():
        m = re.search(r"Building CXX object (\S+)", line)
        if m:
            if obj:
                out[obj] = "\n".join(cur) + "\n"
            obj, cur = m.group(1), []
        if obj:
            cur.append(line)
    if obj:
        out[obj] = "\n".join(cur) + "\n"
    return out


def resources(log):
    """[(object, mangled, regs, stack, spill_stores, spill_loads)] of the kernels in a build log."""
    rows = []
    obj, name, props = "", None, None
    for line in log.splitlines():
        m = re.search(r"Building CXX object (\S+)", line)
        if m:
            obj = m.group(1)
            continue
        m = re.search(r"Compiling entry function '(\S+)' for '(sm_\d+a?)'", line)
        if m:
            name, props = m.group(1), None
            continue
        m = re.search(r"(\d+) bytes stack frame, (\d+) bytes spill stores, (\d+) bytes spill loads", line)
        if m and name:
            props = tuple(int(g) for g in m.groups())
            continue
        m = re.search(r"Used (\d+) registers", line)
        if m and name:
            stack, st, ld = props or (0, 0, 0)
            rows.append((obj, name, int(m.group(1)), stack, st, ld))
            name = None
    return rows


def out_of_line(log):
    """{mangled: (stack, spill_stores, spill_loads)} of the project's device functions that ptxas
    compiled out of line (FDEM_NOINLINE: rare branches called from kernels), the largest figures
    seen for each."""
    out, name = {}, None
    for line in log.splitlines():
        m = re.search(r"Function properties for (\S+)", line)
        if m:
            name = m.group(1) if "4fdem" in m.group(1) and "cuda_parallel_launch" not in m.group(1) else None
            continue
        m = re.search(r"(\d+) bytes stack frame, (\d+) bytes spill stores, (\d+) bytes spill loads", line)
        if m and name:
            v = tuple(int(g) for g in m.groups())
            out[name] = tuple(max(a, b) for a, b in zip(out.get(name, v), v))
            name = None
    return out


def layout_report(root):
    """The Views declared in kernels/ and src/: explicit layouts, and element types that are
    structures (an array of structures: consecutive threads read strided addresses)."""
    explicit, structs, total = [], {}, 0
    scalar = re.compile(r"^(const )?(double|float|int|long|long long|unsigned|unsigned char|char|bool|"
                        r"int8_t|uint8_t|int64_t|uint64_t|size_t)\b")
    for sub in ("kernels", "src"):
        for dirpath, _, files in os.walk(os.path.join(root, sub)):
            for fn in files:
                if not fn.endswith((".hpp", ".cpp")):
                    continue
                path = os.path.join(dirpath, fn)
                with open(path, errors="replace") as f:
                    text = f.read()
                for m in re.finditer(r"Kokkos::View<([^;{}()]*?)>\s+\w", text):
                    total += 1
                    args = m.group(1)
                    if "Layout" in args:
                        explicit.append("%s: View<%s>" % (os.path.relpath(path, root), args))
                    elem = args.split(",")[0].strip()
                    if not scalar.match(elem):
                        structs.setdefault(re.sub(r"[*\[\] ]+$", "", elem), set()).add(os.path.relpath(path, root))
    return total, explicit, structs


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("log")
    ap.add_argument("--title", default="")
    ap.add_argument("--store")
    ap.add_argument("--md")
    ap.add_argument("--json")
    ap.add_argument("--check", action="store_true")
    a = ap.parse_args()
    with open(a.log, errors="replace") as f:
        log = f.read()
    if a.store:
        os.makedirs(a.store, exist_ok=True)
        for obj, text in split_by_object(log).items():
            with open(os.path.join(a.store, obj.replace("/", "__") + ".txt"), "w") as f:
                f.write(text)
        log = ""
        for name in sorted(os.listdir(a.store)):
            with open(os.path.join(a.store, name)) as f:
                log += f.read()
    raw = resources(log)
    if not raw:
        sys.exit("cuda_resources: no ptxas report in %s (build with -DFDEM_CUDA_RESOURCE_REPORT=ON: scripts/cuda_check)"
                 % a.log)
    dem = demangle([r[1] for r in raw])
    seen = {}
    for (obj, mangled, regs, stack, spill_st, spill_ld), d in zip(raw, dem):
        mech, closure, functor, policy = kernel_name(d)
        if mech is None or "fdem::" not in d:
            continue  # a device function, or one of Kokkos' own kernels
        key = (functor, closure, policy, regs, spill_st)
        row = seen.setdefault(key, dict(kernel=functor, closure=closure, policy=policy, registers=regs,
                                         spill_store_bytes=spill_st, spill_load_bytes=spill_ld, stack_bytes=stack,
                                         launch=mech, occupancy=occupancy(regs), objects=[]))
        tu = re.sub(r"\.cpp\.o$|\.o$", "", obj.split("/")[-1])
        if tu and tu not in row["objects"]:
            row["objects"].append(tu)
    rows = sorted(seen.values(), key=lambda r: (-r["registers"], r["kernel"]))
    ool = out_of_line(log)
    ool_dem = [re.sub(r"\(.*$", "", d) for d in demangle(sorted(ool))]
    owners = {d.rsplit("::", 1)[0] for d in ool_dem}  # the functors with out-of-line members

    def calls_out(r):  # the kernel's functor (or the one it wraps) has an out-of-line member
        return any(o in r["kernel"] for o in owners)

    # a kernel that calls an out-of-line branch saves the registers live across the call: spills
    # there are counted apart (docs/cuda.md, "Kernel resources": measured with the call stubbed)
    at_call = [r for r in rows if r["registers"] <= 128 and r["spill_store_bytes"] > 0 and calls_out(r)]
    bad = [r for r in rows if r["registers"] > 128 or (r["spill_store_bytes"] > 0 and r not in at_call)]
    if a.json:
        with open(a.json, "w") as f:
            json.dump(dict(block=BLOCK, rows=rows), f, indent=1)
    if a.md:
        lines = [
            "# Kernel resources (CUDA, sm_90)%s" % (": " + a.title if a.title else ""),
            "",
            "Generated by `scripts/cuda_check` from ptxas' report on every kernel of the CUDA build",
            "(`scripts/cuda_resources.py build/cuda.build.log --md ...`); docs/cuda.md says how to read it.",
            "Occupancy: theoretical, at %d threads per block, limited by registers (H100/H200: %d registers" % (BLOCK, REGS_PER_SM),
            "and %d warps per multiprocessor). Functor: `argument` below %d B (passed with the launch)," % (MAX_WARPS, CONSTANT_THRESHOLD),
            "`constant memory` from %d B on (Kokkos copies it there before each launch)." % CONSTANT_THRESHOLD,
            "",
            "%d kernels; %d above 128 registers or spilling; %d spilling only at the call of an out-of-line "
            "branch (below)." % (len(rows), len(bad), len(at_call)),
            "",
            "| kernel | pattern | registers | occupancy | spill stores / loads B | stack B | functor | in |",
            "|---|---|---|---|---|---|---|---|",
        ]
        for r in rows:
            fb = {"local": "argument", "constant": "constant memory", "global": "global memory"}[r["launch"]]
            lines.append("| `%s` | %s %s | %d | %.1f %% | %d / %d | %d | %s | %s |" % (
                r["kernel"].replace("|", "\\|"), r["closure"], r["policy"], r["registers"], 100 * r["occupancy"],
                r["spill_store_bytes"], r["spill_load_bytes"], r["stack_bytes"], fb,
                ", ".join(sorted(r["objects"]))[:80]))
        if ool:
            names = sorted(ool)
            lines += ["", "## Out-of-line device functions", "",
                      "Branches that the kernels above call rather than inline (`FDEM_NOINLINE`, "
                      "`kernels/fdem_kokkos.hpp`): rare ones, whose registers would otherwise add to their kernel's "
                      "common path. A call costs the caller the registers live across it (saved, in the caller's "
                      "spill figure) and the callee the registers it must preserve (its spill figure): both only "
                      "when the branch is taken.", "",
                      "| function | stack B | spill stores / loads B |", "|---|---|---|"]
            for n, d in zip(names, demangle(names)):
                d = re.sub(r"\(.*$", "", d)
                st, ss, sl = ool[n]
                lines.append("| `%s` | %d | %d / %d |" % (d.replace("|", "\\|"), st, ss, sl))
        total, explicit, structs = layout_report(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
        lines += ["", "## Layout", "",
                  "%d View declarations in kernels/ and src/ (member and local declarations); %d with an explicit "
                  "layout%s. Every other View has the default layout, LayoutLeft on CUDA: the item index first, "
                  "so that consecutive threads read consecutive addresses. Views of structures (each thread reads "
                  "a whole structure: strided unless all threads read the same entry):" % (
                      total, len(explicit), (": " + "; ".join(explicit)) if explicit else "")]
        lines += ["- `%s` (%s)" % (t, ", ".join(sorted(f))) for t, f in sorted(structs.items())]
        with open(a.md, "w") as f:
            f.write("\n".join(lines) + "\n")
    print("%d kernels; registers max %d; %d above 128 registers or spilling; %d spilling at an out-of-line call" % (
        len(rows), max((r["registers"] for r in rows), default=0), len(bad), len(at_call)))
    for r in at_call:
        print("  %4d regs %5d B spilled at an out-of-line call  %s (%s)" % (
            r["registers"], r["spill_store_bytes"], r["kernel"], r["closure"]))
    for r in bad:
        print("  %4d regs %5d B spilled  %s (%s)" % (r["registers"], r["spill_store_bytes"], r["kernel"], r["closure"]))
    if a.check and bad:
        sys.exit(1)


if __name__ == "__main__":
    main()
