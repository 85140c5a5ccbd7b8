// The local set-up of a refined case (src/parallel/local_part.hpp, issue 49) against today's path,
// one process: the coarse mesh as `fdem run` makes it (Gmsh or a generator, renumbered), its
// partition into P parts (METIS where the build has it, else coordinate bisection), then for each
// part p (or only --part p) the time and the neighbourhood of local_part, and the peak resident
// memory of this process at the end. With --whole, first today's path on the same process: the
// whole refinement, interface insertion and PartBuilder's part p.
//   build/openmp/perf/bench_local_part CASE [--set KEY=VALUE ...] --parts P [--part p] [--whole]
// A part's own peak memory: one run per part with --part p (each a fresh process).
#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "io/case.hpp"
#include "mesh/mesh.hpp"
#include "mesh/refine.hpp"
#include "parallel/decompose.hpp"
#include "parallel/local_part.hpp"
#include "parallel/partition.hpp"
#include "solver/simulation.hpp"

using namespace fdem;

namespace {

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

double peak_mb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss / 1024.0;
}

}  // namespace

int main(int argc, char** argv) {
  Kokkos::ScopeGuard guard(argc, argv);
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_local_part CASE [--set KEY=VALUE ...] --parts P [--part p] [--whole]\n");
    return 2;
  }
  std::vector<std::string> sets;
  int parts = 2, only = -1;
  bool whole = false;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--set" && i + 1 < argc) sets.push_back(argv[++i]);
    else if (a == "--parts" && i + 1 < argc) parts = std::atoi(argv[++i]);
    else if (a == "--part" && i + 1 < argc) only = std::atoi(argv[++i]);
    else if (a == "--whole") whole = true;
    else {
      std::fprintf(stderr, "bench_local_part: unknown argument '%s'\n", a.c_str());
      return 2;
    }
  }
  try {
    const Case c = load_case(argv[1], sets);
    const int k = c.mesh.refine;
    if (k < 1) throw InputError("bench_local_part: the case needs mesh.refine >= 1");
    double t0 = now();
    HostMesh coarse = build_mesh(c.mesh, c.dim);
    reorder_for_locality(coarse);
    const double t_mesh = now() - t0;
    t0 = now();
    const std::vector<CurvedSurface> surf = curved_surfaces(c.mesh, c.dim);
    const CoarseTopology topo = coarse_topology(coarse, k, surf);
    const std::vector<std::int64_t> off = refined_interface_offsets(coarse, topo);
    const PartitionMethod method = partition_has_metis() ? PartitionMethod::Metis : PartitionMethod::Rcb;
    const std::vector<int> cpart = partition_elements(coarse, parts, method);
    const double t_coarse = now() - t0;
    const long fine = static_cast<long>(coarse.num_elems() * refine_factor(c.dim, k) + 0.5);
    std::printf("coarse mesh: %d elements (%.2f s, Gmsh or the generator); topology, offsets and %s partition into %d: "
                "%.3f s; fine mesh: %ld elements, %lld interfaces\n",
                coarse.num_elems(), t_mesh, partition_method_name(method), parts, t_coarse, fine,
                static_cast<long long>(off.back()));
    const MeshQuality mq = mesh_quality(coarse);
    // the contact zone's reach of a run (src/solver/run_processes.cpp): dpen + skin + zone, about 1.1 fine
    // mean sizes at the defaults; here 1.2 coarse mean sizes / 2^k
    const double reach = c.contact.enabled != 0 ? 1.2 * mq.mean_size / (1 << k) : 0.0;
    if (whole) {
      t0 = now();
      HostMesh w = refine_mesh(coarse, k, surf);
      insert_interfaces(w, std::vector<bool>(w.region_names.size(), true));
      const double t_ins = now() - t0;
      t0 = now();
      std::vector<int> fpart(w.num_elems());
      const int children = static_cast<int>(refine_factor(c.dim, k) + 0.5);
      for (int e = 0; e < w.num_elems(); ++e) fpart[e] = cpart[e / children];
      PartBuilder b(w, fpart, parts, reach);
      const double t_tables = now() - t0;
      t0 = now();
      const SubMesh s = b.part(only >= 0 ? only : 0);
      std::printf("whole path: refinement and insertion %.2f s, decomposition tables %.2f s, part %d %.2f s "
                  "(%d elements); peak %.0f MB\n",
                  t_ins, t_tables, only >= 0 ? only : 0, now() - t0, s.mesh.num_elems(), peak_mb());
    }
    for (int p = 0; p < parts; ++p) {
      if (only >= 0 && p != only) continue;
      t0 = now();
      LocalPartStats st;
      const SubMesh s = local_part(coarse, topo, off, cpart, parts, p, reach, WholeFacts{}, &st);
      const double t = now() - t0;
      std::printf("part %d: local_part %.2f s (halo %.2f, refinement and insertion %.2f, cut %.2f; %.2f us per own element); own %d, held %d elements; refined %ld coarse "
                  "-> %ld fine elements (%.2f per held), %d ring(s); contact reach %.3g m; peak %.0f MB (%.0f B per "
                  "own element)\n",
                  p, t, st.halo_seconds, st.refine_seconds, st.cut_seconds, 1e6 * t / s.mesh.owned_elems, s.mesh.owned_elems, s.mesh.num_elems(), st.coarse_elems,
                  st.fine_elems, static_cast<double>(st.fine_elems) / s.mesh.num_elems(), st.rings, reach, peak_mb(),
                  peak_mb() * 1048576.0 / s.mesh.owned_elems);
    }
  } catch (const InputError& e) {
    std::fprintf(stderr, "bench_local_part: %s\n", e.what());
    return 2;
  }
  return 0;
}
