// Point loads that ramp (boundary.point_loads[].ramp_time, docs/case-format.md "boundary"): the
// force rises linearly from 0 to its value over ramp_time, several ramps may act on one node, the
// ledger sums a ramped load's work step by step (the energy balance closes), a constant load is
// the load it was (ramp_time 0 = omitted, work F . u), and a restart in the middle of a ramp goes
// on bit for bit (in memory and through the checkpoint file).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/error.hpp"
#include "io/case.hpp"
#include "io/checkpoint.hpp"
#include "mesh/mesh.hpp"
#include "solver/simulation.hpp"
#include "solver_fixtures.hpp"
#include "test_files.hpp"

namespace {

using namespace fdem;

// The bar: 0.1 m x 0.01 m, thickness 0.01 m, plane stress, E = 10 GPa, nu = 0 (uniaxial stress
// under an end load is then exact for linear triangles), 20 x 1 crossed cells (80 triangles).
// The right end has two nodes, so a load shared equally by them is the consistent end load.
constexpr double kL = 0.1, kH = 0.01, kT = 0.01, kE = 10e9, kRho = 2500;

Case bar_case() {
  Case c = fdem_test::basic_case(2, kE, 0.0, kRho);
  c.plane_stress = true;
  c.thickness = kT;
  return c;
}

HostMesh bar_mesh() { return generate_crossed_rectangle(0, 0, kL, kH, 20, 1); }

// Mean x displacement of a node set.
double mean_ux(const Simulation<2>& sim, const HostMesh& mesh, const std::string& set) {
  auto x = Kokkos::create_mirror_view(sim.m.x);
  Kokkos::deep_copy(x, sim.m.x);
  double s = 0;
  const auto& nodes = mesh.node_sets.at(set);
  for (int i : nodes) s += x(i, 0) - mesh.X[2 * i];
  return s / static_cast<double>(nodes.size());
}

PointLoad load(const std::string& set, double fx, double ramp) {
  PointLoad p;
  p.set = set;
  p.force = {fx, 0, 0};
  p.ramp_time = ramp;
  return p;
}

// A slowly ramped tensile end load on a bar fixed at its left end, with local damping: at the end
// of the ramp and after a hold the end displacement is F L / (E A); the ledger's external work
// equals kinetic + strain + damping energy at every sample. Once with one load of 1 kN ramped
// over Tr, once with the same total from three loads on the same nodes (0.5 kN over Tr,
// 0.3 kN over Tr / 2, 0.2 kN at once).
TEST(PointLoadRamp, SlowRampGivesStaticDisplacementAndTheBalanceCloses) {
  // strain 1e-5: the geometric stiffening of the large-strain element (1.5 strain) stays at 1.5e-5
  const double F = 10, Tr = 2e-3;               // 40 wave transits of the bar (L / c = 50 us)
  const double want = F * kL / (kE * kH * kT);  // 1e-6 m
  const std::vector<std::vector<PointLoad>> setups = {
      {load("right", F, Tr)},
      {load("right", 0.5 * F, Tr), load("right", 0.3 * F, 0.5 * Tr), load("right", 0.2 * F, 0)}};
  for (size_t s = 0; s < setups.size(); ++s) {
    Case c = bar_case();
    VelocityBC fixed;
    fixed.set = "left";
    fixed.active = {true, true, false};
    c.velocity_bcs = {fixed};
    c.point_loads = setups[s];
    c.local_damping = 0.7;
    const HostMesh mesh = bar_mesh();
    Simulation<2> sim(c, mesh);
    double worst = 0, u_ramp = 0;
    bool ramp_seen = false;
    while (sim.t < 1.5 * Tr) {
      const bool sample = sim.step_count % 20 == 0;
      sim.step(sample);
      if (!ramp_seen && sim.t >= Tr) {
        u_ramp = mean_ux(sim, mesh, "right");
        ramp_seen = true;
      }
      if (!sample) continue;
      const Energies& e = sim.energies();
      const double stored = e.kinetic + e.strain + e.damping;
      worst = std::max(worst, std::fabs(stored - e.work_external));
    }
    const double u_end = mean_ux(sim, mesh, "right");
    const Energies& e = sim.energies();
    // quasi-static: the end of the ramp within 2 % (the damped bar lags), after a hold of 20
    // transits within 1e-4
    EXPECT_NEAR(u_ramp / want, 1.0, 2e-2) << "setup " << s;
    EXPECT_NEAR(u_end / want, 1.0, 1e-4) << "setup " << s;
    // at rest, the strain energy is F u / 2; the loads did that and the damping's share of work
    EXPECT_NEAR(e.strain / (0.5 * F * want), 1.0, 2e-4) << "setup " << s;
    EXPECT_GT(e.damping, 1e-2 * e.strain) << "setup " << s;
    EXPECT_LT(e.kinetic, 1e-6 * e.strain) << "setup " << s;
    // the external work is the work of the loads (strain + damping), not F . u (twice the strain
    // energy)
    EXPECT_LT(e.work_external, 1.2 * e.strain) << "setup " << s;
    EXPECT_LT(worst, 1e-5 * e.work_external) << "setup " << s << ": worst balance error " << worst;
    std::printf(
        "setup %zu: u(ramp end) / (F L / E A) = %.6f, u(%.1f ms) / (F L / E A) = %.6f, "
        "W_external / E_strain = %.5f, max |balance error| / W_external = %.2g\n",
        s, u_ramp / want, 1e3 * sim.t, u_end / want, e.work_external / e.strain, worst / e.work_external);
  }
}

// A free bar pulled at one end by two ramped loads (ramps Tr1, Tr2): the momentum at t_n is the
// impulse of the loads, sum over earlier steps of F(t_j) dt plus half this step's, F(t) =
// F1 min(1, t / Tr1) + F2 min(1, t / Tr2); after both ramps, F1 (t - Tr1 / 2) + F2 (t - Tr2 / 2).
// Kinetic + strain energy equal the ledger's external work.
TEST(PointLoadRamp, FreeBarMomentumIsTheImpulseOfTheRamp) {
  const double F1 = 300, F2 = -100, Tr1 = 1e-4, Tr2 = 4e-5;
  Case c = bar_case();
  c.point_loads = {load("right", F1, Tr1), load("right", F2, Tr2)};
  const HostMesh mesh = bar_mesh();
  Simulation<2> sim(c, mesh);
  auto force = [&](double t) { return F1 * std::min(1.0, t / Tr1) + F2 * std::min(1.0, t / Tr2); };
  double impulse = 0;  // sum of F(t_j) dt over the steps before this one
  int checked = 0;
  double worst = 0;  // relative balance error once the work is above 1e-6 of its final value
  while (sim.t < 2 * Tr1) {
    const double t = sim.t, dt = sim.dt;
    sim.step(true);
    const Energies& e = sim.energies();
    const double want = impulse + 0.5 * force(t) * dt;
    ASSERT_NEAR(e.momentum[0], want, 1e-9 * std::fabs(want) + 1e-15) << "t = " << t;
    EXPECT_NEAR(e.kinetic + e.strain, e.work_external, 1e-6 * e.work_external + 1e-15) << "t = " << t;
    if (t > 0.2 * Tr1)
      worst = std::max(worst, std::fabs(e.kinetic + e.strain - e.work_external) / e.work_external);
    impulse += force(t) * dt;
    ++checked;
  }
  EXPECT_GT(checked, 100);
  // each step's work over [t, t + dt] with the force linear in time: exact for the kinetic energy
  // 0.5 m v(n-1/2) v(n+1/2) of a free node (the centred F (v(n-1/2) + v(n+1/2)) dt / 2, half of it
  // on the sampled step, leaves 0.25 dt^2 F^2 / m: 1.5e-5 here)
  EXPECT_LT(worst, 1e-7);
  std::printf(
      "free bar: %d steps, max |E_kinetic + E_strain - W_external| / W_external = %.2g (t > 0.2 Tr1)\n",
      checked, worst);
  const double t = sim.energies().time;
  EXPECT_NEAR(sim.energies().momentum[0], F1 * (t - 0.5 * Tr1) + F2 * (t - 0.5 * Tr2),
              (std::fabs(F1) + std::fabs(F2)) * sim.dt);
}

// A constant load: ramp_time 0 and an omitted ramp_time are the same case and the same run, no
// ramp table is built, and the ledger counts the load's work as F . u at the sample (the work
// summed step by step would differ from it in the third digit).
TEST(PointLoadRamp, ZeroRampIsTheConstantLoad) {
  auto doc = [](bool with_zero) {
    nlohmann::json d = nlohmann::json::parse(R"({
      "name": "t", "dimension": 2,
      "mesh": {"generator": "rectangle", "origin": [0, 0], "size": [0.1, 0.01], "cells": [20, 1]},
      "analysis": {"plane": "stress", "thickness": 0.01},
      "materials": {"rock": {"density": 2500, "E": 10e9, "nu": 0}},
      "regions": {"body": "rock"},
      "boundary": {"fixed": [{"set": "left"}], "point_loads": [{"set": "right", "force": [1000, 0]}]},
      "damping": {"local": 0.05},
      "time": {"end_time": 1e-3}
    })");
    if (with_zero) d["boundary"]["point_loads"][0]["ramp_time"] = 0;
    return d;
  };
  const Case a = parse_case(doc(false), "a.json"), b = parse_case(doc(true), "b.json");
  ASSERT_EQ(a.point_loads.size(), 1u);
  EXPECT_EQ(a.point_loads[0].ramp_time, 0.0);
  EXPECT_EQ(b.point_loads[0].ramp_time, 0.0);
  const HostMesh mesh = bar_mesh();
  Simulation<2> sa(a, mesh), sb(b, mesh);
  EXPECT_EQ(sa.m.fext.extent(0), static_cast<size_t>(mesh.num_nodes()));
  EXPECT_EQ(sa.m.fext_ramp.extent(0), 0u);
  for (int s = 0; s < 400; ++s) {
    sa.step(s % 50 == 0);
    sb.step(s % 50 == 0);
  }
  const Energies &ea = sa.energies(), &eb = sb.energies();
  EXPECT_EQ(ea.work_external, eb.work_external);
  EXPECT_EQ(ea.strain, eb.strain);
  EXPECT_EQ(mean_ux(sa, mesh, "right"), mean_ux(sb, mesh, "right"));
  // F . u of the positions at the sample (step 350): the sample's u is that of step 350, so
  // compare with the mean end displacement then (rerun to it)
  Simulation<2> sc(a, mesh);
  for (int s = 0; s < 350; ++s) sc.step(s % 50 == 0);
  const double fu = 1000 * mean_ux(sc, mesh, "right");
  EXPECT_NEAR(ea.work_external / fu, 1.0, 1e-12);
}

// Bad input names the key and the range.
TEST(PointLoadRamp, BadRampTimeNamesTheKey) {
  nlohmann::json d = nlohmann::json::parse(R"({
    "name": "t", "dimension": 2,
    "mesh": {"generator": "rectangle", "origin": [0, 0], "size": [0.1, 0.01], "cells": [20, 1]},
    "materials": {"rock": {"density": 2500, "E": 10e9, "nu": 0}},
    "regions": {"body": "rock"},
    "boundary": {"point_loads": [{"set": "right", "force": [1000, 0], "ramp_time": -1e-3}]},
    "time": {"end_time": 1e-3}
  })");
  auto error = [](const nlohmann::json& doc) -> std::string {
    try {
      parse_case(doc, "bad.json");
    } catch (const InputError& e) {
      return e.what();
    }
    return "<no error>";
  };
  std::string msg = error(d);
  EXPECT_NE(msg.find("bad.json: boundary.point_loads.0.ramp_time: "), std::string::npos) << msg;
  EXPECT_NE(msg.find(">= 0"), std::string::npos) << msg;
  d["boundary"]["point_loads"][0]["ramp_time"] = "slow";
  msg = error(d);
  EXPECT_NE(msg.find("boundary.point_loads.0.ramp_time"), std::string::npos) << msg;
  // nine distinct ramp times > 0 (zeros do not count)
  d["boundary"]["point_loads"] = nlohmann::json::array();
  for (int i = 0; i <= kMaxLoadRamps; ++i)
    d["boundary"]["point_loads"].push_back(
        {{"set", "right"}, {"force", {1, 0}}, {"ramp_time", 1e-4 * (i + 1)}});
  d["boundary"]["point_loads"].push_back({{"set", "right"}, {"force", {1, 0}}, {"ramp_time", 0}});
  msg = error(d);
  EXPECT_NE(msg.find("boundary.point_loads.8.ramp_time"), std::string::npos) << msg;
  EXPECT_NE(msg.find("at most 8"), std::string::npos) << msg;
  d["boundary"]["point_loads"].erase(8);
  EXPECT_EQ(error(d), "<no error>");
}

// Checkpoint in the middle of the ramps (in memory): the restarted run goes on bit for bit,
// positions and the ledger (its summed work of the ramped loads included).
TEST(PointLoadRamp, RestartInTheRampContinuesBitwise) {
  Case c = bar_case();
  VelocityBC fixed;
  fixed.set = "left";
  fixed.active = {true, true, false};
  c.velocity_bcs = {fixed};
  c.point_loads = {load("right", 800, 2e-4), load("top", 50, 1e-4), load("right", 100, 0)};
  c.point_loads[1].force = {0, -50, 0};
  c.local_damping = 0.1;
  const HostMesh mesh = bar_mesh();
  Simulation<2> a(c, mesh);
  for (int s = 0; s < 300; ++s) a.step(s % 25 == 0);
  StateArrays st;
  a.save_state(st);
  ASSERT_TRUE(st.has("simulation/work_ramped_loads"));
  EXPECT_GT(st.get("simulation/work_ramped_loads"), 0.0);
  Simulation<2> b(c, mesh);
  b.load_state(st);
  for (int s = 300; s < 900; ++s) {
    a.step(s % 25 == 0);
    b.step(s % 25 == 0);
  }
  const std::vector<double> ea = energies_to_vector(a.energies()), eb = energies_to_vector(b.energies());
  ASSERT_EQ(ea.size(), eb.size());
  for (size_t i = 0; i < ea.size(); ++i) EXPECT_EQ(ea[i], eb[i]) << "energy field " << i;
  EXPECT_EQ(mean_ux(a, mesh, "right"), mean_ux(b, mesh, "right"));
  EXPECT_LT(std::fabs(a.energies().balance_error), 1e-4 * a.energies().work_external);
  // a checkpoint of a run without ramped loads has no such entry
  Case k = c;
  k.point_loads = {load("right", 100, 0)};
  Simulation<2> plain(k, mesh);
  plain.step(true);
  StateArrays sp;
  plain.save_state(sp);
  EXPECT_FALSE(sp.has("simulation/work_ramped_loads"));
}

// The same through the command line and the checkpoint file: a run killed after its checkpoint at
// 0.1 ms (the ramps end at 0.15 and 0.3 ms) and restarted writes history.csv byte for byte as
// the uninterrupted run; its energy error stays below 1e-5 of the external work. Bar with
// interfaces (some fail), 0.4 ms, about 2300 steps.
TEST(PointLoadRamp, KilledRunRestartsBitwiseThroughTheCheckpointFile) {
  const std::string dir = fdem::test::scratch_dir("ramp", "cli");
  std::filesystem::create_directories(dir);
  nlohmann::json d = nlohmann::json::parse(R"({
    "name": "ramped_loads", "dimension": 2,
    "mesh": {"generator": "rectangle", "origin": [0, 0], "size": [0.1, 0.01], "cells": [20, 2]},
    "analysis": {"plane": "stress", "thickness": 0.01},
    "materials": {"rock": {"density": 2500, "E": 10e9, "nu": 0.2}},
    "regions": {"body": "rock"},
    "interface_materials": {"cif": {"kn": 2e13, "ks": 1e13, "ft": 1e6, "c": 3e6, "phi_deg": 30,
                                    "Gnc": 10, "Gsc": 100}},
    "fracture": {"regions": ["body"], "interface_material": "cif"},
    "boundary": {"fixed": [{"set": "left"}],
                 "point_loads": [{"set": "right", "force": [150, 0], "ramp_time": 3e-4},
                                 {"set": "top", "force": [0, -20], "ramp_time": 1.5e-4},
                                 {"set": "right", "force": [5, 0]}]},
    "damping": {"local": 0.1},
    "time": {"end_time": 4e-4},
    "output": {"history_rows": 200}
  })");
  std::ofstream(dir + "/case.json") << d.dump(2);
  auto run = [&](const std::string& out, const std::string& extra, const std::string& env = "") {
    return fdem::test::system_status("env OMP_NUM_THREADS=1 OMP_PROC_BIND=false " + env + " " + FDEM_BINARY +
                                     " run " + dir + "/case.json --out " + out + " --quiet " + extra + " > " +
                                     out + ".log 2>&1");
  };
  const std::string ref = dir + "/ref", out = dir + "/killed";
  ASSERT_EQ(run(ref, ""), 0) << fdem::test::slurp(ref + ".log");
  ASSERT_EQ(run(out, "--checkpoint-every 1e-4", "FDEM_TEST_CHECKPOINT_KILL=after:1"), 128 + 9)
      << fdem::test::slurp(out + ".log");
  ASSERT_EQ(run(out, "--checkpoint-every 1e-4 --restart " + out + "/checkpoint.h5"), 0)
      << fdem::test::slurp(out + ".log");
  const std::string a = fdem::test::slurp(ref + "/history.csv");
  EXPECT_GT(a.size(), 20000u);
  EXPECT_EQ(a, fdem::test::slurp(out + "/history.csv"));
  // the last row's W_external and energy_error
  std::istringstream rows(a);
  std::string line, last, head;
  std::getline(rows, head);
  while (std::getline(rows, line))
    if (!line.empty()) last = line;
  std::vector<std::string> names, values;
  for (auto [src, dst] : {std::pair{&head, &names}, std::pair{&last, &values}}) {
    std::istringstream cells(*src);
    std::string cell;
    while (std::getline(cells, cell, ',')) dst->push_back(cell);
  }
  ASSERT_EQ(names.size(), values.size());
  double W = 0, err = 1;
  for (size_t i = 0; i < names.size(); ++i) {
    if (names[i] == "W_external [J]") W = std::stod(values[i]);
    if (names[i] == "energy_error [J]") err = std::stod(values[i]);
  }
  EXPECT_GT(W, 0.1);
  EXPECT_LT(std::fabs(err), 1e-5 * W);
  std::filesystem::remove_all(dir);
}

}  // namespace
