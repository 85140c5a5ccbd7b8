// A part built from the coarse mesh alone (src/parallel/local_part.hpp, issue 49): each part's
// process refines its own coarse elements and a halo, inserts their interfaces and cuts its part
// out; the result must be the part decompose() cuts from the whole refined mesh, item for item and
// bit for bit (the same global ids, coordinates, connectivity, interfaces, outer faces, sets and
// exchange lists), with and without a contact zone, in 2D and 3D.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "mesh/mesh.hpp"
#include "mesh/pieces.hpp"
#include "mesh/refine.hpp"
#include "parallel/decompose.hpp"
#include "parallel/local_part.hpp"
#include "solver/local_setup.hpp"
#include "solver/run_setup.hpp"

namespace {

using namespace fdem;

// The coarse elements in `parts` slabs along a tilted direction (by their centroids' rank), so
// that every part has neighbours and the cuts run through the curved boundary.
std::vector<int> slab_parts(const HostMesh& m, int parts) {
  const int D = m.dim, npe = D + 1, ne = m.num_elems();
  std::vector<std::pair<double, int>> key(ne);
  for (int e = 0; e < ne; ++e) {
    double s = 0;
    for (int a = 0; a < npe; ++a) {
      const double* x = &m.X[static_cast<std::size_t>(m.elems[e * npe + a]) * D];
      s += x[0] + 0.4 * x[1] + (D == 3 ? 0.2 * x[2] : 0.0);
    }
    key[e] = {s, e};
  }
  std::sort(key.begin(), key.end());
  std::vector<int> part(ne);
  for (int r = 0; r < ne; ++r) part[key[r].second] = static_cast<int>(static_cast<long>(r) * parts / ne);
  return part;
}

WholeFacts facts_of(const HostMesh& whole) {
  WholeFacts f;
  f.nodes = whole.num_nodes();
  f.elems = whole.num_elems();
  f.ifaces = whole.num_ifaces();
  f.pieces = count_bodies(whole);
  f.min_size = mesh_quality(whole).min_size;
  for (const auto& [name, set] : whole.node_sets) f.set_sizes[name] = static_cast<long>(set.size());
  f.warnings = whole.warnings;
  f.bodies = whole.bodies;
  return f;
}

void expect_same_part(const SubMesh& a, const SubMesh& b) {
  EXPECT_EQ(a.part, b.part);
  EXPECT_EQ(a.parts, b.parts);
  EXPECT_EQ(a.whole_nodes, b.whole_nodes);
  EXPECT_EQ(a.whole_elems, b.whole_elems);
  EXPECT_EQ(a.whole_ifaces, b.whole_ifaces);
  ASSERT_EQ(a.node_global, b.node_global);
  ASSERT_EQ(a.elem_global, b.elem_global);
  ASSERT_EQ(a.iface_global, b.iface_global);
  EXPECT_EQ(a.neighbours, b.neighbours);
  EXPECT_EQ(a.recv, b.recv);
  EXPECT_EQ(a.inert_ghosts, b.inert_ghosts);
  EXPECT_EQ(a.contact_reach, b.contact_reach);
  const HostMesh &m = a.mesh, &n = b.mesh;
  EXPECT_EQ(m.X, n.X);  // the same bits
  EXPECT_EQ(m.elems, n.elems);
  EXPECT_EQ(m.elem_region, n.elem_region);
  EXPECT_EQ(m.ifaces, n.ifaces);
  EXPECT_EQ(m.iface_elems, n.iface_elems);
  EXPECT_EQ(m.node_origin, n.node_origin);
  EXPECT_EQ(m.owned_nodes, n.owned_nodes);
  EXPECT_EQ(m.owned_elems, n.owned_elems);
  EXPECT_EQ(m.owned_ifaces, n.owned_ifaces);
  EXPECT_EQ(m.bulk_elems, n.bulk_elems);
  EXPECT_EQ(m.node_sets, n.node_sets);
  EXPECT_EQ(m.iface_sets, n.iface_sets);
  EXPECT_EQ(m.whole_set_size, n.whole_set_size);
  EXPECT_EQ(m.outer_faces, n.outer_faces);
  EXPECT_EQ(m.pieces, n.pieces);
  EXPECT_EQ(m.whole_min_size, n.whole_min_size);
  EXPECT_EQ(m.iface_ids, n.iface_ids);
  EXPECT_EQ(m.region_names, n.region_names);
  EXPECT_EQ(m.bodies, n.bodies);
}

void check_local_parts(const HostMesh& coarse, int k, const std::vector<CurvedSurface>& surfaces, int parts,
                       double reach) {
  SCOPED_TRACE("dim " + std::to_string(coarse.dim) + ", refine " + std::to_string(k) + ", " + std::to_string(parts) +
               " parts, contact reach " + std::to_string(reach));
  HostMesh whole = refine_mesh(coarse, k, surfaces);
  insert_interfaces(whole, std::vector<bool>(whole.region_names.size(), true));
  const CoarseTopology topo = coarse_topology(coarse, k, surfaces);
  const std::vector<std::int64_t> off = refined_interface_offsets(coarse, topo);
  const std::vector<int> cpart = slab_parts(coarse, parts);
  const int children = static_cast<int>(refine_factor(coarse.dim, k) + 0.5);
  std::vector<int> fpart(whole.num_elems());
  for (int e = 0; e < whole.num_elems(); ++e) fpart[e] = cpart[e / children];
  PartBuilder builder(whole, fpart, parts, reach);
  const WholeFacts facts = facts_of(whole);
  std::vector<SubMesh> local(parts);
  long held = 0;
  for (int p = 0; p < parts; ++p) {
    SCOPED_TRACE("part " + std::to_string(p));
    const SubMesh ref = builder.part(p);
    LocalPartStats st;
    local[p] = local_part(coarse, topo, off, cpart, parts, p, reach, facts, &st);
    expect_same_part(local[p], ref);
    EXPECT_FALSE(local[p].neighbours.empty());
    held += local[p].mesh.num_elems();
    EXPECT_GE(st.rings, 1);
    EXPECT_LE(st.rings, 2);
    // in 2D, where the coarse mesh is fine enough, the halo is a neighbourhood, not the whole mesh
    if (coarse.dim == 2) {
      EXPECT_LT(st.fine_elems, 0.8 * whole.num_elems());
    }
    EXPECT_LT(local[p].mesh.num_elems(), whole.num_elems());
  }
  EXPECT_GT(held, whole.num_elems());  // ghosts
  // the send lists from the other parts' requests: those decompose() gives
  for (int p = 0; p < parts; ++p) {
    std::vector<int> from;
    std::vector<std::vector<std::int64_t>> req;
    for (int q = 0; q < parts; ++q) {
      const auto r = ghost_requests(local[q]);
      for (std::size_t j = 0; j < local[q].neighbours.size(); ++j)
        if (local[q].neighbours[j] == p) {
          from.push_back(q);
          req.push_back(r[j]);
        }
    }
    const PartLists want = builder.lists(p), got = lists_from_requests(local[p], from, req);
    EXPECT_EQ(got.neighbours, want.neighbours) << "part " << p;
    EXPECT_EQ(got.send, want.send) << "part " << p;
  }
}

TEST(LocalPart, DiscPartsAreTheWholeRefinedMeshsParts) {
  const double R = 0.025;
  const HostMesh coarse = generate_disc(0, 0, R, 0.004, "body", 0, 0, false);
  const std::vector<CurvedSurface> s{{{0, 0, 0}, R}};
  check_local_parts(coarse, 2, s, 3, 0.0);
  check_local_parts(coarse, 2, s, 3, 0.0015);  // contact: about 1.5 fine elements
  check_local_parts(coarse, 1, s, 4, 0.003);
}

TEST(LocalPart, SpherePartsAreTheWholeRefinedMeshsParts) {
  const double R = 0.025;
  const HostMesh coarse = generate_sphere({0, 0, 0}, R, 0.006);
  const std::vector<CurvedSurface> s{{{0, 0, 0}, R}};
  check_local_parts(coarse, 1, s, 2, 0.0);
  check_local_parts(coarse, 1, s, 3, 0.004);
}

// What a run whose mesh no process holds reports of it comes from the parts' own rows: the
// checkpoints' mesh hash (the parts' MeshHash sums add up to the whole mesh's) and the mesh
// report's quality (minima, maxima, the edges' sums and counts).
TEST(LocalPart, WholeMeshHashAndQualityFromTheParts) {
  const double R = 0.025;
  const HostMesh coarse = generate_disc(0, 0, R, 0.004, "body", 0, 0, false);
  const std::vector<CurvedSurface> surf{{{0, 0, 0}, R}};
  HostMesh whole = refine_mesh(coarse, 1, surf);
  insert_interfaces(whole, std::vector<bool>(whole.region_names.size(), true));
  const std::vector<int> part = slab_parts(whole, 3);
  PartBuilder builder(whole, part, 3, 0.002);
  MeshHash sum;
  const MeshQuality q = mesh_quality(whole);
  double min_angle = 1e300, max_aspect = 0, min_size = 1e300, edges = 0;
  long count = 0;
  for (int p = 0; p < 3; ++p) {
    const SubMesh s = builder.part(p);
    ASSERT_LT(s.mesh.owned_elems, s.mesh.num_elems());  // (ghosts, which must not count)
    const MeshHash own = own_rows_hash(s);
    for (int k = 0; k < 3; ++k) sum.sums[k] += own.sums[k];
    const MeshQuality o = mesh_quality(s.mesh, s.mesh.owned_elems);
    min_angle = std::min(min_angle, o.min_angle_deg);
    max_aspect = std::max(max_aspect, o.max_aspect);
    min_size = std::min(min_size, o.min_size);
    edges += o.edge_sum;
    count += o.edge_count;
  }
  EXPECT_EQ(sum.hex(), mesh_hash(whole));
  EXPECT_EQ(min_angle, q.min_angle_deg);
  EXPECT_EQ(max_aspect, q.max_aspect);
  EXPECT_EQ(min_size, q.min_size);
  EXPECT_EQ(count, q.edge_count);
  EXPECT_NEAR(edges / count, q.mean_size, 1e-12 * q.mean_size);
  // one coordinate changed in its last bit: another hash
  HostMesh moved = whole;
  moved.X[5] = std::nextafter(moved.X[5], 1.0);
  EXPECT_NE(mesh_hash(moved), mesh_hash(whole));
  // two elements' rows swapped: another hash (each row is hashed with its index)
  HostMesh swapped = whole;
  std::swap_ranges(swapped.elems.begin(), swapped.elems.begin() + 3, swapped.elems.begin() + 3);
  EXPECT_NE(mesh_hash(swapped), mesh_hash(whole));
}

// Requests that name a node the part does not own are refused (a damaged exchange), and a part
// id out of range.
TEST(LocalPart, BadRequestsAndPartsRefused) {
  const double R = 0.025;
  const HostMesh coarse = generate_disc(0, 0, R, 0.006, "body", 0, 0, false);
  const std::vector<CurvedSurface> s{{{0, 0, 0}, R}};
  const CoarseTopology topo = coarse_topology(coarse, 1, s);
  const std::vector<std::int64_t> off = refined_interface_offsets(coarse, topo);
  const std::vector<int> cpart = slab_parts(coarse, 2);
  const SubMesh a = local_part(coarse, topo, off, cpart, 2, 0, 0.0, WholeFacts{});
  const SubMesh b = local_part(coarse, topo, off, cpart, 2, 1, 0.0, WholeFacts{});
  std::vector<std::vector<std::int64_t>> req = ghost_requests(b);
  ASSERT_EQ(b.neighbours, std::vector<int>{0});
  EXPECT_NO_THROW(lists_from_requests(a, {1}, req));
  req[0].push_back(b.node_global[0]);  // one of b's own nodes
  EXPECT_THROW(lists_from_requests(a, {1}, req), InputError);
  EXPECT_THROW(local_part(coarse, topo, off, cpart, 2, 2, 0.0, WholeFacts{}), InputError);
}

}  // namespace
