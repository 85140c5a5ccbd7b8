// The contact faces' nodes (kernels/contact/geometry.hpp, FaceNodes): the outer faces' stored, the
// interfaces' two faces' taken from the interface's nodes (side A in order, side B reversed), the
// same as the topology's table (src/solver/contact_topology.cpp) for every face, one at a time and
// all of a face at once. And the per-node data of the surfaces (kernels/contact/surfaces.hpp,
// ContactSurface): the faces around each node with and without offsets, and the surface nodes'
// areas by place in their list, from face shares computed on the device, the same bits as the
// topology's.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "io/case.hpp"
#include "kernels/contact/geometry.hpp"
#include "mesh/mesh.hpp"
#include "solver/contact_system.hpp"
#include "solver/contact_topology.hpp"
#include "solver/run.hpp"
#include "solver/simulation.hpp"
#include "solver_fixtures.hpp"

namespace {

using namespace fdem;

template <int D>
void faces_as_the_topology_lists_them(const std::string& file) {
  const Case c = load_case(std::string(FDEM_SOURCE_DIR) + file, {"parameters.h=0.008"});
  const HostMesh mesh = prepare_mesh(c);
  const ContactFaces F = contact_faces<D>(c, mesh);
  const int ni = mesh.num_ifaces();
  ASSERT_GT(ni, 0);
  ASSERT_EQ(F.nf, F.nb + 2 * ni);
  FaceNodes<D> fn;
  fn.nb = F.nb;
  fn.nf = F.nf;
  fn.outer = Kokkos::View<int* [D]>("outer", F.nb);
  fn.iface = Kokkos::View<int* [2 * D]>("iface", ni);
  auto outer = Kokkos::create_mirror_view(fn.outer);
  auto iface = Kokkos::create_mirror_view(fn.iface);
  for (int f = 0; f < F.nb; ++f)
    for (int a = 0; a < D; ++a) outer(f, a) = F.fnode[static_cast<size_t>(f) * D + a];
  for (int q = 0; q < ni; ++q)
    for (int a = 0; a < 2 * D; ++a) iface(q, a) = mesh.ifaces[static_cast<size_t>(q) * 2 * D + a];
  Kokkos::deep_copy(fn.outer, outer);
  Kokkos::deep_copy(fn.iface, iface);
  // (on the device: every face, one node at a time and all at once, against the table)
  Kokkos::View<int* [D]> one("one", F.nf), all("all", F.nf);
  Kokkos::parallel_for(
      "test::face_nodes", Kokkos::RangePolicy<ExecSpace>(0, F.nf), KOKKOS_LAMBDA(const int f) {
        int v[D];
        fn.get(f, v);
        for (int a = 0; a < D; ++a) {
          one(f, a) = fn(f, a);
          all(f, a) = v[a];
        }
      });
  const auto one_h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), one);
  const auto all_h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), all);
  for (int f = 0; f < F.nf; ++f)
    for (int a = 0; a < D; ++a) {
      ASSERT_EQ(one_h(f, a), F.fnode[static_cast<size_t>(f) * D + a]) << "face " << f << " node " << a;
      ASSERT_EQ(all_h(f, a), F.fnode[static_cast<size_t>(f) * D + a]) << "face " << f << " node " << a;
    }
  for (int q = 0; q < ni; ++q)  // (and the interface of each face is its number's)
    ASSERT_EQ(face_interface(F.nb + 2 * q + 1, F.nb), q);
  EXPECT_EQ(face_interface(F.nb - 1, F.nb), -1);
}

TEST(FaceNodes, AsTheTopologyListsThem2D) { faces_as_the_topology_lists_them<2>("/cases/particle_impact_2d/case.json"); }

TEST(FaceNodes, AsTheTopologyListsThem3D) { faces_as_the_topology_lists_them<3>("/cases/particle_impact_3d/case.json"); }

// The surfaces of a simulation's contact against the host topology of its mesh: each node's faces
// (faces_begin .. faces_end) the topology's, in its order; without offsets exactly where every
// node is on D faces (`stride`); each surface node's area, by its place in the list, half the sum
// of its active faces' shares as the topology computes them, to the bit.
template <int D>
void surfaces_as_the_topology(const Case& c, const HostMesh& mesh, int stride) {
  Simulation<D> sim(c, mesh);
  const ContactSystem<D>* ct = sim.contact();
  ASSERT_NE(ct, nullptr);
  const ContactSurface<D>& S = ct->surface();
  EXPECT_EQ(S.face_stride, stride);
  EXPECT_EQ(S.nfoff.extent(0), stride > 0 ? 0u : static_cast<size_t>(mesh.num_nodes() + 1));
  const ContactFaces F = contact_faces<D>(c, mesh);
  const FaceShares H = face_shares<D>(mesh, F, D == 2 ? c.thickness : 1.0);
  const int nn = mesh.num_nodes();
  Kokkos::View<int*> range("range", 2 * nn);
  {
    const ContactSurface<D> s = S;
    Kokkos::parallel_for(
        "test::face_ranges", Kokkos::RangePolicy<ExecSpace>(0, nn), KOKKOS_LAMBDA(const int i) {
          range(2 * i) = s.faces_begin(i);
          range(2 * i + 1) = s.faces_end(i);
        });
  }
  const auto r = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), range);
  const auto nface = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), S.nface);
  for (int i = 0; i < nn; ++i) {
    ASSERT_EQ(r(2 * i), H.nfoff[i]) << "node " << i;
    ASSERT_EQ(r(2 * i + 1), H.nfoff[i + 1]) << "node " << i;
    for (int j = H.nfoff[i]; j < H.nfoff[i + 1]; ++j) ASSERT_EQ(nface(j), H.nface[j]) << "node " << i;
  }
  // at the start the outer faces are the surfaces
  const int ns = ct->surface_nodes();
  ASSERT_GT(ns, 0);
  const auto list = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), ct->surface_node_list());
  const auto area = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), S.narea);
  ASSERT_GE(area.extent(0), static_cast<size_t>(ns));
  for (int p = 0; p < ns; ++p) {
    const int i = list(p);
    double a = 0.0;
    for (int j = H.nfoff[i]; j < H.nfoff[i + 1]; ++j) {
      const int f = H.nface[j];
      if (f >= F.nb) continue;  // (an interface's face: not a surface yet)
      double xf[D][D], n[D];
      for (int b = 0; b < D; ++b)
        for (int k = 0; k < D; ++k) xf[b][k] = mesh.X[static_cast<size_t>(F.fnode[static_cast<size_t>(f) * D + b]) * D + k];
      const double meas = face_normal<D>(xf, n) * (D == 2 ? c.thickness : 1.0);
      a += 0.5 * (meas / D);
    }
    ASSERT_EQ(area(p), a) << "surface node " << i;
  }
}

TEST(ContactSurfaces, FacesAroundNodesAndAreasAsTheTopologyWithInterfacesEverywhere3D) {
  const Case c = load_case(std::string(FDEM_SOURCE_DIR) + "/cases/particle_impact_3d/case.json", {"parameters.h=0.008"});
  surfaces_as_the_topology<3>(c, prepare_mesh(c), 3);
}

TEST(ContactSurfaces, FacesAroundNodesAndAreasAsTheTopologyWithInterfacesEverywhere2D) {
  const Case c = load_case(std::string(FDEM_SOURCE_DIR) + "/cases/particle_impact_2d/case.json", {"parameters.h=0.008"});
  surfaces_as_the_topology<2>(c, prepare_mesh(c), 2);
}

TEST(ContactSurfaces, FacesAroundNodesAndAreasAsTheTopologyWithoutInterfaces3D) {
  // two bodies without interfaces: a node is on the faces of every element at it (offsets)
  const HostMesh ball = generate_sphere({0, 0, 0.052}, 0.05, 0.05 / 4, "ball");
  const HostMesh wall = generate_box({-0.03, -0.03, -0.02}, {0.06, 0.06, 0.02}, 3, 3, 1, "wall");
  const HostMesh mesh = merge_meshes(wall, ball, "wall", "ball");
  Case c = fdem_test::basic_case(3, 1e7, 0.25, 1000);
  c.region_material = {{"ball", 0}, {"wall", 0}};
  surfaces_as_the_topology<3>(c, mesh, 0);
}

}  // namespace
