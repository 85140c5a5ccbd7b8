// Run time against error of a wave's arrival (issue 7): the wave test of the solver core
// (tests/test_solver.cpp, Solver.WaveSpeedAndReflectionFromFreeEnd) over element sizes.
//
//   bench_wave [--sizes 0.02,0.01,0.005] [--length 1] [--height 0.04] [--alpha 0.1]
//              [--safety 0.5] [--json FILE]
//
// A bar of length L and height H (plane stress, nu = 0, E 30 GPa, rho 2500 kg/m^3) made of square
// blocks of side d (two triangles each, with their own nodes), with a cohesive interface between
// every two neighbouring blocks (along and across the bar), stiffness k_n = E / (alpha d) (the
// test's alpha = 0.1), so strong that nothing breaks. The blocks of the first tenth of the bar
// start at v0 = 0.1 m/s along it: a pulse of amplitude v0/2 runs to the right at
// c_eff = sqrt(E_eff / rho), E_eff = E k_n d / (E + k_n d) (blocks in series with interfaces,
// docs/theory.md section 5). Its front (the first crossing of v0/4, interpolated between steps) is timed
// at two nodes of the bottom row, at 0.4 L and 0.8 L. Errors: the arrival time at 0.8 L against
// (0.8 L - 0.1 L) / c_eff, and the speed between the two against c_eff (what the test checks);
// also against the continuum bar speed sqrt(E / rho). Wall time: the time loop (the set-up is
// reported separately). Contact as `fdem run` decides it (on; nothing meets).
#include <Kokkos_Core.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "mesh/mesh.hpp"
#include "perf/bench_common.hpp"
#include "solver/simulation.hpp"
#include "tests/scenes.hpp"

namespace {

using namespace fdem;
using namespace fdem_bench;
using fdem_test::front_crossing;

constexpr double kE = 30e9, kRho = 2500, kV0 = 0.1;

struct Options {
  std::vector<double> sizes{0.02, 0.01, 0.005};
  double L = 1.0, H = 0.04, alpha = 0.1, safety = 0.5;
  std::string json_file, command;
};

Options parse(int argc, char** argv) {
  Options o;
  o.command = command_line(argc, argv);
  Args args(argc, argv, [](const std::string& msg) {
    std::fprintf(stderr, "bench_wave: %s\n", msg.c_str());
    std::exit(2);
  });
  while (args.next()) {
    const std::string& a = args.arg();
    auto val = [&]() { return args.value(); };
    if (a == "--sizes") o.sizes = parse_list(val());
    else if (a == "--length") o.L = std::stod(val());
    else if (a == "--height") o.H = std::stod(val());
    else if (a == "--alpha") o.alpha = std::stod(val());
    else if (a == "--safety") o.safety = std::stod(val());
    else if (a == "--json") o.json_file = val();
    else if (a.rfind("--kokkos", 0) == 0) continue;
    else {
      std::fprintf(stderr,
                   "bench_wave: unknown argument %s\nusage: bench_wave [--sizes 0.02,0.01,0.005] [--length 1] "
                   "[--height 0.04] [--alpha 0.1] [--safety 0.5] [--json FILE]\n",
                   a.c_str());
      std::exit(2);
    }
  }
  return o;
}

// nx x ny blocks of side d; block (i, j) has nodes bl, br, tr, tl = 4 (j nx + i) + 0..3 and
// elements (bl, br, tr), (bl, tr, tl). Interfaces: A side = left/lower block (normal from A to B).
HostMesh block_grid(int nx, int ny, double d, int kick_columns) {
  HostMesh m;
  m.dim = 2;
  m.region_names = {"body", "kick"};
  auto node = [&](int i, int j, int c) { return 4 * (j * nx + i) + c; };
  auto elem = [&](int i, int j, int t) { return 2 * (j * nx + i) + t; };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const double x0 = i * d, y0 = j * d;
      for (double p : {x0, y0, x0 + d, y0, x0 + d, y0 + d, x0, y0 + d}) m.X.push_back(p);
      const int b = node(i, j, 0);
      for (int n : {b, b + 1, b + 2, b, b + 2, b + 3}) m.elems.push_back(n);
      const int r = i < kick_columns ? 1 : 0;
      m.elem_region.push_back(r);
      m.elem_region.push_back(r);
    }
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      if (i + 1 < nx) {  // A: br, tr of (i, j); B: bl, tl of (i + 1, j)
        for (int n : {node(i, j, 1), node(i, j, 2), node(i + 1, j, 0), node(i + 1, j, 3)}) m.ifaces.push_back(n);
        m.iface_elems.push_back(elem(i, j, 0));
        m.iface_elems.push_back(elem(i + 1, j, 1));
      }
      if (j + 1 < ny) {  // A: tr, tl of (i, j) (normal +y); B: br, bl of (i, j + 1)
        for (int n : {node(i, j, 2), node(i, j, 3), node(i, j + 1, 1), node(i, j + 1, 0)}) m.ifaces.push_back(n);
        m.iface_elems.push_back(elem(i, j, 1));
        m.iface_elems.push_back(elem(i, j + 1, 0));
      }
    }
  for (int i = 0; i < m.num_nodes(); ++i) m.node_origin.push_back(i);
  std::vector<int> all(m.num_nodes());
  for (int i = 0; i < m.num_nodes(); ++i) all[i] = i;
  m.node_sets["all"] = all;
  return m;
}

Case wave_case(double kn, double safety) {
  Case c;
  c.file = "bench_wave";
  c.name = "bench_wave";
  c.dim = 2;
  c.plane_stress = true;
  c.thickness = 1.0;
  c.materials = {BulkMaterial{"rock", kRho, kE, 0.0}};
  c.region_material = {{"body", 0}, {"kick", 0}};
  c.interface_materials = {fdem_test::strong_interface(kn, kn / 2)};
  c.fracture_material = 0;
  c.initial_velocities = {InitialVelocity{"kick", {kV0, 0, 0}}};
  c.safety_factor = safety;
  c.end_time = 1;
  return c;
}

double node_vx(const Simulation<2>& sim, int i) {
  double out;
  Kokkos::deep_copy(out, Kokkos::subview(sim.m.v, i, 0));
  return out;
}

// One element size: runs the pulse until its front passes the second monitor, prints the row.
json run_size(double d, const Options& o) {
  const auto t0 = Clock::now();
  const int nx = std::max(10, static_cast<int>(std::lround(o.L / d)));
  const int ny = std::max(1, static_cast<int>(std::lround(o.H / d)));
  const double dd = o.L / nx;
  const int kick = nx / 10;
  const HostMesh mesh = block_grid(nx, ny, dd, kick);
  const double kn = kE / (o.alpha * dd);
  Simulation<2> sim(wave_case(kn, o.safety), mesh);
  const double setup = seconds_since(t0);
  const double Eeff = kE * kn * dd / (kE + kn * dd);
  const double ceff = std::sqrt(Eeff / kRho), c0 = std::sqrt(kE / kRho);
  const int m1 = static_cast<int>(std::lround(0.4 * nx)), m2 = static_cast<int>(std::lround(0.8 * nx));
  const int n1 = 4 * m1, n2 = 4 * m2;  // bottom-left nodes of the monitor blocks (row 0)
  const double x0 = kick * dd, x1 = m1 * dd, x2 = m2 * dd;
  const double t_exp = (x2 - x0) / ceff;
  double t1 = -1, t2 = -1, prev1 = 0, prev2 = 0, tprev = 0;
  const auto l0 = Clock::now();
  while (t2 < 0 && sim.t < 2 * t_exp) {
    sim.step(sim.step_count % 100 == 0);
    const double a1 = node_vx(sim, n1), a2 = node_vx(sim, n2);
    front_crossing(a1, prev1, sim.t, tprev, 0.25 * kV0, t1);
    front_crossing(a2, prev2, sim.t, tprev, 0.25 * kV0, t2);
    prev1 = a1;
    prev2 = a2;
    tprev = sim.t;
  }
  Kokkos::fence();
  const double wall = seconds_since(l0);
  sim.check_stability();
  const double arrival_err = t2 > 0 ? (t2 - t_exp) / t_exp : NAN;
  const double speed = t2 > t1 && t1 > 0 ? (x2 - x1) / (t2 - t1) : NAN;
  const double speed_err = speed / ceff - 1;
  const double cont_err = t2 > 0 ? (t2 - (x2 - x0) / c0) / ((x2 - x0) / c0) : NAN;
  json r = {{"element_size_m", dd},
            {"blocks_x", nx},
            {"blocks_y", ny},
            {"elements", sim.m.ne},
            {"interfaces", sim.m.ni},
            {"nodes", sim.m.nn},
            {"dt_s", sim.dt},
            {"steps", sim.step_count},
            {"c_eff_m_per_s", ceff},
            {"c_continuum_m_per_s", c0},
            {"arrival_s", t2},
            {"arrival_expected_s", t_exp},
            {"arrival_error", arrival_err},
            {"speed_m_per_s", speed},
            {"speed_error", speed_err},
            {"arrival_error_vs_continuum", cont_err},
            {"wall_seconds", wall},
            {"setup_seconds", setup},
            {"element_steps_per_second", wall > 0 ? sim.step_count * double(sim.m.ne) / wall : 0.0}};
  std::printf("%10.3g %9d %9d %8ld %11.3f%% %11.3f%% %11.3f%% %10.3f %9.2f\n", dd, sim.m.ne, sim.m.ni,
              sim.step_count, 100 * arrival_err, 100 * speed_err, 100 * cont_err, wall, setup);
  std::fflush(stdout);
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  Kokkos::ScopeGuard guard(argc, argv);
  const Options o = parse(argc, argv);
  json doc = record_header("bench_wave", o.command);
  doc["length_m"] = o.L;
  doc["height_m"] = o.H;
  doc["alpha"] = o.alpha;
  doc["safety_factor"] = o.safety;
  doc["runs"] = json::array();
  std::printf("bench_wave: %s backend, %d threads; bar %.3g m x %.3g m, alpha = E / (kn d) = %.3g\n",
              ExecSpace::name(), ExecSpace().concurrency(), o.L, o.H, o.alpha);
  std::printf("%10s %9s %9s %8s %12s %12s %12s %10s %9s\n", "d [m]", "elements", "ifaces", "steps",
              "arrival err", "speed err", "vs continuum", "wall [s]", "setup [s]");
  for (double d : o.sizes) doc["runs"].push_back(run_size(d, o));
  write_json(o.json_file, doc);
  return 0;
}
