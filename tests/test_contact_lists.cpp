// Candidate lists of contact across handovers (kernels/contact/list_update.hpp): a handover of
// failed interfaces updates the lists by a local search at the build positions instead of a
// rebuild; the result must be the list a full search at those positions gives, with the history
// of every pair that stays.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "common/error.hpp"
#include "scenes.hpp"
#include "solver/simulation.hpp"
#include "solver_fixtures.hpp"

namespace {

using namespace fdem;
using fdem_test::cracked_block;
using fdem_test::fail_interfaces;
using fdem_test::pressed_case;

// A host copy of the candidate lists: per node, face -> history (fn, ac, g0, fs).
using PairMap = std::map<std::pair<int, int>, std::vector<double>>;
template <int D>
PairMap host_pairs(const ContactSystem<D>& ct, int nn) {
  const PairList<D>& P = ct.pairs();
  auto off = fdem_test::host_view(P.off);
  auto face = fdem_test::host_view(P.face);
  auto fn = fdem_test::host_view(P.fn);
  auto ac = fdem_test::host_view(P.ac);
  auto g0 = fdem_test::host_view(P.g0);
  auto fs = fdem_test::host_view(P.fs);
  PairMap out;
  for (int s = 0; s < nn; ++s)
    for (int j = off(s); j < off(s + 1); ++j) {
      std::vector<double> h = {fn(j), ac(j), g0(j)};
      for (int k = 0; k < D; ++k) h.push_back(fs(j, k));
      out[{s, face(j)}] = h;
    }
  return out;
}

template <int D>
void local_update_test() {
  const HostMesh mesh = cracked_block<D>(D == 2 ? 6 : 3);
  Simulation<D> sim(pressed_case<D>(0.004), mesh);
  ContactSystem<D>* ct = sim.contact();
  ASSERT_NE(ct, nullptr);
  // a third of the interfaces fail first: pieces in contact, lists built, contacts with history
  fail_interfaces(sim, [](int q) { return q % 3 == 0; });
  ct->check_failures(sim.m);
  fdem_test::shake(sim, 0.2);
  for (int s = 0; s < 60; ++s) sim.step(s % 20 == 0);
  const long builds = ct->builds();
  ASSERT_GE(builds, 1);
  ASSERT_EQ(ct->list_updates(), 0);
  const int ns_before = ct->surface_nodes();
  const PairMap before = host_pairs(*ct, sim.m.nn);
  int touching = 0;
  for (const auto& [key, h] : before) touching += h[0] > 0.0 ? 1 : 0;
  ASSERT_GT(touching, 0) << "the pieces should touch";

  // another third fails: a local update, no rebuild
  fail_interfaces(sim, [](int q) { return q % 3 == 1; });
  ct->check_failures(sim.m);
  EXPECT_EQ(ct->builds(), builds);
  EXPECT_EQ(ct->list_updates(), 1);
  EXPECT_GT(ct->surface_nodes(), ns_before);
  const PairMap updated = host_pairs(*ct, sim.m.nn);
  EXPECT_GT(updated.size(), before.size());

  // every pair that stays keeps its history, bit for bit; new pairs start without history
  int kept = 0, kept_touching = 0;
  for (const auto& [key, h] : updated) {
    const auto it = before.find(key);
    if (it == before.end()) {
      for (double v : h) EXPECT_EQ(v, 0.0);
      continue;
    }
    ++kept;
    kept_touching += h[0] > 0.0 ? 1 : 0;
    EXPECT_EQ(h, it->second) << "node " << key.first << ", face " << key.second;
  }
  EXPECT_GT(kept, 0);
  EXPECT_EQ(kept_touching, touching);

  // the same pairs as a full search at the build positions
  auto x = Kokkos::create_mirror(sim.m.x);  // copies (create_mirror_view would alias on the host)
  Kokkos::deep_copy(x, sim.m.x);
  auto xb = Kokkos::create_mirror(ct->build_positions());
  Kokkos::deep_copy(xb, ct->build_positions());
  auto xmove = Kokkos::create_mirror(sim.m.x);
  double moved = 0;
  for (int i = 0; i < sim.m.nn; ++i)
    for (int k = 0; k < D; ++k) {
      xmove(i, k) = xb(i, k);
      moved = std::max(moved, std::abs(x(i, k) - xb(i, k)));
    }
  EXPECT_GT(moved, 0.0) << "the nodes should have moved since the build";
  Kokkos::deep_copy(sim.m.x, xmove);
  ct->build(sim.m);
  const PairMap full = host_pairs(*ct, sim.m.nn);
  Kokkos::deep_copy(sim.m.x, x);
  EXPECT_EQ(full.size(), updated.size());
  int missing = 0, extra = 0;
  for (const auto& [key, h] : full) missing += updated.count(key) ? 0 : 1;
  for (const auto& [key, h] : updated) extra += full.count(key) ? 0 : 1;
  EXPECT_EQ(missing, 0) << "pairs of the full search that the local update missed";
  EXPECT_EQ(extra, 0) << "pairs of the local update that the full search does not have";
  ct->build(sim.m);  // back to a build at the current positions

  // the rest fails while the run goes on (handed over as they part): updates, no rebuild, passes on
  // up-to-date lists only
  const long handed = ct->handed_over(), builds2 = ct->builds();
  fail_interfaces(sim, [](int q) { return q % 3 == 2; });
  for (int s = 0; s < 60; ++s) sim.step(s % 20 == 0);
  EXPECT_GT(ct->handed_over(), handed);
  EXPECT_GE(ct->list_updates(), 2);
  EXPECT_EQ(ct->builds(), builds2);
  EXPECT_EQ(ct->stale_passes(), 0);
  EXPECT_GT(ct->active_contacts(), 0);
}

TEST(ContactLists, HandoverUpdatesTheListsAsAFullSearchAtTheBuildPositions2D) { local_update_test<2>(); }
TEST(ContactLists, HandoverUpdatesTheListsAsAFullSearchAtTheBuildPositions3D) { local_update_test<3>(); }

// A handover when a surface node is already beyond half the skin from its build position rebuilds.
TEST(ContactLists, HandoverBeyondTheSkinRebuilds) {
  const HostMesh mesh = cracked_block<2>(4);
  Simulation<2> sim(pressed_case<2>(0.004), mesh);
  ContactSystem<2>* ct = sim.contact();
  fail_interfaces(sim, [](int q) { return q % 2 == 0; });
  ct->check_failures(sim.m);
  for (int s = 0; s < 5; ++s) sim.step(false);
  const long builds = ct->builds();
  auto x = Kokkos::create_mirror_view(sim.m.x);
  Kokkos::deep_copy(x, sim.m.x);
  for (int i = 0; i < sim.m.nn; ++i) x(i, 0) += 0.6 * ct->skin;  // a rigid shift beyond half the skin
  Kokkos::deep_copy(sim.m.x, x);
  fail_interfaces(sim, [](int q) { return q % 2 == 1; });
  ct->check_failures(sim.m);
  EXPECT_EQ(ct->list_updates(), 0);
  sim.step(false);
  EXPECT_EQ(ct->builds(), builds + 1);
  EXPECT_EQ(ct->stale_passes(), 0);
}

// The cracked block pressed by its platen with every other interface failed and handed over, shaken,
// 150 steps (a sample every 25): the scene of the narrow phase's comparisons below. setup(contact)
// sets the contact system's options first.
template <int D, class Setup>
std::unique_ptr<Simulation<D>> pressed_cracked_run(const HostMesh& mesh, double skin, const Setup& setup) {
  auto sim = std::make_unique<Simulation<D>>(pressed_case<D>(skin), mesh);
  ContactSystem<D>* ct = sim->contact();
  setup(*ct);
  fail_interfaces(*sim, [](int q) { return q % 2 == 0; });
  ct->check_failures(sim->m);
  fdem_test::shake(*sim, 0.2);
  for (int s = 0; s < 150; ++s) sim->step(s % 25 == 0);
  return sim;
}

// The narrow phase visits only the pairs that can matter (kernels/contact/narrow_phase.hpp,
// PairSubset): so a skin 400 times smaller (many rebuilds, a fraction of the candidates) and
// subsets that overflow (1 pair per node, then all candidates) must give the same run, bit for
// bit, as a large skin that never rebuilds: positions, velocities, contact energies, histories.
template <int D>
void narrow_phase_exact_test() {
  const HostMesh mesh = cracked_block<D>(D == 2 ? 6 : 3);
  auto run = [&](double skin, bool small) {
    return pressed_cracked_run<D>(mesh, skin, [&](ContactSystem<D>& ct) { ct.small_subsets = small; });
  };
  const auto ref = run(0.004, false), fine = run(1e-5, false), over = run(0.004, true);
  const ContactSystem<D>& c0 = *ref->contact();
  const ContactSystem<D>& c1 = *fine->contact();
  const ContactSystem<D>& c2 = *over->contact();
  EXPECT_EQ(c0.builds(), 1);
  EXPECT_GE(c1.builds(), 4) << "the small skin should rebuild the lists several times";
  // fewer candidates in 2D; on this coarse 3D block the grown face boxes hold the same pairs
  EXPECT_LE(c1.candidates(), c0.candidates());
  if (D == 2) {
    EXPECT_LT(c1.candidates(), c0.candidates());
  }
  EXPECT_EQ(c1.stale_passes(), 0);
  ASSERT_GT(c0.active_contacts(), 0);
  // nodes with more than one contact: their subsets overflow in the third run
  int crowded = 0;
  {
    auto off = fdem_test::host_view(c0.pairs().off);
    auto fn = fdem_test::host_view(c0.pairs().fn);
    for (int s = 0; s < ref->m.nn; ++s) {
      int n = 0;
      for (int j = off(s); j < off(s + 1); ++j) n += fn(j) > 0.0 ? 1 : 0;
      crowded += n > 1 ? 1 : 0;
    }
  }
  EXPECT_GT(crowded, 0);
  const auto x0 = fdem_test::host_view(ref->m.x), v0 = fdem_test::host_view(ref->m.v);
  for (Simulation<D>* other : {fine.get(), over.get()}) {
    const auto x = fdem_test::host_view(other->m.x), v = fdem_test::host_view(other->m.v);
    int differ = 0;
    for (int i = 0; i < ref->m.nn; ++i)
      for (int k = 0; k < D; ++k) differ += x(i, k) != x0(i, k) || v(i, k) != v0(i, k) ? 1 : 0;
    EXPECT_EQ(differ, 0);
    EXPECT_EQ(other->contact()->active_contacts(), c0.active_contacts());
    EXPECT_EQ(other->contact()->elastic_energy(), c0.elastic_energy());
    EXPECT_EQ(other->contact()->dissipated(), c0.dissipated());
  }
  EXPECT_EQ(host_pairs(c2, over->m.nn), host_pairs(c0, ref->m.nn));
}

// The narrow phase by teams (ContactTeamPoints, the GPUs' path: the gaps of a point with more
// candidates than team_above shared among a team's threads) gives the plain pass's run: on the
// host threads the points go to other threads (so the sums add in another order), hence to
// round-off: positions within 1e-12 of the block's size (4 cm) after 150 steps, the same contacts, the
// energies to 1e-9. team_above 1: nearly every point with candidates takes the team path. Also the
// candidates' spread of summary.json against a count on the host.
template <int D>
void narrow_phase_teams_test() {
  const HostMesh mesh = cracked_block<D>(D == 2 ? 6 : 3);
  auto run = [&](int above) {
    return pressed_cracked_run<D>(mesh, 0.004, [&](ContactSystem<D>& ct) { ct.team_above = above; });
  };
  const auto ref = run(0), teams = run(1);
  const ContactSystem<D>& c0 = *ref->contact();
  const ContactSystem<D>& c1 = *teams->contact();
  ASSERT_GT(c0.active_contacts(), 0);
  int heavy = 0;  // points that took the team path
  {
    // and the spread of the candidates that summary.json reports (ContactSystem::candidate_spread),
    // counted here over every node (those off the surface have none)
    auto off = fdem_test::host_view(c0.pairs().off);
    typename ContactSystem<D>::CandidateSpread expect;
    expect.points = c0.surface_nodes();
    for (int s = 0; s < ref->m.nn; ++s) {
      const int c = off(s + 1) - off(s);
      heavy += c > 1 ? 1 : 0;
      expect.pairs += c;
      expect.max = std::max(expect.max, c);
      for (int k = 0; k < ContactSystem<D>::kSpreadBins; ++k)
        if (c > ContactSystem<D>::kSpreadBounds[k]) {
          ++expect.points_above[k];
          expect.pairs_above[k] += c;
        }
    }
    const auto got = c0.candidate_spread();
    EXPECT_EQ(got.points, expect.points);
    EXPECT_EQ(got.pairs, expect.pairs);
    EXPECT_EQ(got.pairs, c0.candidates());
    EXPECT_EQ(got.max, expect.max);
    EXPECT_GT(got.max, 1);
    for (int k = 0; k < ContactSystem<D>::kSpreadBins; ++k) {
      EXPECT_EQ(got.points_above[k], expect.points_above[k]) << k;
      EXPECT_EQ(got.pairs_above[k], expect.pairs_above[k]) << k;
    }
  }
  EXPECT_GT(heavy, 10);
  const auto x0 = fdem_test::host_view(ref->m.x), x1 = fdem_test::host_view(teams->m.x);
  double dmax = 0;
  for (int i = 0; i < ref->m.nn; ++i)
    for (int k = 0; k < D; ++k) dmax = std::max(dmax, std::abs(x1(i, k) - x0(i, k)));
  {
    const Kokkos::TeamPolicy<ExecSpace> probe(1, 1);
    const int ts = std::min(kNarrowTeamSize,
                            probe.team_size_max(ContactTeamPoints<ContactForcesFn<D, true, kSubsetCap, 1>>{},
                                                Kokkos::ParallelReduceTag()));
    std::cout << D << "D: " << heavy << " points with more than one candidate, teams of " << ts
              << " threads, largest position difference " << dmax << " m\n";
  }
  EXPECT_LT(dmax, 4e-14) << "the block is 4 cm";
  EXPECT_EQ(c1.active_contacts(), c0.active_contacts());
  EXPECT_NEAR(c1.elastic_energy(), c0.elastic_energy(), 1e-9 * std::abs(c0.elastic_energy()));
  EXPECT_NEAR(c1.dissipated(), c0.dissipated(), 1e-9 * std::abs(c0.dissipated()) + 1e-300);
  EXPECT_GT(c0.elastic_energy(), 0.0);
}

// The bound of the team path from the environment (GPUs): a whole number >= 0, else an error that
// names the variable.
TEST(ContactLists, NarrowTeamBoundFromTheEnvironment) {
  EXPECT_EQ(parse_narrow_team_above(nullptr, 16), 16);
  EXPECT_EQ(parse_narrow_team_above("", 16), 16);
  EXPECT_EQ(parse_narrow_team_above("0", 16), 0);
  EXPECT_EQ(parse_narrow_team_above("48", 16), 48);
  for (const char* bad : {"-1", "12x", "abc", "1e3", "99999999"}) {
    try {
      parse_narrow_team_above(bad, 16);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("FDEM_NARROW_TEAM_ABOVE"), std::string::npos) << e.what();
    }
  }
  const bool host = std::is_same<MemSpace, Kokkos::HostSpace>::value;
  EXPECT_EQ(narrow_team_above(),
            host ? 0 : parse_narrow_team_above(std::getenv("FDEM_NARROW_TEAM_ABOVE"), kNarrowTeamAbove));
}

TEST(ContactLists, NarrowPhaseByTeamsGivesThePlainPass2D) { narrow_phase_teams_test<2>(); }
TEST(ContactLists, NarrowPhaseByTeamsGivesThePlainPass3D) { narrow_phase_teams_test<3>(); }

TEST(ContactLists, NarrowPhaseDoesNotDependOnTheSkinOrTheSubsets2D) { narrow_phase_exact_test<2>(); }
TEST(ContactLists, NarrowPhaseDoesNotDependOnTheSkinOrTheSubsets3D) { narrow_phase_exact_test<3>(); }

}  // namespace

// The narrow phase's ranges of equal work on host threads (BalancedPoints,
// kernels/contact/narrow_phase.hpp): every point in exactly one range, each range's work within
// one point's work of an equal share, also when all the work sits in a few points at the end (as
// where a body fragments) and when there are more ranges than threads.
struct VisitCount {
  Kokkos::View<int*> seen;
  KOKKOS_INLINE_FUNCTION void operator()(const int i, ContactSums& s) const {
    Kokkos::atomic_add(&seen(i), 1);
    s.active += 1.0;
  }
};

TEST(ContactLists, NarrowPhaseRangesOfEqualWorkCoverEveryPointOnce) {
  for (const int np : {1, 7, 1000, 4099})
    for (const bool skewed : {false, true})
      for (const int nt : {1, 2, 3, 8}) {
        std::vector<int> w(np);
        for (int i = 0; i < np; ++i)
          w[i] = skewed ? (i >= np - np / 10 - 1 ? 40 + i % 13 : 1) : 1 + (i * 7919) % 37;
        Kokkos::View<int*> work("work", np + 1);
        auto hw = Kokkos::create_mirror_view(work);
        long long total = 0;
        int wmax = 0;
        for (int i = 0; i < np; ++i) {
          hw(i) = static_cast<int>(total);
          total += w[i];
          wmax = std::max(wmax, w[i]);
        }
        hw(np) = static_cast<int>(total);
        Kokkos::deep_copy(work, hw);
        VisitCount fn{Kokkos::View<int*>("seen", np)};
        const BalancedPoints<VisitCount> bp{fn, work, np, nt};
        ContactSums sums;
        Kokkos::parallel_reduce(Kokkos::RangePolicy<ExecSpace>(0, nt), bp, sums);
        auto seen = fdem_test::host_view(fn.seen);
        for (int i = 0; i < np; ++i) ASSERT_EQ(seen(i), 1) << "np " << np << " T " << nt << " point " << i;
        EXPECT_EQ(sums.active, np);
        // the ranges as the functor cuts them (first_at on the host copy; host backends, where they run)
        if (!std::is_same<MemSpace, Kokkos::HostSpace>::value) continue;
        const BalancedPoints<VisitCount> hb{fn, Kokkos::View<int*>(hw.data(), np + 1), np, nt};
        int prev = 0;
        for (int t = 0; t < nt; ++t) {
          const int b = hb.first_at(total * t / nt), e = hb.first_at(total * (t + 1) / nt);
          EXPECT_EQ(b, prev);
          long long range_work = 0;
          for (int i = b; i < e; ++i) range_work += w[i];
          EXPECT_LE(range_work, total / nt + wmax) << "np " << np << " T " << nt << " range " << t;
          prev = e;
        }
        EXPECT_EQ(prev, np);
      }
}
