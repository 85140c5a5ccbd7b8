#include "solver/fragment_bodies.hpp"

#include <algorithm>
#include <cstdio>
#include <stdexcept>

#include "common/error.hpp"
#include "common/union_find.hpp"
#include "io/output.hpp"

namespace fdem {

template <int D>
int initial_bodies(const Model<D>& m, std::vector<int>& body) {
  auto el = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.elem);
  auto fc = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.iface);
  UnionFind uf(m.nn);  // src/common/union_find.hpp
  for (int e = 0; e < m.ne; ++e)
    for (int a = 1; a <= D; ++a) uf.join(el(e, 0), el(e, a));
  for (int i = 0; i < m.ni; ++i) uf.join(fc(i, 0), fc(i, D));  // every interface, failed or not
  std::vector<int> id(m.nn, -1);
  body.assign(m.ne, -1);
  int n = 0;
  for (int e = 0; e < m.ne; ++e) {
    const int r = uf.find(el(e, 0));
    if (id[r] < 0) id[r] = n++;
    body[e] = id[r];
  }
  return n;
}

template <int D>
void element_mass_centroids(const Model<D>& m, std::vector<double>& mass, std::vector<double>& centroid) {
  auto el = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.elem);
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.X);
  auto vol = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.vol0);
  auto mat = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.mat);
  auto emat = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.emat);
  mass.assign(m.ne, 0.0);
  centroid.assign(3 * static_cast<std::size_t>(m.ne), 0.0);
  for (int e = 0; e < m.ne; ++e) {
    mass[e] = mat(emat(e), 2) * vol(e);
    for (int a = 0; a <= D; ++a)
      for (int k = 0; k < D; ++k) centroid[3 * static_cast<std::size_t>(e) + k] += X(el(e, a), k) / (D + 1);
  }
}

std::vector<BodyFragments> body_fragments(const std::vector<int>& body, int nbodies,
                                          const std::vector<int>& frag, const std::vector<double>& frag_mass,
                                          const std::vector<double>& elem_mass,
                                          const std::vector<double>& elem_centroid) {
  std::vector<BodyFragments> b(nbodies);
  std::vector<int> owner(frag_mass.size(), -1);
  for (std::size_t e = 0; e < body.size(); ++e) {
    BodyFragments& x = b[body[e]];
    ++x.elements;
    x.mass += elem_mass[e];
    for (int k = 0; k < 3; ++k) x.centroid[k] += elem_mass[e] * elem_centroid[3 * e + k];
    const int f = frag[e];
    if (owner[f] < 0) {
      owner[f] = body[e];
      ++x.fragments;
      x.largest_fraction = std::max(x.largest_fraction, frag_mass[f]);  // a mass until divided below
    } else if (owner[f] != body[e]) {
      throw std::logic_error("fragment " + std::to_string(f) + " spans initial bodies " +
                             std::to_string(owner[f]) + " and " + std::to_string(body[e]));
    }
  }
  for (BodyFragments& x : b) {
    for (double& c : x.centroid) c = x.mass > 0 ? c / x.mass : 0.0;
    x.largest_fraction = x.mass > 0 ? std::min(1.0, x.largest_fraction / x.mass) : 0.0;
  }
  return b;
}

void write_bodies_csv(const std::string& path, const std::vector<BodyFragments>& b, int dim) {
  std::string text = std::string("body,elements,mass [kg],fragments,largest_fraction,x [m],y [m]") +
                     (dim == 3 ? ",z [m]" : "") + "\n";
  char line[256];
  for (std::size_t i = 0; i < b.size(); ++i) {
    std::snprintf(line, sizeof line, "%zu,%d,%.9g,%d,%.9g,%.9g,%.9g", i, b[i].elements, b[i].mass,
                  b[i].fragments, b[i].largest_fraction, b[i].centroid[0], b[i].centroid[1]);
    text += line;
    if (dim == 3) {
      std::snprintf(line, sizeof line, ",%.9g", b[i].centroid[2]);
      text += line;
    }
    text += "\n";
  }
  write_file_atomic(path, text);
}

nlohmann::json body_fragments_summary(const std::vector<BodyFragments>& b, const std::string& file) {
  const int n = static_cast<int>(b.size());
  int broken = 0, most = 0;
  double sum = 0, lf_sum = 0, lf_min = n ? 1.0 : 0.0;
  for (const BodyFragments& x : b) {
    broken += x.fragments > 1;
    most = std::max(most, x.fragments);
    sum += x.fragments;
    lf_sum += x.largest_fraction;
    lf_min = std::min(lf_min, x.largest_fraction);
  }
  constexpr int kTop = 10;  // histogram: 1 .. 9 fragments, then "10 or more"
  std::vector<int> frags, count(std::min(std::max(most, 1), kTop), 0);
  for (int k = 1; k <= static_cast<int>(count.size()); ++k) frags.push_back(k);
  for (const BodyFragments& x : b) ++count[std::min(std::max(x.fragments, 1), kTop) - 1];
  return {{"bodies", n},
          {"broken", broken},
          {"mean_fragments", n ? sum / n : 0.0},
          {"max_fragments", most},
          {"mean_largest_fraction", n ? lf_sum / n : 0.0},
          {"min_largest_fraction", lf_min},
          {"histogram", {{"fragments", frags}, {"bodies", count}, {"last_is_at_least", most >= kTop}}},
          {"file", file}};
}

template int initial_bodies<2>(const Model<2>&, std::vector<int>&);
template int initial_bodies<3>(const Model<3>&, std::vector<int>&);
template void element_mass_centroids<2>(const Model<2>&, std::vector<double>&, std::vector<double>&);
template void element_mass_centroids<3>(const Model<3>&, std::vector<double>&, std::vector<double>&);

}  // namespace fdem
