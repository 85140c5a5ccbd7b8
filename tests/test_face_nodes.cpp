// The contact faces' nodes (kernels/contact/geometry.hpp, FaceNodes): the outer faces' stored, the
// interfaces' two faces' taken from the interface's nodes (side A in order, side B reversed), the
// same as the topology's table (src/solver/contact_topology.cpp) for every face, one at a time and
// all of a face at once.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "io/case.hpp"
#include "kernels/contact/geometry.hpp"
#include "mesh/mesh.hpp"
#include "solver/contact_topology.hpp"
#include "solver/run.hpp"

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

}  // namespace
