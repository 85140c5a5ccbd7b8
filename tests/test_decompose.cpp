// Domain decomposition (src/parallel/decompose.hpp, halo.hpp; docs/parallel.md): every item is
// owned once, every part holds what its own nodes' forces need, the exchange lists match, and the
// parts of a decomposed Brazilian disc stepped in one process with the exchange in between follow
// the whole disc: the same time step, positions, energies and platen force to round-off, and every
// cut interface's history the same bits on each part that computes it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "io/case.hpp"
#include "kernels/halo.hpp"
#include "mesh/mesh.hpp"
#include "mesh/pieces.hpp"
#include "parallel/decompose.hpp"
#include "parallel/partition.hpp"
#include "solver/kept_mesh.hpp"
#include "solver/run.hpp"
#include "solver/simulation.hpp"
#include "solver_fixtures.hpp"

namespace {

using namespace fdem;

// The Brazilian disc, coarse (element size 6 mm), loaded fast from contact so that it cracks within
// a few thousand steps; no contact (not across processes yet).
Case fast_disc(HostMesh& mesh) {
  Case c = load_case(FDEM_SOURCE_DIR "/cases/brazilian_disc/case.json",
                     {"mesh.element_size=0.006", "parameters.gap=0", "parameters.approach_rate=4",
                      "parameters.approach=0.0004", "contact={\"enabled\": false}"});
  mesh = prepare_mesh(c);
  resolve_defaults(c, mesh);
  return c;
}

// A box of tetrahedra, fracturable only in its upper half: the lower half's elements share their
// nodes, so a partition cuts through continuous faces too.
HostMesh half_fracturable_box() {
  HostMesh m = generate_box({0, 0, 0}, {1, 1, 1}, 4, 4, 4);
  m.region_names = {"solid", "rock"};
  for (int e = 0; e < m.num_elems(); ++e) {
    double z = 0;
    for (int a = 0; a < 4; ++a) z += m.X[3 * static_cast<size_t>(m.elems[4 * e + a]) + 2] / 4;
    m.elem_region[e] = z > 0.5 ? 1 : 0;
  }
  reorder_for_locality(m);
  insert_interfaces(m, {false, true});
  return m;
}

void check_decomposition(const HostMesh& whole, int parts, PartitionMethod method, double reach = 0) {
  SCOPED_TRACE(std::to_string(parts) + " parts, " + partition_method_name(method) + ", contact reach " +
               std::to_string(reach));
  const std::vector<int> part = partition_elements(whole, parts, method);
  const std::vector<SubMesh> subs = decompose(whole, part, parts, reach);
  ASSERT_EQ(static_cast<int>(subs.size()), parts);
  const int D = whole.dim, nn = whole.num_nodes(), ne = whole.num_elems(), ni = whole.num_ifaces();
  std::vector<int> elem_owned(ne, 0), node_owned(nn, 0), iface_counted(ni, 0);
  // the whole mesh's adjacency: elements and interfaces of each node
  std::vector<std::vector<int>> n2e(nn), n2i(nn);
  for (int e = 0; e < ne; ++e)
    for (int a = 0; a <= D; ++a) n2e[whole.elems[(D + 1) * e + a]].push_back(e);
  for (int q = 0; q < ni; ++q)
    for (int a = 0; a < 2 * D; ++a) n2i[whole.ifaces[2 * D * q + a]].push_back(q);
  for (const SubMesh& s : subs) {
    const HostMesh& m = s.mesh;
    ASSERT_EQ(static_cast<int>(s.node_global.size()), m.num_nodes());
    ASSERT_EQ(static_cast<int>(s.elem_global.size()), m.num_elems());
    ASSERT_EQ(static_cast<int>(s.iface_global.size()), m.num_ifaces());
    for (int e = 0; e < m.owned_elems; ++e) {
      ++elem_owned[s.elem_global[e]];
      EXPECT_EQ(part[s.elem_global[e]], s.part);
    }
    for (int i = 0; i < m.owned_nodes; ++i) ++node_owned[s.node_global[i]];
    for (int q = 0; q < m.owned_ifaces; ++q) ++iface_counted[s.iface_global[q]];
    // local items are the whole mesh's, renumbered
    for (int e = 0; e < m.num_elems(); ++e)
      for (int a = 0; a <= D; ++a)
        ASSERT_EQ(s.node_global[m.elems[(D + 1) * e + a]], whole.elems[(D + 1) * s.elem_global[e] + a]);
    for (int q = 0; q < m.num_ifaces(); ++q)
      for (int a = 0; a < 2 * D; ++a)
        ASSERT_EQ(s.node_global[m.ifaces[2 * D * q + a]], whole.ifaces[2 * D * s.iface_global[q] + a]);
    // every element and interface at an own node is local: its force is complete on its part
    const std::set<int> els(s.elem_global.begin(), s.elem_global.end());
    const std::set<int> ifs(s.iface_global.begin(), s.iface_global.end());
    for (int i = 0; i < m.owned_nodes; ++i) {
      for (int e : n2e[s.node_global[i]]) ASSERT_TRUE(els.count(e)) << "element " << e;
      for (int q : n2i[s.node_global[i]]) ASSERT_TRUE(ifs.count(q)) << "interface " << q;
    }
    // exchange lists: my receive list from q is q's send list to me, node for node
    ASSERT_EQ(s.neighbours.size(), s.recv.size());
    ASSERT_EQ(s.neighbours.size(), s.send.size());
    int ghosts = 0;
    for (size_t k = 0; k < s.neighbours.size(); ++k) {
      const SubMesh& o = subs[s.neighbours[k]];
      const auto it = std::find(o.neighbours.begin(), o.neighbours.end(), s.part);
      ASSERT_NE(it, o.neighbours.end());
      const auto& theirs = o.send[it - o.neighbours.begin()];
      ASSERT_EQ(theirs.size(), s.recv[k].size());
      for (size_t j = 0; j < theirs.size(); ++j) {
        ASSERT_LT(theirs[j], o.mesh.owned_nodes);
        ASSERT_GE(s.recv[k][j], m.owned_nodes);
        ASSERT_EQ(o.node_global[theirs[j]], s.node_global[s.recv[k][j]]);
      }
      ghosts += static_cast<int>(s.recv[k].size());
    }
    EXPECT_EQ(ghosts, s.ghost_nodes() - s.inert_ghosts);  // every ghost a step reads is received, once
    // a step reads the nodes of the elements with a bulk force and of the interfaces: none inert
    const int first_inert = m.num_nodes() - s.inert_ghosts;
    for (int e = 0; e < m.bulk_elems; ++e)
      for (int a = 0; a <= D; ++a) ASSERT_LT(m.elems[(D + 1) * e + a], first_inert);
    for (int n : m.ifaces) ASSERT_LT(n, first_inert);
    // the elements without a bulk force hold no own node
    for (int e = m.bulk_elems; e < m.num_elems(); ++e)
      for (int a = 0; a <= D; ++a) ASSERT_GE(m.elems[(D + 1) * e + a], m.owned_nodes);
  }
  for (int e = 0; e < ne; ++e) ASSERT_EQ(elem_owned[e], 1) << "element " << e;
  for (int n = 0; n < nn; ++n) ASSERT_EQ(node_owned[n], 1) << "node " << n;
  for (int q = 0; q < ni; ++q) ASSERT_EQ(iface_counted[q], 1) << "interface " << q;
}

TEST(Decompose, EveryItemOwnedOnceAndEveryOwnNodeComplete) {
  HostMesh disc;
  fast_disc(disc);
  const HostMesh box = half_fracturable_box();
  ASSERT_GT(box.num_ifaces(), 0);
  for (int parts : {1, 2, 3, 4}) {
    check_decomposition(disc, parts, PartitionMethod::Rcb);
    check_decomposition(box, parts, PartitionMethod::Rcb);
  }
  check_decomposition(disc, 3, PartitionMethod::Block);
  if (partition_has_metis()) check_decomposition(box, 4, PartitionMethod::Metis);
  // with a contact zone the same holds (the zone only adds ghosts)
  check_decomposition(disc, 3, PartitionMethod::Rcb, 2.5 * mesh_quality(disc).mean_size);
  check_decomposition(box, 4, PartitionMethod::Rcb, 0.3);
}

// The distance from point x to element e's bounding box.
double box_distance(const HostMesh& m, int e, const double* x) {
  const int D = m.dim;
  double d2 = 0;
  for (int k = 0; k < D; ++k) {
    double lo = 1e300, hi = -1e300;
    for (int a = 0; a <= D; ++a) {
      const double c = m.X[D * static_cast<size_t>(m.elems[(D + 1) * e + a]) + k];
      lo = std::min(lo, c);
      hi = std::max(hi, c);
    }
    const double d = x[k] < lo ? lo - x[k] : (x[k] > hi ? x[k] - hi : 0.0);
    d2 += d * d;
  }
  return std::sqrt(d2);
}

// The face's node ids, sorted.
std::vector<int> face_key(const std::vector<int>& faces, size_t f, int D, const std::vector<int>* map = nullptr) {
  std::vector<int> k(faces.begin() + f * D, faces.begin() + (f + 1) * D);
  if (map)
    for (int& n : k) n = (*map)[n];
  std::sort(k.begin(), k.end());
  return k;
}

// With contact (decompose's contact reach): each part holds every element whose bounding box comes
// within the reach of one of its own nodes (brute force over all pairs), the interfaces at their
// nodes, and as outer faces exactly the whole mesh's outer faces whose element it holds; every
// ghost is exchanged; the whole mesh's piece count and thinnest element travel with the part.
TEST(Decompose, ContactZoneHoldsEveryElementWithinReach) {
  HostMesh disc;
  fast_disc(disc);
  const HostMesh box = half_fracturable_box();
  for (const HostMesh* whole : std::vector<const HostMesh*>{&disc, &box}) {
    const int D = whole->dim, parts = 3;
    const double reach = (D == 2 ? 2.0 : 0.5) * mesh_quality(*whole).mean_size;
    SCOPED_TRACE(std::to_string(D) + "D, reach " + std::to_string(reach));
    const std::vector<int> part = partition_elements(*whole, parts, PartitionMethod::Rcb);
    const std::vector<SubMesh> subs = decompose(*whole, part, parts, reach);
    const std::vector<int> outer = boundary_faces(*whole);
    std::set<std::vector<int>> outer_keys;
    for (size_t f = 0; f < outer.size() / D; ++f) outer_keys.insert(face_key(outer, f, D));
    const int pieces = count_bodies(*whole);
    int partial = 0;  // parts that hold less than the whole mesh
    for (const SubMesh& s : subs) {
      const HostMesh& m = s.mesh;
      EXPECT_EQ(s.contact_reach, reach);
      EXPECT_EQ(s.inert_ghosts, 0);
      EXPECT_EQ(m.pieces, pieces);
      EXPECT_EQ(m.whole_min_size, mesh_quality(*whole).min_size);
      const std::set<int> els(s.elem_global.begin(), s.elem_global.end());
      const std::set<int> ifs(s.iface_global.begin(), s.iface_global.end());
      int zone = 0;
      for (int e = 0; e < whole->num_elems(); ++e) {
        if (part[e] == s.part) continue;
        double near = 1e300;
        for (int i = 0; i < m.owned_nodes; ++i) near = std::min(near, box_distance(*whole, e, &m.X[D * static_cast<size_t>(i)]));
        if (near > reach) continue;
        ASSERT_TRUE(els.count(e)) << "element " << e << " at " << near << " of an own node";
        ++zone;
        for (int a = 0; a <= D; ++a)  // the interfaces at its nodes
          for (int q = 0; q < whole->num_ifaces(); ++q)
            for (int b = 0; b < 2 * D; ++b) {
              if (whole->ifaces[2 * D * q + b] == whole->elems[(D + 1) * e + a]) {
                ASSERT_TRUE(ifs.count(q)) << q;
              }
            }
      }
      EXPECT_GT(zone, 0);
      // outer faces: whole-mesh outer faces, and all of those whose element the part holds
      std::set<std::vector<int>> mine;
      for (size_t f = 0; f < m.outer_faces.size() / D; ++f) {
        const auto k = face_key(m.outer_faces, f, D, &s.node_global);
        ASSERT_TRUE(outer_keys.count(k));
        mine.insert(k);
      }
      EXPECT_EQ(mine.size(), m.outer_faces.size() / D);  // each once
      for (size_t j = 0; j < s.elem_global.size(); ++j) {
        const int e = s.elem_global[j];
        for (int skip = 0; skip <= D; ++skip) {
          std::vector<int> k;
          for (int a = 0; a <= D; ++a) {
            if (a != skip) k.push_back(whole->elems[(D + 1) * e + a]);
          }
          std::sort(k.begin(), k.end());
          if (outer_keys.count(k)) {
            ASSERT_TRUE(mine.count(k)) << "outer face of element " << e;
          }
        }
      }
      // a part that holds less than the whole mesh has more boundary (where its ghosts end) than
      // outer faces: that is why outer_faces exist
      partial += s.elem_global.size() < static_cast<size_t>(whole->num_elems());
      if (s.elem_global.size() < static_cast<size_t>(whole->num_elems()))
        EXPECT_GT(boundary_faces(m).size(), m.outer_faces.size());
      else
        EXPECT_EQ(boundary_faces(m).size(), m.outer_faces.size());
      const SubMesh u = unpack_submesh(pack_submesh(s));
      EXPECT_EQ(u.contact_reach, s.contact_reach);
      EXPECT_EQ(u.mesh.outer_faces, m.outer_faces);
      EXPECT_EQ(u.mesh.pieces, m.pieces);
      EXPECT_EQ(u.mesh.whole_min_size, m.whole_min_size);
    }
    EXPECT_GT(partial, 0);
  }
}

// Cutting the parts anew during a run: the contact zones are taken at the given positions and
// those travel with the part (SubMesh::cut_x). Moved rigidly, the disc's zones are those at the
// reference positions; with part 0's elements lifted by ten reaches, every element within reach of
// a part's own nodes at the lifted positions is held, and the parts hold fewer than at the
// reference positions (the gap leaves out what was near); and a run's state (a cut sends it to every
// process) packs and unpacks exactly.
TEST(Decompose, ContactZonesAtGivenPositions) {
  HostMesh disc;
  fast_disc(disc);
  const int D = disc.dim, parts = 4;
  const double reach = 2.0 * mesh_quality(disc).mean_size;
  const std::vector<int> part = partition_elements(disc, parts, PartitionMethod::Rcb);
  const std::vector<SubMesh> ref = decompose(disc, part, parts, reach);
  std::vector<double> moved = disc.X;
  for (size_t i = 0; i < moved.size(); i += D) moved[i] += 3.0;
  const std::vector<SubMesh> shifted = decompose(disc, part, parts, reach, &moved);
  for (int p = 0; p < parts; ++p) {
    EXPECT_TRUE(ref[p].cut_x.empty());
    EXPECT_EQ(shifted[p].elem_global, ref[p].elem_global);
    EXPECT_EQ(shifted[p].node_global, ref[p].node_global);
    EXPECT_EQ(shifted[p].mesh.X, ref[p].mesh.X);  // (the reference positions stay the model's)
    ASSERT_EQ(shifted[p].cut_x.size(), shifted[p].node_global.size() * D);
    for (size_t j = 0; j < shifted[p].node_global.size(); ++j)
      for (int k = 0; k < D; ++k)
        EXPECT_EQ(shifted[p].cut_x[j * D + k], moved[static_cast<size_t>(shifted[p].node_global[j]) * D + k]);
    const SubMesh u = unpack_submesh(pack_submesh(shifted[p]));
    EXPECT_EQ(u.cut_x, shifted[p].cut_x);
  }
  // part 0's elements lifted far away: no part holds an element of another in its zone across the gap
  std::vector<double> lifted = disc.X;
  std::vector<bool> up(disc.num_nodes(), false);
  for (int e = 0; e < disc.num_elems(); ++e)
    if (part[e] == 0)
      for (int a = 0; a <= D; ++a) up[disc.elems[(D + 1) * e + a]] = true;
  for (int n = 0; n < disc.num_nodes(); ++n)
    if (up[n]) lifted[static_cast<size_t>(n) * D + 1] += 10 * reach;
  const std::vector<SubMesh> apart = decompose(disc, part, parts, reach, &lifted);
  HostMesh at = disc;
  at.X = lifted;
  size_t held = 0, held_ref = 0;
  for (const SubMesh& s : apart) {
    const std::set<int> els(s.elem_global.begin(), s.elem_global.end());
    for (int e = 0; e < disc.num_elems(); ++e) {  // every element within reach at the lifted positions
      if (part[e] == s.part) continue;
      double near = 1e300;
      for (int i = 0; i < s.mesh.owned_nodes; ++i)
        near = std::min(near, box_distance(at, e, &lifted[static_cast<size_t>(s.node_global[i]) * D]));
      if (near <= reach) {
        EXPECT_TRUE(els.count(e)) << "element " << e << " at " << near;
      }
    }
    held += s.elem_global.size();
    held_ref += ref[s.part].elem_global.size();
  }
  EXPECT_LT(held, held_ref);  // the gap leaves out what was near part 0 before
  const std::vector<double> short_x(disc.X.begin(), disc.X.end() - 1);
  EXPECT_THROW(decompose(disc, part, parts, reach, &short_x), InputError);
  StateArrays st;
  st.f64["model/x"] = moved;
  st.i64["contact/pair_count"] = {7};
  st.str["note"] = "a cut";
  st.file = "(memory)";
  const StateArrays back = unpack_state(pack_state(st));
  EXPECT_EQ(back.f64, st.f64);
  EXPECT_EQ(back.i64, st.i64);
  EXPECT_EQ(back.str, st.str);
  EXPECT_EQ(back.file, st.file);
  std::vector<char> cut = pack_state(st);
  cut.pop_back();
  EXPECT_THROW(unpack_state(cut), InputError);
}

// The forces on ghosts go back to their owners (Halo::pack_forces, add_forces): each own node gets
// the force every part that holds it as a ghost put there, added to its own.
TEST(Decompose, GhostForcesGoBackToTheirOwners) {
  const HostMesh box = half_fracturable_box();
  const int parts = 4, D = 3;
  const auto subs = decompose(box, partition_elements(box, parts, PartitionMethod::Rcb), parts, 0.3);
  std::vector<NodeData<D>> nd(parts);
  std::vector<Halo<D>> halos;
  std::vector<const NodeData<D>*> ptr;
  std::vector<int> held(box.num_nodes(), 0);  // parts holding each node as a ghost
  for (int p = 0; p < parts; ++p) {
    const SubMesh& s = subs[p];
    nd[p].nn = s.mesh.num_nodes();
    nd[p].nn_own = s.mesh.owned_nodes;
    nd[p].f = Kokkos::View<double* [D]>("f", nd[p].nn);
    auto f = Kokkos::create_mirror_view(nd[p].f);
    for (int i = 0; i < nd[p].nn; ++i) {  // own: 1000 + node; ghost: part + 1 (per component)
      const int g = s.node_global[i];
      for (int k = 0; k < D; ++k) f(i, k) = i < s.mesh.owned_nodes ? 1000.0 + g + k : p + 1.0;
      if (i >= s.mesh.owned_nodes) ++held[g];
    }
    Kokkos::deep_copy(nd[p].f, f);
    halos.emplace_back(s.neighbours, s.send, s.recv, /*velocities=*/true);
  }
  for (auto& n : nd) ptr.push_back(&n);
  return_forces_in_process<D>(halos, ptr);
  std::vector<double> want(box.num_nodes(), 0.0);  // what the ghosts sent: the sum of (part + 1)
  for (int p = 0; p < parts; ++p)
    for (int i = subs[p].mesh.owned_nodes; i < subs[p].mesh.num_nodes(); ++i) want[subs[p].node_global[i]] += p + 1.0;
  int checked = 0;
  for (int p = 0; p < parts; ++p) {
    auto f = Kokkos::create_mirror_view(nd[p].f);
    Kokkos::deep_copy(f, nd[p].f);
    for (int i = 0; i < subs[p].mesh.owned_nodes; ++i) {
      const int g = subs[p].node_global[i];
      for (int k = 0; k < D; ++k) ASSERT_EQ(f(i, k), 1000.0 + g + k + want[g]) << "node " << g;
      checked += held[g] > 0;
    }
  }
  EXPECT_GT(checked, 0);
  EXPECT_EQ(halos[0].force_bytes(), static_cast<long>(halos[0].recv_nodes()) * D * 8);
  EXPECT_EQ(halos[0].send_bytes(), static_cast<long>(halos[0].send_nodes()) * 2 * D * 8);
}

TEST(Decompose, RefusesBadPartIdsAndContactNamingTheKey) {
  HostMesh mesh;
  Case c = fast_disc(mesh);
  std::vector<int> part(mesh.num_elems(), 0);
  part[3] = 2;
  try {
    decompose(mesh, part, 2);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("element 3 has part 2"), std::string::npos) << e.what();
  }
  part[3] = 1;
  const auto subs = decompose(mesh, part, 2);
  c.contact.enabled = 1;
  try {
    Simulation<2> s(c, subs[0].mesh);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("contact"), std::string::npos) << e.what();
  }
}

// A part sent to its process (pack_submesh, unpack_submesh) arrives whole: every field the same;
// data cut short or with bytes left over is refused.
// The parts built one at a time (PartBuilder: process 0 sends each as it is built, in any order)
// with their exchange lists completed afterwards are decompose()'s to the byte, with contact zones
// too; a whole mesh packed and unpacked (process 0 keeps it so between cuts) is the same.
TEST(Decompose, PartsBuiltOneAtATimeAreTheSameAsAllAtOnce) {
  const HostMesh box = half_fracturable_box();
  const int parts = 4;
  const std::vector<int> part = partition_elements(box, parts, PartitionMethod::Rcb);
  for (const double reach : {0.0, 0.3}) {
    const auto subs = decompose(box, part, parts, reach);
    PartBuilder b(box, part, parts, reach);
    std::vector<SubMesh> one(parts);
    for (int p = parts - 1; p >= 0; --p) one[p] = b.part(p);
    for (int p = 0; p < parts; ++p) complete_lists(one[p], unpack_lists(pack_lists(b.lists(p))));
    for (int p = 0; p < parts; ++p) {
      EXPECT_EQ(pack_submesh(one[p]), pack_submesh(subs[p])) << "part " << p << ", reach " << reach;
      EXPECT_FALSE(one[p].send.empty()) << "part " << p;
    }
  }
  const std::vector<char> bytes = pack_mesh(box);
  EXPECT_EQ(pack_mesh(unpack_mesh(bytes)), bytes);
  std::vector<char> cut(bytes.begin(), bytes.end() - 1);
  EXPECT_THROW(unpack_mesh(cut), InputError);
}

// A mesh kept in a temporary file field by field (KeptMesh) reads back as pack_mesh's bytes; a
// TMPDIR that cannot hold it is named; a part's mesh let go (release_part_mesh) keeps its own
// counts, names and sets; a file cut short is refused.
TEST(Decompose, MeshKeptInAFileComesBackTheSameAndAPartsMeshLetGoKeepsItsSets) {
  const HostMesh box = half_fracturable_box();
  KeptMesh kept("for the test");
  kept.write(box);
  EXPECT_EQ(pack_mesh(kept.read()), pack_mesh(box));
  EXPECT_EQ(pack_mesh(kept.read()), pack_mesh(box));  // (read again: from the start)
  {  // no room for the file (a TMPDIR that does not exist): the error names the folder
    const char* t = std::getenv("TMPDIR");
    const std::string saved = t ? t : "";
    setenv("TMPDIR", "/nonexistent/fdem-test-dir", 1);
    KeptMesh no_room("for the test");
    try {
      no_room.write(box);
      ADD_FAILURE() << "a mesh kept in a folder that does not exist";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("/nonexistent/fdem-test-dir"), std::string::npos) << e.what();
    }
    if (t) setenv("TMPDIR", saved.c_str(), 1);
    else unsetenv("TMPDIR");
    EXPECT_FALSE(no_room.kept());
  }

  const int parts = 2;
  std::vector<SubMesh> subs = decompose(box, partition_elements(box, parts, PartitionMethod::Rcb), parts, 0.3);
  SubMesh& s = subs[1];
  const HostMesh m0 = s.mesh;
  ASSERT_GT(m0.num_elems(), 0);
  release_part_mesh(s);
  EXPECT_EQ(s.mesh.num_nodes(), 0);
  EXPECT_EQ(s.mesh.num_elems(), 0);
  EXPECT_EQ(s.mesh.num_ifaces(), 0);
  EXPECT_EQ(s.mesh.X.capacity(), 0u);
  EXPECT_EQ(s.mesh.elems.capacity(), 0u);
  EXPECT_EQ(s.mesh.owned_nodes, m0.owned_nodes);
  EXPECT_EQ(s.mesh.owned_elems, m0.owned_elems);
  EXPECT_EQ(s.mesh.pieces, m0.pieces);
  EXPECT_EQ(s.mesh.node_sets, m0.node_sets);
  EXPECT_EQ(s.mesh.region_names, m0.region_names);

  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  const long bytes = write_mesh_file(f, box);
  EXPECT_EQ(bytes, static_cast<long>(pack_mesh(box).size()));
  std::rewind(f);
  EXPECT_THROW(read_mesh_file(f, bytes - 1), InputError);
  std::fclose(f);
}

TEST(Decompose, PartsPackedAndUnpackedAreTheSameAndDamageIsRefused) {
  const HostMesh box = half_fracturable_box();
  const auto subs = decompose(box, partition_elements(box, 3, PartitionMethod::Rcb), 3);
  for (const SubMesh& s : subs) {
    const std::vector<char> bytes = pack_submesh(s);
    const SubMesh u = unpack_submesh(bytes);
    EXPECT_EQ(u.part, s.part);
    EXPECT_EQ(u.parts, 3);
    EXPECT_EQ(u.whole_nodes, box.num_nodes());
    EXPECT_EQ(u.whole_elems, box.num_elems());
    EXPECT_EQ(u.whole_ifaces, box.num_ifaces());
    const HostMesh &a = s.mesh, &b = u.mesh;
    EXPECT_EQ(b.dim, a.dim);
    EXPECT_EQ(b.X, a.X);
    EXPECT_EQ(b.elems, a.elems);
    EXPECT_EQ(b.elem_region, a.elem_region);
    EXPECT_EQ(b.region_names, a.region_names);
    EXPECT_EQ(b.node_sets, a.node_sets);
    EXPECT_EQ(b.face_sets, a.face_sets);
    EXPECT_EQ(b.iface_sets, a.iface_sets);
    EXPECT_EQ(b.ifaces, a.ifaces);
    EXPECT_EQ(b.iface_elems, a.iface_elems);
    EXPECT_EQ(b.node_origin, a.node_origin);
    EXPECT_EQ(b.warnings, a.warnings);
    EXPECT_EQ(b.bodies, a.bodies);
    EXPECT_EQ(b.owned_nodes, a.owned_nodes);
    EXPECT_EQ(b.owned_elems, a.owned_elems);
    EXPECT_EQ(b.owned_ifaces, a.owned_ifaces);
    EXPECT_EQ(b.bulk_elems, a.bulk_elems);
    EXPECT_EQ(b.whole_set_size, a.whole_set_size);
    EXPECT_EQ(b.iface_ids, a.iface_ids);
    EXPECT_EQ(b.iface_ids, s.iface_global);  // (the strength scatter's draw)
    EXPECT_EQ(u.node_global, s.node_global);
    EXPECT_EQ(u.elem_global, s.elem_global);
    EXPECT_EQ(u.iface_global, s.iface_global);
    EXPECT_EQ(u.neighbours, s.neighbours);
    EXPECT_EQ(u.send, s.send);
    EXPECT_EQ(u.recv, s.recv);
    EXPECT_EQ(u.inert_ghosts, s.inert_ghosts);
    EXPECT_FALSE(a.node_sets.empty());
    EXPECT_GT(u.ghost_nodes(), 0);
    EXPECT_EQ(pack_submesh(u), bytes);
    std::vector<char> cut(bytes.begin(), bytes.end() - 3), more = bytes;
    more.push_back(0);
    auto refusal = [](const std::vector<char>& b) -> std::string {
      try {
        unpack_submesh(b);
      } catch (const InputError& e) {
        return e.what();
      }
      return "no error";
    };
    EXPECT_NE(refusal(cut).find("ends early"), std::string::npos) << refusal(cut);
    EXPECT_NE(refusal(more).find("left over"), std::string::npos) << refusal(more);
    std::vector<char> huge = bytes;  // the first count (X's size, after 5 scalars and dim) made huge
    const size_t at = 2 * sizeof(int) + 3 * sizeof(long) + sizeof(int);
    const long long big = 1LL << 60;
    std::memcpy(huge.data() + at, &big, sizeof big);
    EXPECT_NE(refusal(huge).find("count beyond"), std::string::npos) << refusal(huge);
  }
}

struct Sums {
  double kinetic = 0, strain = 0, interface_elastic = 0, platen_elastic = 0, fracture = 0, damping = 0,
         external = 0, balance = 0, force = 0;
  long damaged = 0;
};

Sums add(Sums s, const Energies& e, double force) {
  s.kinetic += e.kinetic;
  s.strain += e.strain;
  s.interface_elastic += e.interface_elastic;
  s.platen_elastic += e.contact_elastic;
  s.fracture += e.fracture;
  s.damping += e.damping;
  s.external += e.work_external;
  s.balance += e.balance_error;
  s.force += force;
  s.damaged += e.damaged;
  return s;
}

double rel(double a, double b) { return std::fabs(a - b) / std::max({std::fabs(a), std::fabs(b), 1e-300}); }

// The parts of a decomposition stepped in one process: their models, their halos, the time step
// agreed as a run over processes would (the smallest contributions of all parts) and the first
// exchange. own_dt: each part's step before the agreement.
template <int D>
struct Parts {
  std::vector<std::unique_ptr<Simulation<D>>> sims;
  std::vector<Halo<D>> halos;
  std::vector<const NodeData<D>*> nodes;
  std::vector<double> own_dt;
  Parts(const Case& c, const std::vector<SubMesh>& subs) {
    StepContributions all;
    for (const SubMesh& s : subs) {
      sims.push_back(std::make_unique<Simulation<D>>(c, s.mesh));
      halos.emplace_back(s.neighbours, s.send, s.recv);
      own_dt.push_back(sims.back()->dt);
      all =
          sims.size() == 1 ? sims[0]->step_contributions() : smallest(all, sims.back()->step_contributions());
    }
    for (auto& s : sims) {
      nodes.push_back(&s->m);
      s->agree_time_step(all);
    }
    exchange();
  }
  void exchange() { exchange_in_process<D>(halos, nodes); }
  // The largest distance of a node's position from the whole run's (x_ref: by whole-mesh index),
  // over every part's own and exchanged ghost nodes (the inert ghosts are never read).
  template <class HostX>
  double worst_position(const std::vector<SubMesh>& subs, const HostX& x_ref) const {
    double worst = 0;
    for (size_t p = 0; p < subs.size(); ++p) {
      auto x = Kokkos::create_mirror_view(sims[p]->m.x);
      Kokkos::deep_copy(x, sims[p]->m.x);
      for (int i = 0; i < subs[p].mesh.num_nodes() - subs[p].inert_ghosts; ++i)
        for (int k = 0; k < D; ++k)
          worst = std::max(worst, std::fabs(x(i, k) - x_ref(subs[p].node_global[i], k)));
    }
    return worst;
  }
};

TEST(Decompose, PartsSteppedWithTheExchangeFollowTheWholeDisc) {
  HostMesh whole;
  const Case c = fast_disc(whole);
  Simulation<2> ref(c, whole);
  // 1000 steps: the first damage near step 250, the peak load near step 900
  const int steps = 1000, sample_every = 50;
  std::vector<Sums> want;
  for (int s = 0; s < steps; ++s) {
    const bool sample = s % sample_every == 0;
    ref.step(sample);
    if (sample) want.push_back(add(Sums{}, ref.energies(), ref.platen_force(0)[1]));
  }
  double peak_want = 0;
  for (const Sums& w : want) peak_want = std::max(peak_want, std::fabs(w.force));
  ASSERT_EQ(want[2].damaged, 0) << "the disc should be intact for the first 100 steps";
  ASSERT_GT(want.back().damaged, 20) << "the disc should be cracking by the end";
  ASSERT_LT(std::fabs(want.back().force), peak_want) << "the run should pass the peak load";
  auto x_ref = Kokkos::create_mirror_view(ref.m.x);
  Kokkos::deep_copy(x_ref, ref.m.x);
  double xscale = 0;  // largest displacement of the whole disc
  for (int i = 0; i < ref.m.nn; ++i)
    for (int k = 0; k < 2; ++k) xscale = std::max(xscale, std::fabs(x_ref(i, k) - whole.X[2 * i + k]));

  for (int parts : {2, 3, 4}) {
    SCOPED_TRACE(std::to_string(parts) + " parts");
    const std::vector<int> part = partition_elements(whole, parts, PartitionMethod::Rcb);
    const std::vector<SubMesh> subs = decompose(whole, part, parts);
    Parts<2> parts_(c, subs);
    auto& sims = parts_.sims;
    for (size_t p = 0; p < sims.size(); ++p) {
      EXPECT_GE(parts_.own_dt[p], ref.dt);
      // each part holds every element, interface and platen node that its own nodes' steps need
      EXPECT_EQ(sims[p]->dt, ref.dt);
    }
    double intact_energy = 0, intact_force = 0, worst_energy = 0, peak_got = 0;
    long worst_count = 0;
    for (int st = 0, j = 0; st < steps; ++st) {
      const bool sample = st % sample_every == 0;
      for (auto& s : sims) s->step(sample);
      parts_.exchange();
      if (!sample) continue;
      Sums got;
      for (auto& s : sims) got = add(got, s->energies(), s->platen_force(0)[1]);
      const Sums& w = want[j++];
      const double escale =
          w.kinetic + w.strain + w.interface_elastic + w.platen_elastic + w.fracture + w.damping;
      double de = 0;
      for (double d : {got.kinetic - w.kinetic, got.strain - w.strain,
                       got.interface_elastic - w.interface_elastic, got.platen_elastic - w.platen_elastic,
                       got.fracture - w.fracture, got.damping - w.damping, got.external - w.external})
        de = std::max(de, std::fabs(d) / std::max(escale, 1e-300));
      worst_energy = std::max(worst_energy, de);
      if (w.damaged == 0) {
        intact_energy = std::max(intact_energy, de);
        intact_force = std::max(intact_force, rel(got.force, w.force));
        EXPECT_EQ(got.damaged, 0) << "step " << st;
      }
      worst_count = std::max(worst_count, std::labs(got.damaged - w.damaged));
      peak_got = std::max(peak_got, std::fabs(got.force));
    }
    // Round-off only: the parts add each node's contributions in another order than the whole
    // disc (and OpenMP's per-thread copies in another split). Intact, the difference stays at
    // round-off (measured: 1e-18 of the force); each damage onset amplifies it (measured: 1e-10 of
    // the force and positions at the peak, growing to 1e-3 by step 2100 as the cracks run), so
    // after the first damage the bounds are those of the issue: the peak load to 1e-9.
    EXPECT_LT(intact_energy, 1e-12);
    EXPECT_LT(intact_force, 1e-12);
    EXPECT_LT(rel(peak_got, peak_want), 1e-9);
    EXPECT_LT(worst_energy, 1e-8);
    EXPECT_LE(worst_count, 1) << "damaged interfaces";
    const double worst_x = parts_.worst_position(subs, x_ref);  // ghosts too: the owners' after the exchange
    EXPECT_LT(worst_x, 1e-8 * xscale);
    std::printf(
        "[ decomposed ] %d parts: intact energy %.1e force %.1e; peak %.1e; energies %.1e; "
        "damaged count %ld; positions %.1e of the largest displacement\n",
        parts, intact_energy, intact_force, rel(peak_got, peak_want), worst_energy, worst_count,
        worst_x / xscale);
    // a cut interface: the same history, bit for bit, on every part that computes it
    std::map<int, std::vector<double>> hist;
    long compared = 0;
    for (size_t p = 0; p < subs.size(); ++p) {
      auto h = Kokkos::create_mirror_view(sims[p]->m.ihist);
      Kokkos::deep_copy(h, sims[p]->m.ihist);
      for (int q = 0; q < subs[p].mesh.num_ifaces(); ++q) {
        std::vector<double> v;
        for (int k = 0; k < 2; ++k)
          for (int a = 0; a < 4; ++a) v.push_back(h(q, k, a));
        auto [it, fresh] = hist.emplace(subs[p].iface_global[q], v);
        if (!fresh) {
          ++compared;
          ASSERT_EQ(0, std::memcmp(it->second.data(), v.data(), v.size() * sizeof(double)))
              << "interface " << subs[p].iface_global[q];
        }
      }
    }
    EXPECT_GT(compared, 0);
    EXPECT_EQ(static_cast<int>(hist.size()), whole.num_ifaces());
  }
}

// The box of half_fracturable_box stretched along z (its bottom held, its top pulled): in the lower
// half the parts share nodes, so the force on such a node comes from elements of several parts,
// and the interfaces between the halves join shared nodes to own ones. Elastic throughout (strong
// interfaces): the parts follow the whole box to round-off.
TEST(Decompose, SharedNodesAcrossPartsStepLikeTheWholeBox) {
  const HostMesh whole = half_fracturable_box();
  fdem::Case c = fdem_test::basic_case(3);
  c.region_material = {{"solid", 0}, {"rock", 0}};
  c.interface_materials = {fdem_test::strong_interface(1e13, 4e12)};
  c.fracture_material = 0;
  c.fracturable_regions = {"rock"};
  c.contact.enabled = 0;
  c.local_damping = 0.05;
  VelocityBC top, bottom;
  top.set = "zmax";
  top.active = {false, false, true};
  top.velocity = {0, 0, 0.5};
  top.ramp_time = 2e-5;
  bottom.set = "zmin";
  bottom.active = {true, true, true};
  c.velocity_bcs = {top, bottom};
  resolve_defaults(c, whole);
  Simulation<3> ref(c, whole);
  const int steps = 400;
  std::vector<double> want_strain, want_kinetic, want_reaction;
  for (int s = 0; s < steps; ++s) {
    const bool sample = s % 50 == 49;
    ref.set_sample_reactions(sample);
    ref.step(sample);
    if (!sample) continue;
    want_strain.push_back(ref.energies().strain + ref.energies().interface_elastic);
    want_kinetic.push_back(ref.energies().kinetic);
    want_reaction.push_back(ref.reactions()[0][2]);
  }
  ASSERT_GT(want_strain.back(), 0);
  ASSERT_EQ(ref.energies().damaged, 0);
  auto x_ref = Kokkos::create_mirror_view(ref.m.x);
  Kokkos::deep_copy(x_ref, ref.m.x);
  double xscale = 0;
  for (int i = 0; i < ref.m.nn; ++i)
    for (int k = 0; k < 3; ++k) xscale = std::max(xscale, std::fabs(x_ref(i, k) - whole.X[3 * i + k]));

  for (int parts : {2, 3, 4}) {
    SCOPED_TRACE(std::to_string(parts) + " parts");
    const std::vector<int> part = partition_elements(whole, parts, PartitionMethod::Rcb);
    const std::vector<SubMesh> subs = decompose(whole, part, parts);
    long shared_ghosts = 0;  // ghosts of the continuous half: nodes of own elements owned elsewhere
    for (const SubMesh& s : subs)
      for (int e = 0; e < s.mesh.owned_elems; ++e)
        for (int a = 0; a < 4; ++a) shared_ghosts += s.mesh.elems[4 * e + a] >= s.mesh.owned_nodes;
    EXPECT_GT(shared_ghosts, 0) << "the partition should cut the continuous half";
    Parts<3> parts_(c, subs);
    auto& sims = parts_.sims;
    for (auto& s : sims) EXPECT_EQ(s->dt, ref.dt);
    double worst = 0;
    for (int st = 0, j = 0; st < steps; ++st) {
      const bool sample = st % 50 == 49;
      for (auto& s : sims) {
        s->set_sample_reactions(sample);
        s->step(sample);
      }
      parts_.exchange();
      if (!sample) continue;
      double strain = 0, kinetic = 0, reaction = 0;
      for (auto& s : sims) {
        strain += s->energies().strain + s->energies().interface_elastic;
        kinetic += s->energies().kinetic;
        reaction += s->reactions()[0][2];
      }
      worst = std::max({worst, rel(strain, want_strain[j]), rel(kinetic, want_kinetic[j]),
                        rel(reaction, want_reaction[j])});
      ++j;
    }
    EXPECT_LT(worst, 1e-10);
    const double worst_x = parts_.worst_position(subs, x_ref);
    EXPECT_LT(worst_x, 1e-10 * xscale);
    std::printf(
        "[ decomposed ] box, %d parts: %ld shared ghosts; energies and reaction %.1e, positions %.1e\n",
        parts, shared_ghosts, worst, worst_x / xscale);
  }
}

}  // namespace
