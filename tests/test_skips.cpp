// Work skipped because a scene does not need it (issue 7) gives the same results as the work done:
// each test runs one scene twice, with the skip and with it switched off, and compares positions,
// velocities and energies exactly (==).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "solver/simulation.hpp"
#include "scenes.hpp"
#include "solver_fixtures.hpp"

namespace {

using namespace fdem;
using fdem_test::cracked_block;
using fdem_test::fail_all_interfaces;
using fdem_test::shake;

template <int D>
void expect_same_state(const Simulation<D>& a, const Simulation<D>& b, const std::string& what) {
  const auto xa = fdem_test::host_view(a.m.x);
  const auto xb = fdem_test::host_view(b.m.x);
  const auto va = fdem_test::host_view(a.m.v);
  const auto vb = fdem_test::host_view(b.m.v);
  long differ = 0;
  for (int i = 0; i < a.m.nn; ++i)
    for (int k = 0; k < D; ++k) differ += (xa(i, k) != xb(i, k)) + (va(i, k) != vb(i, k));
  EXPECT_EQ(differ, 0) << what << ": node positions or velocities differ";
  const Energies& ea = a.energies();
  const Energies& eb = b.energies();
  EXPECT_EQ(ea.kinetic, eb.kinetic) << what;
  EXPECT_EQ(ea.strain, eb.strain) << what;
  EXPECT_EQ(ea.interface_elastic, eb.interface_elastic) << what;
  EXPECT_EQ(ea.contact_elastic, eb.contact_elastic) << what;
  EXPECT_EQ(ea.fracture, eb.fracture) << what;
  EXPECT_EQ(ea.damping, eb.damping) << what;
  EXPECT_EQ(ea.friction, eb.friction) << what;
  EXPECT_EQ(ea.work_external, eb.work_external) << what;
  EXPECT_EQ(ea.balance_error, eb.balance_error) << what;
}

// ---- no damping work when damping is zero ----

// Interfaces that soften and break under the random velocities, no damping; with and without
// velocity BCs (without them the unsampled node update is a plain parallel_for, no reduction).
template <int D>
void zero_damping_scene(bool with_bcs) {
  const HostMesh mesh = cracked_block<D>(D == 2 ? 4 : 2);
  auto c = fdem_test::basic_case(D, 30e9, 0.2, 2500);
  InterfaceMaterial im = fdem_test::strong_interface(30e9 / (0.1 * 0.01), 30e9 / (0.25 * 0.01));
  im.ft = 1e6;
  im.c = 2e6;
  im.Gnc = 1;
  im.Gsc = 10;
  c.interface_materials = {im};
  c.fracture_material = 0;
  c.contact.enabled = 0;
  if (with_bcs) {
    VelocityBC left, right;
    left.set = "xmin";
    left.active = {true, true, true};
    right.set = "xmax";
    right.active = {true, false, false};
    right.velocity = {1.0, 0, 0};
    right.ramp_time = 1e-5;
    c.velocity_bcs = {left, right};
  }
  c.local_damping = 0.0;
  c.mass_damping = 0.0;
  Simulation<D> skip(c, mesh), full(c, mesh);
  full.skips.damping = false;
  shake(skip, 0.5);
  shake(full, 0.5);
  for (int s = 0; s < 3000; ++s) {
    const bool sample = s % 100 == 0;
    skip.step(sample);
    full.step(sample);
  }
  skip.step(true);
  full.step(true);
  expect_same_state(skip, full, std::to_string(D) + "D, BCs " + (with_bcs ? "on" : "off"));
  EXPECT_GT(skip.energies().fracture, 0.0) << "the scene should damage interfaces";
  EXPECT_EQ(skip.energies().damping, 0.0);
  if (with_bcs) {
    EXPECT_NE(skip.energies().work_external, 0.0);
  }
}

TEST(Skips, ZeroDampingGivesTheSameResults2D) {
  zero_damping_scene<2>(false);
  zero_damping_scene<2>(true);
}

TEST(Skips, ZeroDampingGivesTheSameResults3D) {
  zero_damping_scene<3>(false);
  zero_damping_scene<3>(true);
}

// ---- no contact search while nothing can meet ----

// The block of these scenes: one intact body with interfaces (contact "auto": on).
template <int D>
Case block_case() {
  auto c = fdem_test::basic_case(D, 30e9, 0.2, 2500);
  c.interface_materials = {fdem_test::strong_interface(30e9 / (0.1 * 0.01), 30e9 / (0.25 * 0.01))};
  c.fracture_material = 0;
  return c;
}

// One intact body with interfaces: contact on (the case's "auto") does nothing until an interface
// fails, so the run is the one without contact.
template <int D>
void contact_idle_scene() {
  const HostMesh mesh = cracked_block<D>(D == 2 ? 4 : 2);
  auto c = block_case<D>();
  c.local_damping = 0.1;
  // the same time step for both: contact's springs do not shorten it while nothing can meet
  auto c_off = c;
  c_off.contact.enabled = 0;
  Simulation<D> on(c, mesh), off(c_off, mesh);
  ASSERT_EQ(on.dt, off.dt);
  EXPECT_TRUE(on.stable.contact_pending);
  ASSERT_NE(on.contact(), nullptr);
  ASSERT_EQ(off.contact(), nullptr);
  shake(on, 0.5);
  shake(off, 0.5);
  for (int s = 0; s < 2000; ++s) {
    on.step(s % 100 == 0);
    off.step(s % 100 == 0);
  }
  on.step(true);
  off.step(true);
  EXPECT_FALSE(on.contact()->may_meet());
  EXPECT_EQ(on.contact()->builds(), 0);
  expect_same_state(on, off, std::to_string(D) + "D, contact on / off");
}

TEST(Skips, ContactWhileNothingCanMeetGivesTheSameResults2D) { contact_idle_scene<2>(); }
TEST(Skips, ContactWhileNothingCanMeetGivesTheSameResults3D) { contact_idle_scene<3>(); }


// The step of idle contact: the springs of contacts (and of the platens on crack faces) count in
// the stable step only from the step on which surfaces can meet. Before: the step without contact.
// Then: the safety factor times the critical step with contact, with the velocity step of the
// change (dt_old + dt_new) / 2 (leap-frog with a step change). Momentum and energy through the
// change: Impact.* (a fragmenting impact changes the step when its first interface fails).
template <int D>
void contact_step_scene() {
  const HostMesh mesh = cracked_block<D>(D == 2 ? 4 : 2);
  const auto c = block_case<D>();
  auto c_off = c;
  c_off.contact.enabled = 0;
  Simulation<D> sim(c, mesh), off(c_off, mesh);
  ASSERT_NE(sim.contact(), nullptr);
  ASSERT_TRUE(sim.stable.contact_pending);
  EXPECT_EQ(sim.dt, off.dt);
  EXPECT_DOUBLE_EQ(sim.dt, c.safety_factor * off.stable.critical);
  // the contact springs are stiffer than the interfaces' (about twice the area, both masses)
  EXPECT_LT(sim.stable.critical_contact, 0.9 * sim.stable.critical);
  const double dt0 = sim.dt, crit_c = sim.stable.critical_contact;
  shake(sim, 0.5);
  for (int s = 0; s < 50; ++s) sim.step(s == 0);
  EXPECT_EQ(sim.dt, dt0);
  EXPECT_EQ(sim.dt_changed_at(), -1);
  EXPECT_EQ(sim.last_velocity_step(), dt0);
  fail_all_interfaces(sim);  // the pieces come apart: surfaces can meet
  ASSERT_TRUE(sim.contact()->may_meet());
  const long n = sim.step_count;
  sim.step(true);
  EXPECT_EQ(sim.dt_changed_at(), n);
  EXPECT_DOUBLE_EQ(sim.dt, c.safety_factor * crit_c);
  EXPECT_DOUBLE_EQ(sim.stable.critical, crit_c);
  EXPECT_FALSE(sim.stable.contact_pending);
  EXPECT_DOUBLE_EQ(sim.last_velocity_step(), 0.5 * (dt0 + sim.dt));
  EXPECT_DOUBLE_EQ(sim.dt_before_change(), dt0);
  const double dt1 = sim.dt;
  for (int s = 0; s < 1000; ++s) sim.step(false);
  EXPECT_NO_THROW(sim.check_finite());
  EXPECT_EQ(sim.dt, dt1);
  EXPECT_EQ(sim.last_velocity_step(), dt1);
}

TEST(Skips, ContactStepAppliesOnceSurfacesCanMeet2D) { contact_step_scene<2>(); }
TEST(Skips, ContactStepAppliesOnceSurfacesCanMeet3D) { contact_step_scene<3>(); }

// ---- no friction history when friction is off ----

// Largest difference between the node velocities of two runs, relative to the largest speed.
template <int D>
double velocity_difference(const Simulation<D>& a, const Simulation<D>& b) {
  auto va = Kokkos::create_mirror_view(a.m.v);
  auto vb = Kokkos::create_mirror_view(b.m.v);
  Kokkos::deep_copy(va, a.m.v);
  Kokkos::deep_copy(vb, b.m.v);
  double d = 0, vmax = 0;
  for (int i = 0; i < a.m.nn; ++i)
    for (int k = 0; k < D; ++k) {
      d = std::max(d, std::fabs(va(i, k) - vb(i, k)));
      vmax = std::max(vmax, std::fabs(va(i, k)));
    }
  return vmax > 0 ? d / vmax : d;
}

// Number of (node, face) pairs whose contact history differs (normal force, area, shear force).
template <int D>
long history_difference(const ContactSystem<D>& a, const ContactSystem<D>& b) {
  const auto& pa = a.pairs();
  const auto& pb = b.pairs();
  if (pa.size != pb.size) return -1;
  auto h = [](const auto& v) {
    auto m = Kokkos::create_mirror_view(v);
    Kokkos::deep_copy(m, v);
    return m;
  };
  const auto fa = h(pa.face), fb = h(pb.face);
  const auto na = h(pa.fn), nb = h(pb.fn), aa = h(pa.ac), ab = h(pb.ac);
  const auto sa = h(pa.fs), sb = h(pb.fs);
  long n = 0;
  for (int j = 0; j < pa.size; ++j) {
    bool same = fa(j) == fb(j) && na(j) == nb(j) && aa(j) == ab(j);
    for (int k = 0; k < D; ++k) same = same && sa(j, k) == sb(j, k);
    n += same ? 0 : 1;
  }
  return n;
}

// A block cracked into single elements, shaken, fragments in contact. Friction: `mu[0]` for the
// first third of the run, `mu[1]` for the second, `mu[2]` for the last. The contact forces are
// summed with atomics, in an order that varies from run to run (two runs of either kind differ by
// round-off, which the fragments' motion amplifies), so the two runs go in lock-step: after each
// step the second takes the first one's positions and velocities. Per step, the velocities agree
// to round-off, and the contact history (normal and shear forces, areas of every pair), the
// friction dissipation and the spring energy agree exactly.
template <int D>
void frictionless_scene(const double (&mu)[3]) {
  const HostMesh mesh = cracked_block<D>(D == 2 ? 3 : 2);
  auto c = fdem_test::basic_case(D, 1e7, 0.25, 2000);
  c.interface_materials = {fdem_test::strong_interface(2e7 / 0.01, 0.8e7 / 0.01)};
  c.fracture_material = 0;
  c.contact.enabled = 1;
  c.contact.friction = mu[0];
  VelocityBC fix;
  fix.set = D == 2 ? "ymin" : "zmin";
  fix.active = {true, true, true};
  c.velocity_bcs = {fix};
  c.gravity = {0, 0, 0};
  c.gravity[D - 1] = -9.81;
  Simulation<D> skip(c, mesh), full(c, mesh);
  full.contact()->skip_frictionless = false;
  for (Simulation<D>* s : {&skip, &full}) {
    fail_all_interfaces(*s);
    shake(*s, 0.05);
  }
  const std::string what = std::to_string(D) + "D, mu " + std::to_string(mu[0]) + ", " +
                           std::to_string(mu[1]) + ", " + std::to_string(mu[2]);
  const int n = 400;
  double worst_v = 0;
  long history_differs = 0, contacts = 0;
  for (int s = 0; s < 3 * n; ++s) {
    if (s % n == 0) {
      skip.contact()->law.mu = mu[s / n];
      full.contact()->law.mu = mu[s / n];
    }
    skip.step(false);
    full.step(false);
    worst_v = std::max(worst_v, velocity_difference(skip, full));
    history_differs += history_difference(*skip.contact(), *full.contact()) != 0;
    EXPECT_EQ(skip.contact()->dissipated(), full.contact()->dissipated()) << what << ", step " << s;
    EXPECT_EQ(skip.contact()->elastic_energy(), full.contact()->elastic_energy()) << what << ", step " << s;
    contacts += skip.contact()->active_contacts();
    Kokkos::deep_copy(full.m.x, skip.m.x);
    Kokkos::deep_copy(full.m.v, skip.m.v);
  }
  EXPECT_LT(worst_v, 1e-10) << what << ": velocities differ by more than round-off";
  EXPECT_EQ(history_differs, 0) << what << ": steps with a different contact history";
  EXPECT_GT(contacts, 3 * n) << what << ": the fragments should touch";
  const bool friction = mu[0] > 0 || mu[1] > 0 || mu[2] > 0;
  if (friction) {
    EXPECT_GT(skip.contact()->dissipated(), 0.0) << what;
  } else {
    EXPECT_EQ(skip.contact()->dissipated(), 0.0) << what;
  }
}

TEST(Skips, FrictionlessContactGivesTheSameResults2D) {
  frictionless_scene<2>({0.0, 0.0, 0.0});
  frictionless_scene<2>({0.5, 0.0, 0.3});  // friction switched off with springs loaded, then on
}

TEST(Skips, FrictionlessContactGivesTheSameResults3D) {
  frictionless_scene<3>({0.0, 0.0, 0.0});
  frictionless_scene<3>({0.5, 0.0, 0.3});
}

}  // namespace
