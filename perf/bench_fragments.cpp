// Cost of one fragment analysis (kernels/fragments.hpp) on a box of tetrahedra with interfaces
// everywhere: intact, with a random 30 % of the interfaces failed, and with all failed.
//   build/openmp/perf/bench_fragments [cells per side, default 30: 162 thousand tetrahedra]
#include <chrono>
#include <cstdio>
#include <cstdlib>

#include "mesh/mesh.hpp"
#include "solver/fragment_analysis.hpp"
#include "solver/simulation.hpp"

using namespace fdem;

int main(int argc, char** argv) {
  Kokkos::ScopeGuard guard(argc, argv);
  const int n = argc > 1 ? std::atoi(argv[1]) : 30;
  HostMesh mesh = generate_box({0, 0, 0}, {1, 1, 1}, n, n, n);
  reorder_for_locality(mesh);
  insert_interfaces(mesh, {true});
  Case c;
  c.dim = 3;
  c.materials = {BulkMaterial{"rock", 2700, 33e9, 0.25}};
  c.region_material = {{"body", 0}};
  InterfaceMaterial im;
  im.kn = 1e13;
  im.ks = 4e12;
  im.ft = im.c = 1e6;
  im.Gnc = im.Gsc = 10;
  c.interface_materials = {im};
  c.fracture_material = 0;
  c.end_time = 1;
  Simulation<3> sim(c, mesh);
  FragmentAnalysis<3> fa(sim.m);
  auto h = Kokkos::create_mirror_view(sim.m.ihist);
  unsigned seed = 1;
  for (double pfail : {0.0, 0.3, 1.0}) {
    for (int q = 0; q < sim.m.ni; ++q) {
      seed = seed * 1664525u + 1013904223u;
      const bool f = (seed >> 8) * (1.0 / 16777216.0) < pfail;
      for (int k = 0; k < 3; ++k) {
        h(q, k, 0) = f ? 3e-6 : 0;
        h(q, k, 1) = f ? 1e-6 : 0;
        h(q, k, 2) = f ? 2e-6 : 0;
        h(q, k, 3) = 0;
      }
    }
    Kokkos::deep_copy(sim.m.ihist, h);
    fa.compute(sim.m);  // warm-up
    const int reps = 5;
    const auto t0 = std::chrono::steady_clock::now();
    FragmentStats s;
    for (int r = 0; r < reps; ++r) s = fa.compute(sim.m);
    const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / reps;
    std::printf("%d tets, %d interfaces, %.0f %% failed: %d fragments, %d rounds, %.3f s per analysis (%.1f ns per tet)\n",
                sim.m.ne, sim.m.ni, 100 * pfail, s.count, s.rounds, dt, 1e9 * dt / sim.m.ne);
  }
  return 0;
}
