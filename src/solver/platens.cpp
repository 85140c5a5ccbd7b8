// The rigid platens' host side (solver/platens.hpp): build, contact's surface nodes, ledger terms,
// forces and loads, history columns.
#include "solver/platens.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "solver/contact_system.hpp"
#include "solver/model_builder.hpp"

namespace fdem {

namespace {

constexpr const char* kAxes[] = {"x", "y", "z"};

// The outer boundary nodes (m.bnode, ascending) and their tributary areas (m.barea, a row each).
template <int D>
void boundary_areas(const HostMesh& mesh, Model<D>& m) {
  const auto faces = boundary_faces(mesh);
  std::map<int, double> area;
  const int nf = static_cast<int>(faces.size()) / D;
  for (int fi = 0; fi < nf; ++fi) {
    double meas;
    const double* p0 = &mesh.X[static_cast<size_t>(faces[fi * D]) * D];
    const double* p1 = &mesh.X[static_cast<size_t>(faces[fi * D + 1]) * D];
    if constexpr (D == 2) {
      meas = std::hypot(p1[0] - p0[0], p1[1] - p0[1]) * m.thickness;
    } else {
      const double* p2 = &mesh.X[static_cast<size_t>(faces[fi * D + 2]) * D];
      double a[3], b[3];
      for (int k = 0; k < 3; ++k) {
        a[k] = p1[k] - p0[k];
        b[k] = p2[k] - p0[k];
      }
      meas = triangle_area(a, b);
    }
    for (int k = 0; k < D; ++k) area[faces[fi * D + k]] += meas / D;
  }
  // one part of a decomposed run: the platens act on its own nodes (the ghosts take their owners'
  // state), whose boundary faces it holds all of (src/parallel/decompose.hpp)
  if (mesh.owned_nodes >= 0)
    for (auto it = area.begin(); it != area.end();) it = it->first >= mesh.owned_nodes ? area.erase(it) : ++it;
  m.nb = static_cast<int>(area.size());
  m.bnode = Kokkos::View<int*>("fdem::bnode", m.nb);
  m.barea = Kokkos::View<double*>("fdem::barea", m.nb);
  auto bn_h = Kokkos::create_mirror_view(m.bnode);
  auto ba_h = Kokkos::create_mirror_view(m.barea);
  int b = 0;
  for (const auto& [node, a] : area) {
    bn_h(b) = node;
    ba_h(b) = a;
    ++b;
  }
  Kokkos::deep_copy(m.bnode, bn_h);
  Kokkos::deep_copy(m.barea, ba_h);
}

// Room for the springs and allowances of `rows` nodes of every platen (zero).
template <int D>
void allocate_springs(PlatenData<D>& d, int rows) {
  d.platen_fs = Kokkos::View<double** [D]>("fdem::platen_fs", d.platens.count, rows);
  d.platen_g0 = Kokkos::View<double**>("fdem::platen_g0", d.platens.count, rows);
}

// A platen with a mass (PlatenDev::inv_mass): the velocity across its normal and gravity along it.
void drive(const PlatenSpec& ps, const Vec3& gravity, PlatenDev& P) {
  P.inv_mass = ps.mass > 0 ? 1.0 / ps.mass : 0.0;
  double vn = 0, gn = 0;
  for (int k = 0; k < 3; ++k) {
    vn += P.vel[k] * P.n[k];
    gn += gravity[k] * P.n[k];
  }
  for (int k = 0; k < 3; ++k) P.vt[k] = ps.mass > 0 ? P.vel[k] - vn * P.n[k] : 0.0;
  P.gn = ps.mass > 0 ? gn : 0.0;
}

// A driven platen (inverse mass w) on springs of stiffness kA in all: its stable step.
double weight_step(double kA, double w) { return kA > 0 && w > 0 ? 2.0 / std::sqrt(kA * w) : std::numeric_limits<double>::infinity(); }

// The platens (after boundary_areas) and their springs' storage; their names into `names`, each
// platen's spring stiffness on the boundary nodes at once into `kA`. Returns the platen springs'
// stable step on the boundary nodes.
template <int D>
double platens_of(const Case& c, const std::vector<double>& mass, Model<D>& m, std::vector<std::string>& names,
                  std::vector<double>& kA) {
  if (static_cast<int>(c.platens.size()) > kMaxPlatens)
    throw InputError(c.file + ": platens: at most " + std::to_string(kMaxPlatens) + " allowed");
  auto bn_h = Kokkos::create_mirror_view(m.bnode);
  auto ba_h = Kokkos::create_mirror_view(m.barea);
  Kokkos::deep_copy(bn_h, m.bnode);
  Kokkos::deep_copy(ba_h, m.barea);
  double step = std::numeric_limits<double>::infinity();
  m.platens.count = static_cast<int>(c.platens.size());
  for (int p = 0; p < m.platens.count; ++p) {
    const auto& ps = c.platens[p];
    PlatenDev& P = m.platens.p[p];
    double nlen = 0;
    for (int k = 0; k < 3; ++k) nlen += ps.normal[k] * ps.normal[k];
    nlen = std::sqrt(nlen);
    for (int k = 0; k < 3; ++k) {
      P.p0[k] = ps.point[k];
      P.n[k] = ps.normal[k] / nlen;
      P.vel[k] = ps.velocity[k];
      P.vel2[k] = ps.has_change ? ps.change_velocity[k] : ps.velocity[k];
    }
    P.tc = ps.has_change ? ps.change_time : std::numeric_limits<double>::infinity();
    P.kn = ps.kn;  // derived values filled by resolve_defaults (io/case.hpp)
    P.ks = ps.ks;
    P.mu = ps.friction;
    P.coh = ps.cohesion;
    drive(ps, c.gravity, P);
    names.push_back(ps.name);
    double area = 0;
    for (int bb = 0; bb < m.nb; ++bb) {
      // a node between its spring and a driven platen: the two masses in series
      const double w = std::sqrt(std::max(P.kn, P.ks) * ba_h(bb) * (1.0 / mass[bn_h(bb)] + P.inv_mass));
      step = std::min(step, 2.0 / w);
      area += ba_h(bb);
    }
    // a driven platen on the springs of the whole boundary at once (a part of a decomposed run:
    // its own share, summed over the parts by Platens::weight_steps)
    kA.push_back(std::max(P.kn, P.ks) * area);
    step = std::min(step, weight_step(kA.back(), P.inv_mass));
  }
  allocate_springs<D>(m, m.nb);
  return step;
}

// With contact: the platen springs' stable step on every potential surface node at its largest
// contact area amax (a part's own nodes, owned >= 0: its own), and each platen's springs on all of
// them at once into kA.
template <int D>
double surface_step(const Model<D>& m, const std::vector<double>& amax, const std::vector<double>& mass,
                    std::vector<double>& kA) {
  double step = std::numeric_limits<double>::infinity();
  kA.assign(m.platens.count, 0.0);
  for (int p = 0; p < m.platens.count; ++p) {
    const PlatenDev& P = m.platens.p[p];
    double area = 0;
    for (int i = 0; i < m.nn; ++i)
      if (amax[i] > 0 && mass[i] > 0) {
        step = std::min(step, 2.0 / std::sqrt(std::max(P.kn, P.ks) * amax[i] * (1.0 / mass[i] + P.inv_mass)));
        if (i < m.owned_nodes()) area += amax[i];
      }
    kA[p] = std::max(P.kn, P.ks) * area;
    step = std::min(step, weight_step(kA[p], P.inv_mass));
  }
  return step;
}

}  // namespace

template <int D>
void Platens<D>::build(const Case& c, const HostMesh& mesh, const std::vector<double>& mass, Model<D>& m,
                       StepContributions& sc) {
  if (!c.platens.empty()) {
    boundary_areas<D>(mesh, m);
    sc.platens = platens_of<D>(c, mass, m, names_, weight_kA_);
  }
  m.platen_acc = Kokkos::View<double* [kPlatenAcc]>("fdem::platen_acc", std::max(1, m.platens.count));
  acc_host_ = Kokkos::create_mirror_view(m.platen_acc);
  m.platen_motion = Kokkos::View<double* [kPlatenMotion]>("fdem::platen_motion", std::max(1, m.platens.count));
  motion_host_ = Kokkos::create_mirror_view(m.platen_motion);
  for (int p = 0; p < m.platens.count; ++p) {
    const PlatenDev& P = m.platens.p[p];
    driven_ = driven_ || P.inv_mass > 0;
    driven_platen_.push_back(P.inv_mass > 0);
    for (int k = 0; k < 3; ++k) motion_host_(p, kPlatenSpeed) += P.inv_mass > 0 ? P.vel[k] * P.n[k] : 0.0;
    motion_host_(p, kPlatenSpeedAtForces) = motion_host_(p, kPlatenSpeed);
  }
  Kokkos::deep_copy(m.platen_motion, motion_host_);
}

template <int D>
void Platens<D>::advance(const Model<D>& m, const Parts<D>& parts, double dt, double dtv) const {
  if (!driven_) return;
  PlatenTotals totals;
  if (parts.size() > 1) {  // the total force: every part's own nodes' (one small copy and sum)
    Kokkos::deep_copy(acc_host_, m.platen_acc);
    std::vector<double> flat(static_cast<size_t>(m.platens.count) * 3);
    for (int p = 0; p < m.platens.count; ++p)
      for (int k = 0; k < 3; ++k) flat[static_cast<size_t>(p) * 3 + k] = acc_host_(p, kPlatenForce + k);
    parts.sum(flat.data(), static_cast<int>(flat.size()));
    totals.given = 1;
    for (int p = 0; p < m.platens.count; ++p)
      for (int k = 0; k < 3; ++k) totals.F[p][k] = flat[static_cast<size_t>(p) * 3 + k];
  }
  advance_platens<D>(m, totals, dt, dtv);
  cached_at_ = -1;  // (the work and the motion have changed)
}

template <int D>
void Platens<D>::contact_step(const Model<D>& m, const std::vector<double>& amax, const std::vector<double>& mass,
                              StepContributions& sc) {
  sc.platens_on_surfaces = surface_step<D>(m, amax, mass, weight_kA_surfaces_);
}

template <int D>
void Platens<D>::weight_steps(const Parts<D>& parts, const Model<D>& m, StepContributions& sc) const {
  if (!driven_) return;
  std::vector<double> kA = weight_kA_;
  kA.insert(kA.end(), weight_kA_surfaces_.begin(), weight_kA_surfaces_.end());
  kA.resize(2 * static_cast<size_t>(m.platens.count), 0.0);
  parts.sum(kA.data(), static_cast<int>(kA.size()));
  for (int p = 0; p < m.platens.count; ++p) {
    sc.platens = std::min(sc.platens, weight_step(kA[p], m.platens.p[p].inv_mass));
    if (sc.has_contact)
      sc.platens_on_surfaces = std::min(sc.platens_on_surfaces, weight_step(kA[m.platens.count + p], m.platens.p[p].inv_mass));
  }
}

template <int D>
bool Platens<D>::surfaces_changed(const ContactSystem<D>& contact) const {
  return contact.surface_version() != surface_version_;
}

template <int D>
void Platens<D>::follow_surfaces(Model<D>& m, const ContactSystem<D>& contact, double t) {
  surface_version_ = contact.surface_version();
  if (m.platens.count == 0) return;
  const int ns = contact.own_surface_nodes();  // (a part: the platens act on its own nodes)
  PlatenData<D> to;                            // the rows of the new list
  to.platens = m.platens;
  to.bnode = Kokkos::View<int*>(Kokkos::view_alloc(Kokkos::WithoutInitializing, "fdem::bnode"), ns);
  Kokkos::deep_copy(to.bnode, Kokkos::subview(contact.surface_node_list(), std::make_pair(0, ns)));
  to.barea = Kokkos::View<double*>("fdem::barea", ns);
  allocate_springs<D>(to, ns);
  to.nb = ns;
  if (!loaded_.empty()) {  // a checkpoint's rows, per node
    settle_loaded(to);
  } else if (const int lost = carry_platen_rows<D>(m, m.nb, to, contact.surface_places()); lost > 0) {
    throw std::logic_error("platens: " + std::to_string(lost) + " nodes left the contact surfaces");
  }
  m.bnode = to.bnode;
  m.barea = to.barea;
  m.platen_fs = to.platen_fs;
  m.platen_g0 = to.platen_g0;
  m.nb = ns;
  grow_platen_areas<D>(m, contact.surface().narea, ns, t);
}

template <int D>
std::vector<double> Platens<D>::node_rows(const Model<D>& m, int which) const {
  const int np = m.platens.count, w = which == kFs ? D : 1;
  std::vector<double> out(static_cast<size_t>(which == kArea ? 1 : np) * m.nn * w, 0.0);
  auto bn = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.bnode);
  if (which == kArea) {
    auto a = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.barea);
    for (int b = 0; b < m.nb; ++b) out[bn(b)] = a(b);
  } else if (which == kG0) {
    auto g = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.platen_g0);
    for (int p = 0; p < np; ++p)
      for (int b = 0; b < m.nb; ++b) out[static_cast<size_t>(p) * m.nn + bn(b)] = g(p, b);
  } else {
    auto f = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.platen_fs);
    for (int p = 0; p < np; ++p)
      for (int b = 0; b < m.nb; ++b)
        for (int k = 0; k < D; ++k) out[(static_cast<size_t>(p) * m.nn + bn(b)) * D + k] = f(p, b, k);
  }
  return out;
}

template <int D>
void Platens<D>::settle_loaded(PlatenData<D>& to) {
  if (loaded_.empty()) return;
  const int np = to.platens.count;
  const size_t nn = loaded_nn_;
  const Kokkos::HostSpace host;
  auto bn = Kokkos::create_mirror_view_and_copy(host, to.bnode);
  auto a = Kokkos::create_mirror_view_and_copy(host, to.barea);
  auto g = Kokkos::create_mirror_view_and_copy(host, to.platen_g0);
  auto f = Kokkos::create_mirror_view_and_copy(host, to.platen_fs);
  const std::vector<double>&area = loaded_[kArea], &g0 = loaded_[kG0], &fs = loaded_[kFs];
  for (int b = 0; b < to.nb; ++b) {
    const size_t i = static_cast<size_t>(bn(b));
    if (!area.empty()) a(b) = area[i];
    for (int p = 0; p < np; ++p) {
      if (!g0.empty()) g(p, b) = g0[p * nn + i];
      for (int k = 0; k < D && !fs.empty(); ++k) f(p, b, k) = fs[(p * nn + i) * D + k];
    }
  }
  Kokkos::deep_copy(to.barea, a);
  Kokkos::deep_copy(to.platen_g0, g);
  Kokkos::deep_copy(to.platen_fs, f);
  loaded_.clear();
}

template <int D>
void Platens<D>::copy_accumulators(const Model<D>& m, long stamp) const {
  if (cached_at_ == stamp) return;
  Kokkos::deep_copy(acc_host_, m.platen_acc);
  if (driven_) Kokkos::deep_copy(motion_host_, m.platen_motion);
  cached_at_ = stamp;
}

template <int D>
void Platens<D>::book(const Model<D>& m, double t, double dt, long stamp, double& work, double& friction) const {
  // Works done by time t: everything before this step plus the part of this step's increment
  // (centred on x(n): over [t - dt/2, t + dt/2]) up to t.
  copy_accumulators(m, stamp);
  for (int p = 0; p < m.platens.count; ++p) {
    double inc = 0;
    for (int k = 0; k < 3; ++k)
      inc += acc_host_(p, kPlatenForce + k) * platen_velocity(m.platens.p[p], motion_host_, p, k, t, 0.5 * dt) * dt;
    work += acc_host_(p, kPlatenWork) - 0.5 * inc;
    friction += acc_host_(p, kPlatenFriction);
  }
}

template <int D>
std::vector<std::array<double, 3>> Platens<D>::forces(const Model<D>& m, const Parts<D>& parts, long stamp) const {
  copy_accumulators(m, stamp);
  std::vector<std::array<double, 3>> out(m.platens.count);
  for (int p = 0; p < m.platens.count; ++p)
    for (int k = 0; k < 3; ++k) out[p][k] = acc_host_(p, kPlatenForce + k);
  if (!out.empty()) {  // the parts' own boundary nodes: summed, the whole body's
    std::vector<double> flat;
    for (const auto& f : out) flat.insert(flat.end(), f.begin(), f.end());
    parts.sum(flat.data(), static_cast<int>(flat.size()));
    for (size_t i = 0; i < flat.size(); ++i) out[i / 3][i % 3] = flat[i];
  }
  return out;
}

template <int D>
double Platens<D>::displacement(const Model<D>& m, int p, double at) const {
  const PlatenDev& P = m.platens.p[p];
  double s2 = 0;
  if (P.inv_mass > 0) {  // its state at the last step's forces: `at` is their time
    Kokkos::deep_copy(motion_host_, m.platen_motion);
    for (int k = 0; k < 3; ++k) {
      const double s = P.vt[k] * at + motion_host_(p, kPlatenTravelAtForces) * P.n[k];
      s2 += s * s;
    }
  } else {
    for (int k = 0; k < 3; ++k) s2 += P.shift(k, at) * P.shift(k, at);
  }
  return std::sqrt(s2);
}

template <int D>
void Platens<D>::add_columns(std::vector<std::string>& cols) const {
  for (const auto& name : names_) {
    cols.push_back(name + "_displacement [m]");
    for (int k = 0; k < D; ++k) cols.push_back(name + "_force_" + kAxes[k] + " [N]");
    cols.push_back(name + "_load [N]");
  }
  for (size_t p = 0; p < names_.size(); ++p)  // a driven platen: its speed towards the body
    if (driven_platen_[p]) cols.push_back(names_[p] + "_speed [m/s]");
}

template <int D>
void Platens<D>::append_row(const Model<D>& m, const std::vector<std::array<double, 3>>& forces, double t,
                            std::vector<double>& row) const {
  for (int p = 0; p < m.platens.count; ++p) {
    const auto& F = forces[p];
    const auto& P = m.platens.p[p];
    row.push_back(displacement(m, p, t));
    for (int k = 0; k < D; ++k) row.push_back(F[k]);
    row.push_back(load(P, F));
  }
  for (int p = 0; p < m.platens.count; ++p)  // (displacement() has copied the motion)
    if (driven_platen_[p]) row.push_back(motion_host_(p, kPlatenSpeedAtForces));
}

template class Platens<2>;
template class Platens<3>;

}  // namespace fdem
