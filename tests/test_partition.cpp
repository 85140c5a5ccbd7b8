// Element partitions (src/parallel/partition.hpp): every element in exactly one part, balanced
// load, the counts of the statistics against brute force, METIS against a plain index split,
// determinism, continuous regions (shared faces), and `fdem partition` with bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/error.hpp"
#include "io/case.hpp"
#include "io/output.hpp"
#include "mesh/mesh.hpp"
#include "mesh/refine.hpp"
#include "parallel/partition.hpp"
#include "solver/run.hpp"
#include "test_files.hpp"

namespace {

using fdem::HostMesh;
using fdem::PartitionMethod;

// The shipped cases' meshes as a run prepares them: the Brazilian disc at its own element size
// (Gmsh disc, symmetric about its loaded diameter, 2342 triangles) and the 3D impact's sphere at
// h = 6 mm (coarse: 1844 tetrahedra).
const HostMesh& disc() {
  static const HostMesh m =
      fdem::prepare_mesh(fdem::load_case(std::string(FDEM_SOURCE_DIR) + "/cases/brazilian_disc/case.json"));
  return m;
}
const HostMesh& sphere() {
  static const HostMesh m = fdem::prepare_mesh(fdem::load_case(
      std::string(FDEM_SOURCE_DIR) + "/cases/particle_impact_3d/case.json", {"parameters.h=0.006"}));
  return m;
}

long brute_force_cut(const HostMesh& m, const std::vector<int>& part) {
  long cut = 0;
  for (int i = 0; i < m.num_ifaces(); ++i)
    cut += part[m.iface_elems[2 * i]] != part[m.iface_elems[2 * i + 1]];
  return cut;
}

const PartitionMethod kMethods[] = {PartitionMethod::Metis, PartitionMethod::Rcb, PartitionMethod::Block};

TEST(Partition, EveryElementInExactlyOnePartInRange) {
  for (const HostMesh* m : {&disc(), &sphere()}) {
    ASSERT_GT(m->num_elems(), 1500);
    ASSERT_GT(m->num_ifaces(), m->num_elems());  // fully fracturable: interfaces on every internal face
    for (PartitionMethod method : kMethods)
      for (int n : {1, 2, 3, 8}) {
        const auto part = fdem::partition_elements(*m, n, method);
        ASSERT_EQ(static_cast<int>(part.size()), m->num_elems());
        std::vector<long> count(n, 0);
        for (int p : part) {
          ASSERT_GE(p, 0);
          ASSERT_LT(p, n);
          ++count[p];
        }
        for (int p = 0; p < n; ++p)
          EXPECT_GT(count[p], 0) << fdem::partition_method_name(method) << " n " << n;
        const auto s = fdem::partition_stats(*m, part, n);
        EXPECT_EQ(s.elements_per_part, count);
      }
  }
}

// Load = elements + the interfaces whose side A they are (the work model, partition.hpp). METIS is
// asked for 1 % (UFACTOR 10; granularity adds to it); the bisection splits at the weighted median.
TEST(Partition, LoadImbalanceBelowFivePercent) {
  for (const HostMesh* m : {&disc(), &sphere()})
    for (PartitionMethod method : {PartitionMethod::Metis, PartitionMethod::Rcb})
      for (int n : {2, 4, 8, 16}) {
        const auto s = fdem::partition_stats(*m, fdem::partition_elements(*m, n, method), n);
        EXPECT_LT(s.imbalance, 0.05) << fdem::partition_method_name(method) << " dim " << m->dim << " n "
                                     << n;
        if (method == PartitionMethod::Metis) {
          EXPECT_LT(s.imbalance, 0.02) << "METIS asked for 1 %, n " << n;
        }
        EXPECT_GE(s.imbalance, 0.0);
      }
}

// The cut during a run (solver/run.cpp) is weighted by each element's modelled work: the contact
// work of a node is shared among its elements, and the bisection splits at the weighted median, so
// with the sphere's lowest tenth of nodes carrying as much contact work as all the elements
// together, every part's work is within a few elements' work of an equal share although the
// element counts differ by more than half.
TEST(Partition, WeightedBisectionBalancesTheWorkNotTheElements) {
  const HostMesh& m = sphere();
  const std::vector<double> base = fdem::element_work(m, {});
  const int nv = m.dim + 1;
  const fdem::WorkModel wm;  // the defaults
  for (int e = 0; e < 3; ++e) {  // each element's own work: bulk, its nodes, side-A interfaces
    int side_a = 0;
    for (int i = 0; i < m.num_ifaces(); ++i) side_a += m.iface_elems[2 * static_cast<size_t>(i)] == e;
    EXPECT_DOUBLE_EQ(base[e], wm.element + nv * wm.node +
                                  side_a * wm.interface);
  }
  {  // the interfaces handed over to contact count for nothing: one flag takes one interface's work
    // off its side-A element and nothing else; every flag leaves the bulk and the nodes alone
    std::vector<long long> handed(m.num_ifaces(), 0);
    const int q = m.num_ifaces() / 2, a = m.iface_elems[2 * static_cast<size_t>(q)];
    handed[q] = 1;
    const std::vector<double> one = fdem::element_work(m, {}, handed);
    for (int e = 0; e < m.num_elems(); ++e)
      EXPECT_DOUBLE_EQ(one[e], base[e] - (e == a ? wm.interface : 0.0));
    std::fill(handed.begin(), handed.end(), 1);
    for (double x : fdem::element_work(m, {}, handed))
      EXPECT_DOUBLE_EQ(x, wm.element + nv * wm.node);
    EXPECT_THROW(fdem::element_work(m, {}, std::vector<long long>(3, 0)), fdem::InputError);
    // a case's own model (parallel.work_model): the interfaces alone, at 1 ns each
    fdem::WorkModel only;
    only.element = only.node = 1e-300;
    only.interface = 1;
    const std::vector<double> own = fdem::element_work(m, {}, {}, only);
    for (int e = 0; e < m.num_elems(); ++e)
      EXPECT_NEAR(own[e], (base[e] - wm.element - nv * wm.node) / wm.interface, 1e-12);
  }
  double total = 0, biggest = 0;
  for (double w : base) total += w;
  // contact work on the lowest tenth of the nodes (where a falling sphere meets the plate)
  std::vector<int> order(m.num_nodes());
  for (int n = 0; n < m.num_nodes(); ++n) order[n] = n;
  std::sort(order.begin(), order.end(), [&](int a, int b) { return m.X[3 * a + 2] < m.X[3 * b + 2]; });
  std::vector<double> node_work(m.num_nodes(), 0.0);
  const int low = m.num_nodes() / 10;
  for (int k = 0; k < low; ++k) node_work[order[k]] = total / low;
  const std::vector<double> w = fdem::element_work(m, node_work);
  double with = 0;
  for (double x : w) {
    with += x;
    biggest = std::max(biggest, x);
  }
  EXPECT_NEAR(with, 2 * total, 1e-9 * total);  // every node's work shared out once
  for (int n : {2, 3, 4, 8}) {
    const std::vector<int> part = fdem::partition_elements_weighted(m, n, w);
    std::vector<double> work(n, 0.0);
    std::vector<long> count(n, 0);
    for (int e = 0; e < m.num_elems(); ++e) {
      ASSERT_GE(part[e], 0);
      ASSERT_LT(part[e], n);
      work[part[e]] += w[e];
      ++count[part[e]];
    }
    const double share = with / n;
    for (int p = 0; p < n; ++p) EXPECT_LT(std::fabs(work[p] - share), 3 * biggest) << "n " << n << " part " << p;
    // unweighted, the same bisection leaves the parts at the bottom with far more than their share
    // (from 4 parts on: the sphere's first cut may run through the bottom and halve it)
    const std::vector<int> plain = fdem::partition_elements(m, n, PartitionMethod::Rcb);
    std::vector<double> plain_work(n, 0.0);
    for (int e = 0; e < m.num_elems(); ++e) plain_work[plain[e]] += w[e];
    const double plain_most = *std::max_element(plain_work.begin(), plain_work.end());
    EXPECT_LE(*std::max_element(work.begin(), work.end()), plain_most + 3 * biggest) << "n " << n;
    if (n >= 4) {
      EXPECT_GT(plain_most, 1.3 * share) << "n " << n;
      const auto [lo, hi] = std::minmax_element(count.begin(), count.end());
      EXPECT_GT(static_cast<double>(*hi) / *lo, 1.5) << "n " << n << ": the element counts follow the work";
    }
  }
  EXPECT_EQ(fdem::partition_elements_weighted(m, 4, w), fdem::partition_elements_weighted(m, 4, w));
  std::vector<double> bad = w;
  bad[7] = 0;
  EXPECT_THROW(fdem::partition_elements_weighted(m, 2, bad), fdem::InputError);
  EXPECT_THROW(fdem::partition_elements_weighted(m, 2, std::vector<double>(5, 1.0)), fdem::InputError);
  EXPECT_THROW(fdem::partition_elements_weighted(m, 0, w), fdem::InputError);
  EXPECT_THROW(fdem::element_work(m, std::vector<double>(3, 1.0)), fdem::InputError);
}

TEST(Partition, CutAndGhostCountsMatchBruteForce) {
  for (const HostMesh* m : {&disc(), &sphere()})
    for (PartitionMethod method : kMethods) {
      const int n = 5;
      const auto part = fdem::partition_elements(*m, n, method);
      const auto s = fdem::partition_stats(*m, part, n);
      const long cut = brute_force_cut(*m, part);
      EXPECT_EQ(s.interfaces_cut, cut);
      EXPECT_GT(cut, 0);
      EXPECT_EQ(s.shared_faces, 0);
      std::vector<std::set<int>> ghosts(n), nodes(n);
      const int d = m->dim;
      for (int i = 0; i < m->num_ifaces(); ++i) {
        const int a = m->iface_elems[2 * i], b = m->iface_elems[2 * i + 1];
        if (part[a] == part[b]) continue;
        ghosts[part[a]].insert(b);
        ghosts[part[b]].insert(a);
        for (int k = 0; k < d; ++k) {
          nodes[part[a]].insert(m->ifaces[2 * d * i + d + k]);  // side B's nodes, for A's part
          nodes[part[b]].insert(m->ifaces[2 * d * i + k]);
        }
      }
      long total = 0, total_nodes = 0;
      for (int p = 0; p < n; ++p) {
        EXPECT_EQ(s.ghosts_per_part[p], static_cast<long>(ghosts[p].size()));
        EXPECT_EQ(s.ghost_nodes_per_part[p], static_cast<long>(nodes[p].size()));
        total += ghosts[p].size();
        total_nodes += nodes[p].size();
      }
      EXPECT_EQ(s.ghosts, total);
      // every cut interface is computed twice (both parts): the work is the load plus the cut
      long load = 0, work = 0;
      for (int p = 0; p < n; ++p) {
        load += s.load_per_part[p];
        work += s.work_per_part[p];
        EXPECT_GE(s.work_per_part[p], s.load_per_part[p]);
      }
      EXPECT_EQ(load, m->num_elems() + m->num_ifaces());
      EXPECT_EQ(work, load + cut);
      EXPECT_EQ(s.ghost_nodes, total_nodes);
      // a ghost node lies on at least one cut face, and each cut face brings dim of them to each side
      EXPECT_LE(s.ghost_nodes, 2L * d * cut);
      EXPECT_GT(s.ghost_nodes, 0);
    }
}

// METIS minimises the cut; the contiguous index split (Morton order) is the naive alternative.
TEST(Partition, MetisCutsNoMoreInterfacesThanAnIndexSplit) {
  for (const HostMesh* m : {&disc(), &sphere()})
    for (int n : {2, 4, 8, 16}) {
      const long metis = brute_force_cut(*m, fdem::partition_elements(*m, n, PartitionMethod::Metis));
      const long block = brute_force_cut(*m, fdem::partition_elements(*m, n, PartitionMethod::Block));
      EXPECT_LE(metis, block) << "dim " << m->dim << " n " << n;
    }
}

TEST(Partition, SameResultTwice) {
  for (const HostMesh* m : {&disc(), &sphere()})
    for (PartitionMethod method : kMethods)
      EXPECT_EQ(fdem::partition_elements(*m, 7, method), fdem::partition_elements(*m, 7, method));
}

// Without interfaces (a continuous region) the elements share nodes: the graph's edges are the
// shared faces. Crossed rectangle 4 x 2 cells: 32 triangles; internal edges = (3 * 32 - 12) / 2 = 42.
TEST(Partition, ContinuousRegionsAreJoinedByTheirSharedFaces) {
  const HostMesh m = fdem::generate_crossed_rectangle(0, 0, 4, 2, 4, 2);
  ASSERT_EQ(m.num_elems(), 32);
  ASSERT_EQ(m.num_ifaces(), 0);
  const auto part = fdem::partition_elements(m, 2, PartitionMethod::Rcb);
  const auto s = fdem::partition_stats(m, part, 2);
  EXPECT_EQ(s.shared_faces, 42);
  EXPECT_EQ(s.interfaces_cut, 0);
  // the bisection splits the 4 x 2 rectangle at x = 2: the cut runs along 2 cell edges
  EXPECT_EQ(s.shared_faces_cut, 2);
  EXPECT_EQ(s.elements_per_part, (std::vector<long>{16, 16}));
  EXPECT_EQ(s.ghosts_per_part, (std::vector<long>{2, 2}));
}

TEST(Partition, BadArgumentsThrowInputErrorNamingTheOption) {
  const HostMesh& m = disc();
  for (int n : {0, -3, m.num_elems() + 1}) {
    try {
      fdem::partition_elements(m, n, PartitionMethod::Metis);
      ADD_FAILURE() << "no error for " << n;
    } catch (const fdem::InputError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find("--parts"), std::string::npos) << msg;
      EXPECT_NE(msg.find("[1, " + std::to_string(m.num_elems()) + "]"), std::string::npos) << msg;
    }
  }
  EXPECT_THROW(fdem::parse_partition_method("scotch"), fdem::InputError);
  EXPECT_EQ(static_cast<int>(fdem::partition_elements(m, m.num_elems(), PartitionMethod::Rcb).size()),
            m.num_elems());
}

// Zoltan's geometric partitioners where the build has them (-DFDEM_ENABLE_MPI=ON); else the
// method is refused with a message naming the build option.
TEST(Partition, ZoltanMethodsBalancedOrRefusedNamingTheBuildOption) {
  if (!fdem::partition_has_zoltan()) {
    try {
      fdem::parse_partition_method("zoltan-rcb");
      ADD_FAILURE() << "zoltan-rcb accepted by a build without Zoltan";
    } catch (const fdem::InputError& e) {
      EXPECT_NE(std::string(e.what()).find("FDEM_ENABLE_MPI"), std::string::npos) << e.what();
    }
    return;
  }
  for (const char* name : {"zoltan-rcb", "zoltan-rib", "zoltan-hsfc"})
    for (const HostMesh* m : {&disc(), &sphere()}) {
      const int n = 8;
      const auto part = fdem::partition_elements(*m, n, fdem::parse_partition_method(name));
      const auto s = fdem::partition_stats(*m, part, n);
      for (int p : part) ASSERT_TRUE(p >= 0 && p < n);
      for (long c : s.elements_per_part) EXPECT_GT(c, 0) << name;
      EXPECT_LT(s.imbalance, 0.05) << name;
      EXPECT_EQ(s.interfaces_cut, brute_force_cut(*m, part));
    }
}

TEST(Partition, MigratedElementsIgnoreRenamedParts) {
  const std::vector<int> before{0, 0, 1, 1, 2, 2};
  EXPECT_EQ(fdem::migrated_elements(before, {2, 2, 0, 0, 1, 1}, 3), 0);
  EXPECT_EQ(fdem::migrated_elements(before, {2, 2, 0, 1, 1, 1}, 3), 1);
  // each part of `after` holds one element of two parts of `before`: renamed, it keeps one of them
  EXPECT_EQ(fdem::migrated_elements(before, {0, 1, 2, 0, 1, 2}, 3), 3);
}

// A rigid translation moves no element under a geometric method, nor (the graph unchanged) under
// METIS; failed interfaces leave the graph and the counts.
TEST(Partition, MovedMeshTranslatedMovesNothingAndDropsFailedInterfaces) {
  const HostMesh& m = disc();
  std::vector<double> x(3 * static_cast<size_t>(m.num_nodes()), 0.0);
  for (int n = 0; n < m.num_nodes(); ++n)
    for (int k = 0; k < 2; ++k) x[3 * n + k] = m.X[2 * n + k] + (k == 0 ? 0.75 : -0.25);
  std::vector<double> damage(m.num_ifaces(), 0.0);
  const HostMesh same = fdem::moved_mesh(m, x, damage);
  EXPECT_EQ(same.num_ifaces(), m.num_ifaces());
  for (PartitionMethod method : {PartitionMethod::Metis, PartitionMethod::Rcb}) {
    const auto a = fdem::partition_elements(m, 6, method), b = fdem::partition_elements(same, 6, method);
    EXPECT_EQ(fdem::migrated_elements(a, b, 6), 0) << fdem::partition_method_name(method);
  }
  for (int i = 0; i < 40; ++i) damage[3 * i] = 1.0;
  damage[1] = 0.99;  // damaged, not failed: stays
  const HostMesh cracked = fdem::moved_mesh(m, x, damage);
  EXPECT_EQ(cracked.num_ifaces(), m.num_ifaces() - 40);
  const auto part = fdem::partition_elements(cracked, 4, PartitionMethod::Metis);
  EXPECT_EQ(fdem::partition_stats(cracked, part, 4).interfaces_cut, brute_force_cut(cracked, part));
}

// The command: files written, exit 2 with a message naming the option for bad input.
TEST(Partition, CommandWritesStatsAndRejectsBadInput) {
  namespace fs = std::filesystem;
  using fdem::test::slurp;
  using fdem::test::system_status;
  const std::string dir = fdem::test::scratch_dir("partition", "cli");
  const std::string disc_case = std::string(FDEM_SOURCE_DIR) + "/cases/brazilian_disc/case.json";
  const std::string fdem = std::string("OMP_NUM_THREADS=1 ") + FDEM_BINARY + " partition " + disc_case;
  ASSERT_EQ(system_status(fdem + " --parts 4 --out " + dir + " > " + dir + ".log 2>&1"), 0)
      << slurp(dir + ".log");
  const auto j = nlohmann::json::parse(slurp(dir + "/partition.json"));
  EXPECT_EQ(j["method"], "metis");
  EXPECT_EQ(j["parts"], 4);
  EXPECT_EQ(j["elements"], disc().num_elems());
  EXPECT_EQ(j["interfaces_cut"].get<long>(),
            fdem::partition_stats(disc(), fdem::partition_elements(disc(), 4, PartitionMethod::Metis), 4)
                .interfaces_cut);
  EXPECT_EQ(slurp(dir + "/partition.vtk").rfind("# vtk DataFile", 0), 0u);
  EXPECT_NE(slurp(dir + ".log").find("interfaces cut"), std::string::npos);

  const std::string range = "[1, " + std::to_string(disc().num_elems()) + "]";  // at most the elements
  const std::pair<std::string, std::vector<std::string>> bad[] = {
      {"--parts 0", {"--parts 0", "[1, "}},
      {"--parts 999999", {"--parts 999999", range}},
      {"--parts 4 --method scotch", {"--method 'scotch'", "metis, rcb, block"}},
  };
  for (const auto& [args, words] : bad) {
    EXPECT_EQ(system_status(fdem + " " + args + " --out " + dir + " > " + dir + ".err 2>&1"), 2) << args;
    const std::string err = slurp(dir + ".err");
    for (const auto& w : words) EXPECT_NE(err.find(w), std::string::npos) << args << ": " << err;
  }
  {  // a folder in use by another run or partition (its lock held here) is refused, not raced on
    const fdem::OutputLock held(dir);
    EXPECT_EQ(system_status(fdem + " --parts 4 --out " + dir + " > " + dir + ".err 2>&1"), 2);
    const std::string err = slurp(dir + ".err");
    EXPECT_NE(err.find("is in use by another fdem run"), std::string::npos) << err;
  }
  fs::remove_all(dir);
  fs::remove(dir + ".log");
  fs::remove(dir + ".err");
}

// --snapshot: the rebalance at the last frame of a run of the same case; a snapshot of another
// mesh is refused (exit 2) naming the option.
TEST(Partition, CommandRebalancesAtTheLastSnapshot) {
  using fdem::test::slurp;
  using fdem::test::system_status;
  const std::string dir = fdem::test::scratch_dir("partition", "snapshot");
  const std::string bar = std::string(FDEM_TEST_DATA) + "/cases/bar.json --set output.snapshot_count=2";
  const std::string fdem = std::string("OMP_NUM_THREADS=1 ") + FDEM_BINARY;
  ASSERT_EQ(system_status(fdem + " run " + bar + " --quiet --out " + dir + "/run > " + dir + ".log 2>&1"), 0)
      << slurp(dir + ".log");
  const std::string snap = " --snapshot " + dir + "/run/snapshots.h5";
  ASSERT_EQ(system_status(fdem + " partition " + bar + " --parts 2" + snap + " --out " + dir + "/p > " + dir +
                          ".log 2>&1"),
            0)
      << slurp(dir + ".log");
  const auto j = nlohmann::json::parse(slurp(dir + "/p/partition.json"));
  const auto& r = j["rebalance"];
  EXPECT_GT(r["time"].get<double>(), 0);
  EXPECT_EQ(r["rebalanced"]["elements"], j["elements"]);
  EXPECT_EQ(r["rebalanced"]["interfaces"].get<long>(),
            j["interfaces"].get<long>() - r["failed_interfaces"].get<long>());
  EXPECT_GE(r["migrated_elements"].get<long>(), 0);
  EXPECT_LE(r["migrated_elements"].get<long>(),
            j["elements"].get<long>() / 2);  // after renaming: at most half
  const std::string disc_case = std::string(FDEM_SOURCE_DIR) + "/cases/brazilian_disc/case.json";
  EXPECT_EQ(system_status(fdem + " partition " + disc_case + " --parts 2" + snap + " --out " + dir + "/q > " +
                          dir + ".err 2>&1"),
            2);
  const std::string err = slurp(dir + ".err");
  EXPECT_NE(err.find("--snapshot"), std::string::npos) << err;
  EXPECT_NE(err.find("not of this mesh"), std::string::npos) << err;
  std::filesystem::remove_all(dir);
  std::filesystem::remove(dir + ".log");
  std::filesystem::remove(dir + ".err");
}

}  // namespace

// A refined mesh is partitioned on its coarse mesh's graph (partition_elements' group: each coarse
// element's 8 children stay in one part), as balanced as METIS on the fine graph and cutting about
// as many interfaces (measured on the 3D impact's sphere at 8 mm refined once, 4 parts).
TEST(Partition, RefinedMeshPartitionedByItsCoarseElements) {
  if (!fdem::partition_has_metis()) GTEST_SKIP() << "built without METIS";
  fdem::HostMesh mesh = fdem::generate_sphere({0, 0, 0}, 0.025, 0.008);
  fdem::reorder_for_locality(mesh);
  mesh = fdem::refine_mesh(mesh, 1, {{{0, 0, 0}, 0.025}});
  fdem::reorder_for_locality(mesh, false);
  fdem::insert_interfaces(mesh, {true});
  const int parts = 4, ne = mesh.num_elems();
  const std::vector<int> grouped = fdem::partition_elements(mesh, parts, fdem::PartitionMethod::Metis, 8);
  const std::vector<int> fine = fdem::partition_elements(mesh, parts, fdem::PartitionMethod::Metis);
  for (int e = 0; e < ne; ++e) ASSERT_EQ(grouped[e], grouped[e / 8 * 8]) << "element " << e;
  const fdem::PartitionStats g = fdem::partition_stats(mesh, grouped, parts);
  const fdem::PartitionStats f = fdem::partition_stats(mesh, fine, parts);
  EXPECT_LT(g.imbalance, 0.03);
  EXPECT_LT(g.interfaces_cut, 1.3 * f.interfaces_cut);
  std::printf("refined sphere, %d elements, 4 parts: by coarse elements %ld cut, imbalance %.4f; "
              "fine graph %ld cut, imbalance %.4f\n",
              ne, g.interfaces_cut, g.imbalance, f.interfaces_cut, f.imbalance);
  // too few groups for the parts (fewer than 8 each): the fine graph
  const int many = ne / 8 / 8 + 1;
  EXPECT_EQ(fdem::partition_elements(mesh, many, fdem::PartitionMethod::Metis, 8),
            fdem::partition_elements(mesh, many, fdem::PartitionMethod::Metis));
}

// The partition of a refined mesh from its coarse mesh alone (partition_coarse, what every process
// of a run computes before any refines): balanced, cutting about as few interfaces as METIS on the
// whole fine graph, the same twice, and refused for more parts than coarse elements.
TEST(Partition, RefinedMeshPartitionedFromItsCoarseMeshAlone) {
  const double R = 0.025;
  fdem::HostMesh coarse = fdem::generate_sphere({0, 0, 0}, R, 0.008);
  fdem::reorder_for_locality(coarse);
  const std::vector<fdem::CurvedSurface> s{{{0, 0, 0}, R}};
  fdem::HostMesh mesh = fdem::refine_mesh(coarse, 1, s);
  fdem::insert_interfaces(mesh, {true});
  const fdem::CoarseTopology topo = fdem::coarse_topology(coarse, 1, s);
  const std::vector<std::int64_t> off = fdem::refined_interface_offsets(coarse, topo);
  const int parts = 4, ne = mesh.num_elems();
  std::vector<fdem::PartitionMethod> methods{fdem::PartitionMethod::Rcb};
  if (fdem::partition_has_metis()) methods.push_back(fdem::PartitionMethod::Metis);
  for (const fdem::PartitionMethod m : methods) {
    SCOPED_TRACE(fdem::partition_method_name(m));
    const std::vector<int> cpart = fdem::partition_coarse(coarse, topo, off, parts, m);
    ASSERT_EQ(cpart.size(), static_cast<size_t>(coarse.num_elems()));
    EXPECT_EQ(cpart, fdem::partition_coarse(coarse, topo, off, parts, m));
    std::vector<int> fine(ne);
    for (int e = 0; e < ne; ++e) fine[e] = cpart[e / 8];
    const fdem::PartitionStats g = fdem::partition_stats(mesh, fine, parts);
    for (long n : g.elements_per_part) EXPECT_GT(n, 0);
    EXPECT_LT(g.imbalance, 0.05);
    if (m == fdem::PartitionMethod::Metis) {
      const fdem::PartitionStats f = fdem::partition_stats(mesh, fdem::partition_elements(mesh, parts, m), parts);
      EXPECT_LT(g.interfaces_cut, 1.3 * f.interfaces_cut);
    }
  }
  EXPECT_THROW(fdem::partition_coarse(coarse, topo, off, coarse.num_elems() + 1, fdem::PartitionMethod::Rcb),
               fdem::InputError);
}
