// Cost of contact per step against the rest of the step (src/solver/contact_system.hpp).
//
//   bench_contact [cells2d=80] [cells3d=12] [steps=200]
//
// Scenes: a block with interfaces everywhere (2D: crossed rectangle cells x cells; 3D: box of
// cells^3 hexahedra, 6 tetrahedra each) resting on a fixed floor under gravity, rock-like
// material. For each dimension:
//   off         contact disabled (the step as without this feature)
//   intact      contact on, no interface failed: contact only watches for failures (the floor is a
//               second body, so the broad and narrow phases run for the block's outer boundary)
//   fragmented  contact on, every interface failed at the start: every element is a free piece
// It prints the median ns per step (whole step) and per contact update (timed separately, each
// after a step, on the state it left: interleaved, so both see the same machine load)
// and the rest of the step, with the contact statistics.
#include <Kokkos_Core.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "mesh/mesh.hpp"
#include "solver/simulation.hpp"
#include "tests/scenes.hpp"

namespace {

using namespace fdem;
using Clock = std::chrono::steady_clock;

Case make_case(int dim, double h, int contact) {
  Case c;
  c.file = "bench";
  c.name = "bench";
  c.dim = dim;
  c.materials = {BulkMaterial{"rock", 2700, 30e9, 0.25}};
  c.region_material = {{"block", 0}, {"floor", 0}};
  const double kn = 30e9 / (0.1 * h);
  c.interface_materials = {fdem_test::strong_interface(kn, kn / 2.5)};  // no failures during the run
  c.fracturable_regions = {"block"};
  c.fracture_material = 0;
  c.contact.enabled = contact;
  c.contact.friction = 0.5;
  VelocityBC fix;
  fix.set = "floor.all";
  fix.active = {true, true, true};
  c.velocity_bcs = {fix};
  c.gravity = {0, 0, 0};
  c.gravity[dim - 1] = -9.81;
  c.local_damping = 0.7;
  c.end_time = 1;
  return c;
}

template <int D>
HostMesh scene(int cells) {
  const double L = 1.0;
  HostMesh block, floor;
  if constexpr (D == 2) {
    block = generate_crossed_rectangle(0, 0, L, L, cells, cells, "block");
    floor = generate_crossed_rectangle(-0.25 * L, -0.1 * L, 1.5 * L, 0.1 * L, cells + cells / 2, 2, "floor");
  } else {
    block = generate_box({0, 0, 0}, {L, L, L}, cells, cells, cells, "block");
    floor = generate_box({-0.25 * L, -0.25 * L, -0.1 * L}, {1.5 * L, 1.5 * L, 0.1 * L}, cells + cells / 2,
                         cells + cells / 2, 1, "floor");
  }
  insert_interfaces(block, {true});
  HostMesh m = merge_meshes(floor, block, floor.region_names[0], block.region_names[0]);
  return m;
}

template <int D>
void run(int cells, int steps) {
  const HostMesh mesh = scene<D>(cells);
  const double h = 1.0 / cells;
  std::printf("%dD: %d elements, %d nodes, %d interfaces\n", D, mesh.num_elems(), mesh.num_nodes(),
              mesh.num_ifaces());
  for (const std::string mode : {"off", "intact", "fragmented"}) {
    Simulation<D> sim(make_case(D, h, mode == "off" ? 0 : 1), mesh);
    if (mode == "fragmented") fdem_test::fail_all_interfaces(sim);
    for (int s = 0; s < 50; ++s) sim.step();  // warm-up (first build, first contacts)
    Kokkos::fence();
    // interleaved: one step, then one contact update on the state it left (into the step's
    // scatter view, which the next step resets), `steps` times; medians of each
    ContactSystem<D>* ct = sim.contact();
    std::vector<double> ts, tc;
    for (int s = 0; s < steps; ++s) {
      auto t0 = Clock::now();
      sim.step();
      Kokkos::fence();
      ts.push_back(std::chrono::duration<double, std::nano>(Clock::now() - t0).count());
      if (ct) {
        t0 = Clock::now();
        ct->update(sim.m, sim.dt, sim.force_scatter());
        Kokkos::fence();
        tc.push_back(std::chrono::duration<double, std::nano>(Clock::now() - t0).count());
      }
    }
    auto median = [](std::vector<double> v) {
      if (v.empty()) return 0.0;
      std::sort(v.begin(), v.end());
      return v[v.size() / 2];
    };
    const double step_ns = median(ts), contact_ns = median(tc);
    // the rest is a difference of two medians: where contact is nearly all of the step it is
    // within their noise (a few %), and printed as such
    const double rest = step_ns - contact_ns;
    char rest_s[32];
    if (rest > 0.05 * step_ns) std::snprintf(rest_s, sizeof rest_s, "%12.0f ns", rest);
    else std::snprintf(rest_s, sizeof rest_s, "%15s", "< 5 % (noise)");
    std::printf("  %-10s  step %12.0f ns   contact %12.0f ns   rest %s   (contact %5.1f %%)", mode.c_str(),
                step_ns, contact_ns, rest_s, 100.0 * contact_ns / step_ns);
    if (ct)
      std::printf("   surface nodes %d, active faces %d, candidates %d, contacts %d, builds %ld",
                  ct->surface_nodes(), ct->active_faces(), ct->candidates(), ct->active_contacts(),
                  ct->builds());
    std::printf("\n");
  }
}

}  // namespace

int main(int argc, char** argv) {
  Kokkos::ScopeGuard guard(argc, argv);
  const int c2 = argc > 1 ? std::atoi(argv[1]) : 80;
  const int c3 = argc > 2 ? std::atoi(argv[2]) : 12;
  const int steps = argc > 3 ? std::atoi(argv[3]) : 200;
  std::printf("bench_contact: %s, concurrency %d\n", ExecSpace::name(), ExecSpace().concurrency());
  run<2>(c2, steps);
  run<3>(c3, steps);
  return 0;
}
