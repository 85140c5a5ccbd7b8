#!/usr/bin/env python3
"""scripts/cuda_resources.py on a recorded ptxas report (tests/data/cuda/ptxas_sample.log: three
kernels of the project and one of Kokkos' own, from an sm_90 build): the kernels' names, registers,
spills, occupancy at 128 threads per block (the CUDA occupancy calculator's rule for an H100),
functor passing and objects, the Kokkos kernel left out, and --check failing on the spilling one;
and a kernel that spills only at the call of an out-of-line member counted apart.
ctest runs it (CudaResources.ReadsPtxasReport)."""
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCRIPT = os.path.join(ROOT, "scripts", "cuda_resources.py")
LOG = os.path.join(ROOT, "tests", "data", "cuda", "ptxas_sample.log")

sys.path.insert(0, os.path.join(ROOT, "scripts"))
import cuda_resources  # noqa: E402

failures = []


def check(cond, what):
    if not cond:
        failures.append(what)


# occupancy at 128 threads per block: 65536 registers, 64 warps per multiprocessor, registers
# allocated per warp in units of 256, warps in units of 4
for regs, occ in ((32, 1.0), (64, 0.5), (79, 0.375), (128, 0.25), (168, 0.1875), (208, 0.125), (255, 0.125)):
    check(abs(cuda_resources.occupancy(regs) - occ) < 1e-12, "occupancy(%d) = %g, not %g" % (
        regs, cuda_resources.occupancy(regs), occ))

with tempfile.TemporaryDirectory() as tmp:
    js, md = os.path.join(tmp, "r.json"), os.path.join(tmp, "r.md")
    r = subprocess.run([sys.executable, SCRIPT, LOG, "--json", js, "--md", md], capture_output=True, text=True)
    check(r.returncode == 0, "exit status %d without --check: %s" % (r.returncode, r.stderr))
    rows = {x["kernel"]: x for x in json.load(open(js))["rows"]}
    check(len(rows) == 3, "3 kernels of the project, not %d: %s" % (len(rows), sorted(rows)))
    lean = rows.get("fdem::ChunkForceKernel<fdem::LeanInterfaceForces<3, false, false>, 3>", {})
    check(lean.get("registers") == 127 and lean.get("spill_store_bytes") == 0 and lean.get("launch") == "constant",
          "interface kernel: %s" % lean)
    bulk = rows.get("fdem::ChunkForceKernel<fdem::BulkForces<3>, 3>", {})
    check(bulk.get("registers") == 79 and bulk.get("launch") == "local" and bulk.get("objects") == ["contact_system"],
          "bulk kernel: %s" % bulk)
    seed = rows.get("fdem::ContactForcesFn<3, true, 48, 2>", {})
    check(seed.get("closure") == "ParallelReduce" and seed.get("spill_store_bytes") == 74 and
          seed.get("spill_load_bytes") == 72 and seed.get("stack_bytes") == 496, "narrow phase: %s" % seed)
    text = open(md).read()
    check("| 79 | 37.5 % |" in text, "the table's bulk row")
    r = subprocess.run([sys.executable, SCRIPT, LOG, "--check"], capture_output=True, text=True)
    check(r.returncode == 1 and "ContactForcesFn<3, true, 48, 2>" in r.stdout,
          "--check: exit %d, %s" % (r.returncode, r.stdout))

# a kernel that spills only where it calls an out-of-line member (tests/data/cuda/ptxas_out_of_line.log:
# the 3D interface kernel with residual friction and its friction_step, from an sm_90 build): counted
# apart, not failing --check, and the callee listed with its own figures
OOL = os.path.join(ROOT, "tests", "data", "cuda", "ptxas_out_of_line.log")
with tempfile.TemporaryDirectory() as tmp:
    md = os.path.join(tmp, "r.md")
    r = subprocess.run([sys.executable, SCRIPT, OOL, "--md", md, "--check"], capture_output=True, text=True)
    check(r.returncode == 0 and "1 spilling at an out-of-line call" in r.stdout,
          "out-of-line call: exit %d, %s %s" % (r.returncode, r.stdout, r.stderr))
    text = open(md).read()
    check("| `fdem::LeanInterfaceForces<3, false, true>::friction_step` | 0 | 32 / 24 |" in text,
          "the out-of-line table's friction_step row")
    check("0 above 128 registers or spilling; 1 spilling only at the call" in text, "the table's count line")
    ool = cuda_resources.out_of_line(open(OOL).read())
    check(len(ool) == 2, "two out-of-line functions (friction_step, fail), not %d" % len(ool))

for f in failures:
    print("FAIL:", f)
print("cuda_resources: %d checks failed" % len(failures) if failures else "cuda_resources: all checks hold")
sys.exit(1 if failures else 0)
