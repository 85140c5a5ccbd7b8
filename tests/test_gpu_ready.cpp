// GPU readiness (issue 19): an unsampled step (Simulation::step(false)) asks for no fence, no copy
// between memories and no reduction or scan whose result goes to the host: on a GPU each of these
// stops the host until the device has caught up. The test records Kokkos' profiling events
// (Kokkos Tools callbacks registered in-process) while a scene with contact steps, and names the
// offending ones.
//
// What is allowed in an unsampled step: kernel launches (parallel_for); reductions and scans into
// device memory, whose labels end in kDeviceResult (kernels/fdem_kokkos.hpp: a reduction into a
// host value has no other mark that the callbacks could see); and the contact system's periodic
// reads of its device status, one small copy labelled kContactSyncLabel at most every step on
// which ContactSystem::update re-checks its candidate lists or the handover flag
// (solver/contact_system.hpp, "Synchronisation"): the test counts them and requires them rare.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "scenes.hpp"
#include "solver/simulation.hpp"
#include "solver_fixtures.hpp"

namespace {

using namespace fdem;
using fdem_test::cracked_block;
using fdem_test::fail_interfaces;
using fdem_test::pressed_case;

struct Recorded {
  std::vector<std::string> fences, copies, host_reductions;
  long launches = 0, device_reductions = 0, sync_copies = 0;
};

Recorded* g_rec = nullptr;  // recording while not null
bool g_in_sync = false;     // inside a copy of the contact system's status (its fences are its own)

bool device_result(const char* name) {
  const std::string s(name);
  const std::string mark(kDeviceResult);
  return s.size() >= mark.size() && s.compare(s.size() - mark.size(), mark.size(), mark) == 0;
}

void on_fence(const char* name, const uint32_t, uint64_t* id) {
  *id = 0;
  if (g_rec && !g_in_sync) g_rec->fences.push_back(name);
}
void on_copy(Kokkos_Profiling_SpaceHandle dst, const char* dst_name, const void*,
             Kokkos_Profiling_SpaceHandle src, const char* src_name, const void*, uint64_t bytes) {
  if (!g_rec) return;
  const std::string d(dst_name), s(src_name);
  if (d.find(kContactSyncLabel) != std::string::npos || s.find(kContactSyncLabel) != std::string::npos) {
    ++g_rec->sync_copies;
    g_in_sync = true;
    return;
  }
  g_rec->copies.push_back(s + " (" + src.name + ") -> " + d + " (" + dst.name + "), " +
                          std::to_string(bytes) + " bytes");
}
void on_copy_end() { g_in_sync = false; }
void on_reduce(const char* name, const uint32_t, uint64_t* id) {
  *id = 0;
  if (!g_rec) return;
  if (device_result(name))
    ++g_rec->device_reductions;
  else
    g_rec->host_reductions.push_back(std::string("reduce ") + name);
}
void on_scan(const char* name, const uint32_t, uint64_t* id) {
  *id = 0;
  if (!g_rec) return;
  if (device_result(name))
    ++g_rec->device_reductions;
  else
    g_rec->host_reductions.push_back(std::string("scan ") + name);
}
void on_for(const char*, const uint32_t, uint64_t* id) {
  *id = 0;
  if (g_rec) ++g_rec->launches;
}

// Registers the callbacks while it lives (nothing else in the test binary uses Kokkos Tools).
struct Hooks {
  Hooks() {
    namespace T = Kokkos::Tools::Experimental;
    T::set_begin_fence_callback(on_fence);
    T::set_begin_deep_copy_callback(on_copy);
    T::set_end_deep_copy_callback(on_copy_end);
    T::set_begin_parallel_reduce_callback(on_reduce);
    T::set_begin_parallel_scan_callback(on_scan);
    T::set_begin_parallel_for_callback(on_for);
  }
  ~Hooks() {
    g_rec = nullptr;
    namespace T = Kokkos::Tools::Experimental;
    T::set_begin_fence_callback(nullptr);
    T::set_begin_deep_copy_callback(nullptr);
    T::set_end_deep_copy_callback(nullptr);
    T::set_begin_parallel_reduce_callback(nullptr);
    T::set_begin_parallel_scan_callback(nullptr);
    T::set_begin_parallel_for_callback(nullptr);
  }
};

std::string list(const std::vector<std::string>& v) {
  std::map<std::string, int> count;
  for (const auto& s : v) ++count[s];
  std::string out;
  for (const auto& [s, n] : count) out += "\n    " + s + " (x" + std::to_string(n) + ")";
  return out;
}

// What `n` unsampled steps of `sim` ask for: on the steps that neither re-check the contact
// system's device status nor rebuild its candidate lists ("quiet" steps), on those that re-check
// without a rebuild, and on those that rebuild or hand interfaces over (the grid, the counts of
// new surfaces and the list sizes come from the device; a handover updates the lists by a local
// search, kernels/contact/list_update.hpp).
struct StepsRecord {
  Recorded quiet, recheck, build;
  int quiet_steps = 0, recheck_steps = 0, build_steps = 0, update_steps = 0;
};

template <int D>
StepsRecord record_steps(Simulation<D>& sim, int n) {
  StepsRecord out;
  Hooks hooks;
  for (int s = 0; s < n; ++s) {
    const long syncs = sim.contact()->syncs(), builds = sim.contact()->builds();
    const long updates = sim.contact()->list_updates(), checks = sim.contact()->handover_checks();
    Recorded r;
    const long fences = fence_count();
    g_rec = &r;
    sim.step(false);
    g_rec = nullptr;
    for (long k = fences; k < fence_count(); ++k) r.fences.push_back("fdem::fence");
    const bool updated = sim.contact()->list_updates() != updates;
    const bool synced = sim.contact()->syncs() != syncs;
    const bool built = sim.contact()->builds() != builds || sim.contact()->handover_checks() != checks;
    out.update_steps += updated ? 1 : 0;
    Recorded& into = built ? out.build : synced ? out.recheck : out.quiet;
    ++(built ? out.build_steps : synced ? out.recheck_steps : out.quiet_steps);
    using List = std::vector<std::string> Recorded::*;
    for (List v : {&Recorded::fences, &Recorded::copies, &Recorded::host_reductions})
      (into.*v).insert((into.*v).end(), (r.*v).begin(), (r.*v).end());
    into.launches += r.launches;
    into.device_reductions += r.device_reductions;
    into.sync_copies += r.sync_copies;
  }
  return out;
}

// staged: half of the interfaces fail before the recording, the rest after its first 100 steps
// (handovers during the recorded steps: local updates of the candidate lists)
template <int D>
void unsampled_steps_scene(bool staged = false) {
  const HostMesh mesh = cracked_block<D>(D == 2 ? 4 : 2);
  Case c = pressed_case<D>();
  // staged: no rebuild by the displacement bound around the handover. Else a tenth of the mean
  // element size (the derived skin before it became 2 %): rebuilds and re-checks, none of which
  // falls on a step that also polls the handover flag (every 25 steps; a step with both reads two
  // values, and the count of reads per re-check step below would not hold)
  c.contact.skin = staged ? 0.004 : 0.1 * mesh_quality(mesh).mean_size;
  Simulation<D> sim(c, mesh);
  ASSERT_NE(sim.contact(), nullptr);
  if (staged) {
    fail_interfaces(sim, [](int q) { return q % 2 == 0; });
    sim.contact()->check_failures(sim.m);
  } else {
    fdem_test::fail_all_interfaces(sim);
  }
  fdem_test::shake(sim, D == 2 ? 0.05 : 0.2);
  for (int s = 0; s < 20; ++s) sim.step(s % 10 == 0);  // warm-up: first build, sampled steps
  const long syncs0 = sim.contact()->syncs();
  const int n = 300;
  StepsRecord r;
  if (staged) {
    const StepsRecord a = record_steps(sim, 100);
    fail_interfaces(sim, [](int q) { return q % 2 == 1; });
    const StepsRecord b = record_steps(sim, n - 100);
    r = a;
    for (auto [to, from] : {std::make_pair(&r.quiet, &b.quiet), std::make_pair(&r.recheck, &b.recheck),
                            std::make_pair(&r.build, &b.build)}) {
      using List = std::vector<std::string> Recorded::*;
      for (List v : {&Recorded::fences, &Recorded::copies, &Recorded::host_reductions})
        (to->*v).insert((to->*v).end(), (from->*v).begin(), (from->*v).end());
      to->launches += from->launches;
      to->device_reductions += from->device_reductions;
      to->sync_copies += from->sync_copies;
    }
    r.quiet_steps += b.quiet_steps;
    r.recheck_steps += b.recheck_steps;
    r.build_steps += b.build_steps;
    r.update_steps += b.update_steps;
    EXPECT_GT(sim.contact()->handed_over(), sim.m.ni / 2);
    EXPECT_GT(r.update_steps, 0) << D << "D: the handover should update the lists without a rebuild";
  } else {
    r = record_steps(sim, n);
  }
  const std::string what = std::to_string(D) + "D" + (staged ? " (staged failures), " : ", ") +
                           std::to_string(n) + " unsampled steps";
  // the scene exercises what it should, and the hooks see the step's kernels
  EXPECT_GT(sim.contact()->active_contacts(), 0) << what << ": the fragments should touch";
  EXPECT_GT(r.build_steps, 0) << what << ": the candidate lists should be rebuilt";
  EXPECT_GE(r.quiet.launches, 4L * r.quiet_steps) << what << ": the hooks should see the step's kernels";
  EXPECT_GE(r.quiet.device_reductions, r.quiet_steps) << what << ": the contact pass reduces on the device";
  // quiet steps: nothing that stops the host
  EXPECT_TRUE(r.quiet.fences.empty()) << what << ", quiet steps: fences" << list(r.quiet.fences);
  EXPECT_TRUE(r.quiet.copies.empty()) << what << ", quiet steps: copies" << list(r.quiet.copies);
  EXPECT_EQ(r.quiet.sync_copies, 0) << what << ", quiet steps: status reads";
  EXPECT_TRUE(r.quiet.host_reductions.empty())
      << what << ", quiet steps: reductions or scans into host memory" << list(r.quiet.host_reductions);
  // re-check steps without a rebuild: one status read each, nothing else
  EXPECT_EQ(r.recheck.sync_copies + r.build.sync_copies, sim.contact()->syncs() - syncs0) << what;
  EXPECT_EQ(r.recheck.sync_copies, r.recheck_steps) << what;
  EXPECT_TRUE(r.recheck.fences.empty()) << what << ", re-check steps: fences" << list(r.recheck.fences);
  EXPECT_TRUE(r.recheck.copies.empty()) << what << ", re-check steps: copies" << list(r.recheck.copies);
  EXPECT_TRUE(r.recheck.host_reductions.empty())
      << what << ", re-check steps: host reductions" << list(r.recheck.host_reductions);
  // the steps that wait are few
  EXPECT_GT(r.quiet_steps, 2 * n / 3)
      << what << ": " << r.recheck_steps << " re-check steps, " << r.build_steps << " rebuilds";
  EXPECT_EQ(sim.contact()->stale_passes(), 0) << what << ": passes over outdated candidate lists";
  std::printf(
      "%s: %d quiet steps, %d re-check steps, %d rebuild or handover steps (%d list updates); on "
      "these:%s%s%s\n",
      what.c_str(), r.quiet_steps, r.recheck_steps, r.build_steps, r.update_steps,
      list(r.build.fences).c_str(), list(r.build.copies).c_str(), list(r.build.host_reductions).c_str());
}

TEST(GpuReady, UnsampledStepsDoNotWaitForTheDevice2D) { unsampled_steps_scene<2>(); }
TEST(GpuReady, UnsampledStepsDoNotWaitForTheDevice3D) { unsampled_steps_scene<3>(); }
TEST(GpuReady, UnsampledStepsWithHandoversDoNotWaitForTheDevice2D) { unsampled_steps_scene<2>(true); }
TEST(GpuReady, UnsampledStepsWithHandoversDoNotWaitForTheDevice3D) { unsampled_steps_scene<3>(true); }

// Ramped point loads (boundary.point_loads[].ramp_time) in a scene without damping, velocity BCs
// or contact: their work is summed every step, on the device (one reduction into device memory
// per unsampled step), with no fence, copy or host reduction; the ledger then closes.
TEST(GpuReady, RampedPointLoadsSumTheirWorkOnTheDevice) {
  const HostMesh mesh = generate_crossed_rectangle(0, 0, 0.1, 0.01, 20, 1);
  Case c = fdem_test::basic_case(2, 10e9, 0.0, 2500);
  PointLoad a, b;
  a.set = "right";
  a.force = {300, 0, 0};
  a.ramp_time = 1e-4;
  b.set = "top";
  b.force = {0, -50, 0};
  b.ramp_time = 4e-5;
  c.point_loads = {a, b};
  Simulation<2> sim(c, mesh);
  ASSERT_EQ(sim.contact(), nullptr);
  sim.step(true);
  Recorded r;
  const int n = 100;
  {
    Hooks hooks;
    const long fences = fence_count();
    g_rec = &r;
    for (int s = 0; s < n; ++s) sim.step(false);
    g_rec = nullptr;
    for (long k = fences; k < fence_count(); ++k) r.fences.push_back("fdem::fence");
  }
  EXPECT_TRUE(r.fences.empty()) << "fences" << list(r.fences);
  EXPECT_TRUE(r.copies.empty()) << "copies" << list(r.copies);
  EXPECT_TRUE(r.host_reductions.empty()) << "host reductions" << list(r.host_reductions);
  EXPECT_EQ(r.device_reductions, n);
  sim.step(true);
  const Energies& e = sim.energies();
  EXPECT_GT(e.work_external, 0.0);
  EXPECT_NEAR(e.kinetic + e.strain, e.work_external, 1e-7 * e.work_external);
}

// The test can fail: the hooks see what a sampled step asks for (its clocks fence, the energies are
// reductions into host values, the platen accumulators are copied to the host).
TEST(GpuReady, HooksSeeWhatASampledStepAsksFor) {
  const HostMesh mesh = cracked_block<2>(3);
  Simulation<2> sim(pressed_case<2>(), mesh);
  fdem_test::fail_all_interfaces(sim);
  for (int s = 0; s < 3; ++s) sim.step(s == 0);
  Recorded r;
  {
    Hooks hooks;
    const long fences = fence_count();
    g_rec = &r;
    sim.step(true);
    g_rec = nullptr;
    for (long k = fences; k < fence_count(); ++k) r.fences.push_back("fdem::fence");
  }
  EXPECT_FALSE(r.fences.empty());
  EXPECT_FALSE(r.copies.empty());
  EXPECT_FALSE(r.host_reductions.empty());
  EXPECT_GT(r.launches, 0);
}

// Kokkos 3.4.1 reports no fence of a host backend to the hooks: every fence in src/ and kernels/
// goes through fdem::fence (kernels/fdem_kokkos.hpp), which counts them.
TEST(GpuReady, EveryFenceIsCounted) {
  namespace fs = std::filesystem;
  std::vector<std::string> raw;
  for (const char* dir : {"src", "kernels"})
    for (const auto& e : fs::recursive_directory_iterator(fs::path(FDEM_SOURCE_DIR) / dir)) {
      if (!e.is_regular_file() || e.path().filename() == "fdem_kokkos.hpp") continue;
      std::ifstream in(e.path());
      std::string line;
      for (int n = 1; std::getline(in, line); ++n)
        if (line.find("Kokkos::fence") != std::string::npos || line.find(".fence()") != std::string::npos)
          raw.push_back(e.path().string() + ":" + std::to_string(n));
    }
  EXPECT_TRUE(raw.empty()) << "fences not counted (use fdem::fence):" << list(raw);
}

}  // namespace
