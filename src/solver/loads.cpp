// Boundary conditions and loads (solver/loads.hpp): the velocity-BC table, point loads, initial
// velocities (build steps declared in solver/model_builder.hpp), the reactions and their history
// columns.
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "kernels/nodes.hpp"
#include "kernels/outputs.hpp"
#include "solver/loads.hpp"
#include "solver/model_builder.hpp"

namespace fdem {

namespace {

template <class V>
auto mirror(const V& v) {
  return Kokkos::create_mirror_view(v);
}

}  // namespace

template <int D>
VelocityBCTable build_velocity_bcs(const Case& c, const HostMesh& mesh, Model<D>& m) {
  VelocityBCTable t;
  t.node_bc.assign(m.nn, -1);
  std::map<std::pair<int, int>, int> merged;
  for (size_t b = 0; b < c.velocity_bcs.size(); ++b) {
    const auto& bc = c.velocity_bcs[b];
    BCDev d{};
    for (int k = 0; k < D; ++k)
      if (bc.active[k]) {
        d.mask |= 1 << k;
        d.vel[k] = bc.velocity[k];
      }
    d.ramp = bc.ramp_time;
    const int id = static_cast<int>(t.table.size());
    t.table.push_back(d);
    t.names.push_back(bc.set);
    const auto& nodes = mesh.node_sets.at(bc.set);
    Kokkos::View<int*> nv("fdem::bc_nodes", nodes.size());
    auto nv_h = mirror(nv);
    for (size_t j = 0; j < nodes.size(); ++j) {
      const int i = nodes[j];
      nv_h(j) = i;
      if (t.node_bc[i] < 0) {
        t.node_bc[i] = id;
        continue;
      }
      auto key = std::make_pair(t.node_bc[i], id);
      auto it = merged.find(key);
      if (it == merged.end()) {
        BCDev md = t.table[t.node_bc[i]];
        md.mask |= d.mask;
        for (int k = 0; k < D; ++k)
          if (d.mask >> k & 1) md.vel[k] = d.vel[k];
        md.ramp = std::max(md.ramp, d.ramp);
        it = merged.emplace(key, static_cast<int>(t.table.size())).first;
        t.table.push_back(md);
      }
      t.node_bc[i] = it->second;
    }
    Kokkos::deep_copy(nv, nv_h);
    t.nodes.push_back(nv);
  }
  m.bcs = Kokkos::View<BCDev*>("fdem::bcs", t.table.size());
  auto bcs_h = mirror(m.bcs);
  for (size_t b = 0; b < t.table.size(); ++b) bcs_h(b) = t.table[b];
  Kokkos::deep_copy(m.bcs, bcs_h);
  m.node_bc = Kokkos::View<int*>("fdem::node_bc", m.nn);
  auto nbc_h = mirror(m.node_bc);
  for (int i = 0; i < m.nn; ++i) nbc_h(i) = t.node_bc[i];
  Kokkos::deep_copy(m.node_bc, nbc_h);
  return t;
}

template <int D>
std::vector<double> build_point_loads(const Case& c, const HostMesh& mesh, Model<D>& m) {
  static_assert(kMaxLoadRamps <= kLoadRampSlots, "the node update holds every load ramp");
  std::vector<double> ramps;  // distinct ramp times > 0, in the order of the loads
  bool constant = false;
  for (const auto& pl : c.point_loads) {
    if (pl.ramp_time > 0 && std::find(ramps.begin(), ramps.end(), pl.ramp_time) == ramps.end())
      ramps.push_back(pl.ramp_time);
    constant = constant || !(pl.ramp_time > 0);
  }
  if (ramps.size() > static_cast<size_t>(kMaxLoadRamps))  // the case reader refuses these
    throw InputError("'" + c.file + "': more than " + std::to_string(kMaxLoadRamps) +
                     " distinct boundary.point_loads ramp_time values");
  m.fext = Kokkos::View<double* [D]>("fdem::fext", constant ? m.nn : 0);
  m.fext_ramp = Kokkos::View<double** [D]>("fdem::fext_ramp", ramps.size(), ramps.empty() ? 0 : m.nn);
  auto fe_h = mirror(m.fext);
  auto fr_h = mirror(m.fext_ramp);
  for (const auto& pl : c.point_loads) {
    const auto& nodes = mesh.node_sets.at(pl.set);
    // shared by the whole set's nodes (a part of a decomposed mesh holds its own ones only)
    const double count = mesh.owned_nodes >= 0 ? static_cast<double>(mesh.whole_set_size.at(pl.set))
                                               : static_cast<double>(nodes.size());
    if (pl.ramp_time > 0) {
      const size_t g =
          static_cast<size_t>(std::find(ramps.begin(), ramps.end(), pl.ramp_time) - ramps.begin());
      for (int i : nodes)
        for (int k = 0; k < D; ++k) fr_h(g, i, k) += pl.force[k] / count;
    } else {
      for (int i : nodes)
        for (int k = 0; k < D; ++k) fe_h(i, k) += pl.force[k] / count;
    }
  }
  Kokkos::deep_copy(m.fext, fe_h);
  Kokkos::deep_copy(m.fext_ramp, fr_h);
  return ramps;
}

template <int D>
void set_initial_velocities(const Case& c, const HostMesh& mesh, const VelocityBCTable& bcs, Model<D>& m) {
  if (!c.initial_velocities.empty()) {
    auto v_h = mirror(m.v);
    for (const auto& iv : c.initial_velocities) {
      const int r = iv.region == "all" ? -1 : mesh.region_index(iv.region);
      for (int e = 0; e < m.ne; ++e)
        if (r < 0 || mesh.elem_region[e] == r)
          for (int a = 0; a < D + 1; ++a) {
            const int i = mesh.elems[static_cast<size_t>(e) * (D + 1) + a];
            for (int k = 0; k < D; ++k) v_h(i, k) = iv.velocity[k];
          }
    }
    Kokkos::deep_copy(m.v, v_h);
  }
  // Velocity BCs hold from the start: v(-dt/2) of a constrained component is its prescribed value
  // (0 for a ramp), so the run does not begin with an impulse.
  if (bcs.table.empty()) return;
  auto v_h = mirror(m.v);
  Kokkos::deep_copy(v_h, m.v);
  for (int i = 0; i < m.nn; ++i) {
    if (bcs.node_bc[i] < 0) continue;
    const BCDev& b = bcs.table[bcs.node_bc[i]];
    for (int k = 0; k < D; ++k)
      if (b.mask >> k & 1) v_h(i, k) = b.ramp > 0 ? 0.0 : b.vel[k];
  }
  Kokkos::deep_copy(m.v, v_h);
}

namespace {
constexpr const char* kAxes[] = {"x", "y", "z"};
}  // namespace

template <int D>
void Loads<D>::build(const Case& c, const HostMesh& mesh, Model<D>& m, NodeUpdateParams& prm) {
  const VelocityBCTable bcs = build_velocity_bcs<D>(c, mesh, m);
  names_ = bcs.names;
  nodes_ = bcs.nodes;
  reactions_.assign(nodes_.size(), {0, 0, 0});
  const std::vector<double> load_ramps = build_point_loads<D>(c, mesh, m);
  set_initial_velocities<D>(c, mesh, bcs, m);
  for (int k = 0; k < 3; ++k) prm.gravity[k] = c.gravity[k];
  prm.has_fext = m.fext.extent(0) > 0;
  prm.load_ramps = static_cast<int>(load_ramps.size());
  for (size_t g = 0; g < load_ramps.size(); ++g) prm.load_ramp[g] = load_ramps[g];
}

template <int D>
void Loads<D>::sample_reactions(const Model<D>& m, const Parts<D>& parts) {
  for (size_t b = 0; b < nodes_.size(); ++b) {
    double s[3] = {0, 0, 0};
    node_list_force<D>(m, nodes_[b], s);
    parts.sum(s, 3);
    for (int k = 0; k < 3; ++k) reactions_[b][k] = -s[k];
  }
}

template <int D>
void Loads<D>::add_columns(std::vector<std::string>& cols) const {
  for (const auto& name : names_)
    for (int k = 0; k < D; ++k) cols.push_back(name + "_reaction_" + kAxes[k] + " [N]");
}

template <int D>
void Loads<D>::append_row(std::vector<double>& row) const {
  for (const auto& r : reactions_)
    for (int k = 0; k < D; ++k) row.push_back(r[k]);
}

template class Loads<2>;
template class Loads<3>;

#define FDEM_BUILDERS(D)                                                                                     \
  template VelocityBCTable build_velocity_bcs<D>(const Case&, const HostMesh&, Model<D>&);                  \
  template std::vector<double> build_point_loads<D>(const Case&, const HostMesh&, Model<D>&);               \
  template void set_initial_velocities<D>(const Case&, const HostMesh&, const VelocityBCTable&, Model<D>&);
FDEM_BUILDERS(2)
FDEM_BUILDERS(3)
#undef FDEM_BUILDERS

}  // namespace fdem
