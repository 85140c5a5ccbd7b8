#include "solver/model_builder.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

#include "common/error.hpp"
#include "common/setup_times.hpp"
#include "kernels/host_loops.hpp"
#include "kernels/interface.hpp"
#include "solver/elastic_host.hpp"
#include "solver/interface_materials.hpp"
#include "solver/simulation.hpp"

namespace fdem {

namespace {

// Largest face measure of a simplex (2D: longest edge; 3D: largest face area).
template <int D>
double largest_face(const double (&x)[D + 1][D]) {
  double best = 0;
  for (int skip = 0; skip < D + 1; ++skip) {
    int idx[D], c = 0;
    for (int a = 0; a < D + 1; ++a)
      if (a != skip) idx[c++] = a;
    double meas;
    if constexpr (D == 2) {
      meas = std::hypot(x[idx[1]][0] - x[idx[0]][0], x[idx[1]][1] - x[idx[0]][1]);
    } else {
      double a[3], b[3];
      for (int k = 0; k < 3; ++k) {
        a[k] = x[idx[1]][k] - x[idx[0]][k];
        b[k] = x[idx[2]][k] - x[idx[0]][k];
      }
      meas = triangle_area(a, b);
    }
    best = std::max(best, meas);
  }
  return best;
}

template <class V>
auto mirror(const V& v) {
  return Kokkos::create_mirror_view(v);
}

}  // namespace

template <int D>
MaterialTable build_materials(const Case& c, const HostMesh& mesh, Model<D>& m) {
  const int nmat = static_cast<int>(c.materials.size());
  m.mat = Kokkos::View<double* [3]>("fdem::mat", nmat);
  auto mat_h = mirror(m.mat);
  MaterialTable t;
  t.cp.resize(nmat);
  t.rho.resize(nmat);
  for (int k = 0; k < nmat; ++k) {
    const auto& bm = c.materials[k];
    const Lame L = lame(bm.E, bm.nu, m.plane_stress);
    const double lam = L.lambda, mu = L.mu;
    mat_h(k, 0) = lam;
    mat_h(k, 1) = mu;
    mat_h(k, 2) = bm.density;
    t.rho[k] = bm.density;
    t.cp[k] = std::sqrt((lam + 2 * mu) / bm.density);
  }
  Kokkos::deep_copy(m.mat, mat_h);
  t.region_mat.assign(mesh.region_names.size(), -1);
  for (size_t r = 0; r < mesh.region_names.size(); ++r) {
    auto it = c.region_material.find(mesh.region_names[r]);
    if (it != c.region_material.end()) {
      t.region_mat[r] = it->second;
    } else if (nmat == 1) {
      t.region_mat[r] = 0;
    } else {
      throw InputError(c.file + ": regions: mesh region '" + mesh.region_names[r] + "' has no material");
    }
  }
  return t;
}

template <int D>
void build_nodes(const HostMesh& mesh, Model<D>& m) {
  const int nn = m.nn;
  m.X = Kokkos::View<double* [D]>("fdem::X", nn);
  m.x = Kokkos::View<double* [D]>("fdem::x", nn);
  m.v = Kokkos::View<double* [D]>("fdem::v", nn);
  m.f = Kokkos::View<double* [D]>("fdem::f", nn);
  auto X_h = mirror(m.X);
  host_for("fdem::build_nodes", nn, [&](int i) {
    for (int k = 0; k < D; ++k) X_h(i, k) = mesh.X[static_cast<size_t>(i) * D + k];
  });
  Kokkos::deep_copy(m.X, X_h);
  Kokkos::deep_copy(m.x, X_h);
}

template <int D>
ElementSetup build_elements(const Case& c, const HostMesh& mesh, const MaterialTable& mats, Model<D>& m) {
  const int ne = m.ne, nn = m.nn;
  m.elem = Kokkos::View<int* [D + 1]>("fdem::elem", ne);
  m.grad = Kokkos::View<double* [D][D]>("fdem::grad", ne);
  m.vol0 = Kokkos::View<double*>("fdem::vol0", ne);
  m.emat = Kokkos::View<int*>("fdem::emat", ne);
  auto elem_h = mirror(m.elem);
  auto grad_h = mirror(m.grad);
  auto vol_h = mirror(m.vol0);
  auto emat_h = mirror(m.emat);
  ElementSetup out;
  out.mass.assign(nn, 0.0);
  double fact = 1;
  for (int k = 2; k <= D; ++k) fact *= k;
  out.bulk_step = std::numeric_limits<double>::infinity();
  // Geometry element by element on the host's threads; then, in element order, the checks, the
  // lumped masses (the same sums in the same order whatever the threads) and the bulk step.
  std::vector<double> det_e(ne), dt_e(ne);
  host_for("fdem::build_elements", ne, [&](int e) {
    double xe[D + 1][D], A[D][D], B[D][D];
    for (int a = 0; a < D + 1; ++a) {
      elem_h(e, a) = mesh.elems[static_cast<size_t>(e) * (D + 1) + a];
      for (int k = 0; k < D; ++k) xe[a][k] = mesh.X[static_cast<size_t>(elem_h(e, a)) * D + k];
    }
    for (int i = 0; i < D; ++i)
      for (int b = 0; b < D; ++b) A[i][b] = xe[b + 1][i] - xe[0][i];
    const double dA = det<D>(A);
    det_e[e] = dA;
    if (!(dA > 0)) return;
    inverse<D>(A, B);  // rows of B are the gradients of N_1..N_D
    for (int b = 0; b < D; ++b)
      for (int j = 0; j < D; ++j) grad_h(e, b, j) = B[b][j];
    const double meas = dA / fact;
    vol_h(e) = meas * m.thickness;
    const int mt = mats.region_mat[mesh.elem_region[e]];
    emat_h(e) = mt;
    const double h = D * meas / largest_face<D>(xe);  // shortest altitude
    dt_e[e] = h / mats.cp[mt];
  });
  for (int e = 0; e < ne; ++e) {
    if (!(det_e[e] > 0)) {
      std::ostringstream os;
      os << c.file << ": element " << e << " is inverted or degenerate (signed measure " << det_e[e] / fact
         << ")";
      throw InputError(os.str());
    }
    const int mt = emat_h(e);
    for (int a = 0; a < D + 1; ++a) out.mass[elem_h(e, a)] += mats.rho[mt] * vol_h(e) / (D + 1);
    if (dt_e[e] < out.bulk_step) {
      out.bulk_step = dt_e[e];
      out.bulk_element = e;
    }
  }
  for (int e = 0; e < ne; ++e) out.volume += vol_h(e);
  Kokkos::deep_copy(m.elem, elem_h);
  Kokkos::deep_copy(m.grad, grad_h);
  Kokkos::deep_copy(m.vol0, vol_h);
  Kokkos::deep_copy(m.emat, emat_h);
  m.mass = Kokkos::View<double*>("fdem::mass", nn);
  auto mass_h = mirror(m.mass);
  for (int i = 0; i < nn; ++i) mass_h(i) = out.mass[i] > 0 ? out.mass[i] : 1.0;  // orphan nodes: inert
  Kokkos::deep_copy(m.mass, mass_h);
  return out;
}

CohesiveParams cohesive_params(const InterfaceMaterial& im) {
  // (a frictional joint starts failed and handed over: its interfaces never act)
  const double tanphir = im.residual_friction && !im.frictional() ? std::tan(im.phi_r) : -1.0;
  return CohesiveParams{im.kn, im.ks, im.ft, im.c, std::tan(im.phi), im.Gnc, im.Gsc, im.eta, tanphir};
}

// The per-interface material table, index and strength factors (InterfaceData::params); nothing
// for a run with one interface material and no scatter.
template <int D>
void upload_interface_materials(const Case& c, const InterfaceMaterialMap& map, Model<D>& m) {
  if (map.material.empty()) return;
  const int nm = static_cast<int>(c.interface_materials.size());
  m.coh_table = Kokkos::View<CohesiveParams*>("fdem::coh_table", nm);
  auto t_h = mirror(m.coh_table);
  for (int k = 0; k < nm; ++k) t_h(k) = cohesive_params(c.interface_materials[k]);
  Kokkos::deep_copy(m.coh_table, t_h);
  m.imat = Kokkos::View<int*>("fdem::imat", map.material.size());
  auto im_h = mirror(m.imat);
  for (size_t q = 0; q < map.material.size(); ++q) im_h(q) = map.material[q];
  Kokkos::deep_copy(m.imat, im_h);
  if (!map.scale.empty()) {
    m.iscale = Kokkos::View<float*>("fdem::iscale", map.scale.size());
    auto s_h = mirror(m.iscale);
    for (size_t q = 0; q < map.scale.size(); ++q) s_h(q) = map.scale[q];
    Kokkos::deep_copy(m.iscale, s_h);
  }
  m.scale_energy = c.scatter.energy;
}

// The friction of the interfaces: slip states (m.islip) when some interface's material has
// a residual friction (InterfaceMaterial::residual_friction); the friction of the
// contact faces each interface leaves (m.ifric: a frictional joint's tan(phi), a softening
// material's residual tan(phi_r), -1 for the paper's law) when some interface takes either.
// Interfaces of frictional joint materials (no tension, no cohesion) start failed (damage 1 at
// every point, nothing dissipated) and handed over to contact. Nothing when no interface needs it.
template <int D>
void start_interface_friction(const Case& c, const InterfaceMaterialMap& map, Model<D>& m) {
  auto material = [&](int q) -> const InterfaceMaterial& {
    return c.interface_materials[map.material.empty() ? c.fracture_material : map.material[q]];
  };
  bool joints = false, slip = false;
  for (int q = 0; q < m.ni && !(joints && slip); ++q) {
    joints = joints || material(q).frictional();
    slip = slip || (!material(q).frictional() && material(q).residual_friction);
  }
  if (slip) m.islip = Kokkos::View<double* [D][D + 1]>("fdem::islip", m.ni);
  if (!joints && !slip) return;
  m.ifric = Kokkos::View<double*>("fdem::ifric", m.ni);
  auto fr_h = mirror(m.ifric);
  auto h_h = Kokkos::create_mirror_view(m.ihist);
  auto ic_h = Kokkos::create_mirror_view(m.icontact);
  Kokkos::deep_copy(h_h, m.ihist);
  Kokkos::deep_copy(ic_h, m.icontact);
  for (int q = 0; q < m.ni; ++q) {
    const InterfaceMaterial& iq = material(q);
    fr_h(q) = iq.frictional() ? std::tan(iq.phi) : iq.residual_friction ? std::tan(iq.phi_r) : -1.0;
    if (!iq.frictional()) continue;
    for (int k = 0; k < D; ++k) store_point(h_h, q, k, failed_point());  // damage 1, nothing dissipated
    ic_h(q) = 1;
  }
  Kokkos::deep_copy(m.ifric, fr_h);
  Kokkos::deep_copy(m.ihist, h_h);
  Kokkos::deep_copy(m.icontact, ic_h);
}

template <int D>
double build_interfaces(const Case& c, const HostMesh& mesh, const std::vector<double>& mass, Model<D>& m) {
  const int ni = m.ni;
  double step = std::numeric_limits<double>::infinity();
  m.iface = Kokkos::View<int* [2 * D]>("fdem::iface", ni);
  m.ihist = Kokkos::View<double* [D][kPointHistory]>("fdem::ihist", ni);
  m.iarea = Kokkos::View<double*>("fdem::iarea", ni);
  m.icontact = Kokkos::View<int*>("fdem::icontact", ni);
  if (ni == 0) return step;
  if (c.fracture_material < 0) throw InputError(c.file + ": fracture: no interface material");
  const auto& im = c.interface_materials[c.fracture_material];
  m.coh = cohesive_params(im);
  const InterfaceMaterialMap map = interface_material_map(c, mesh);
  upload_interface_materials<D>(c, map, m);
  auto if_h = mirror(m.iface);
  auto ia_h = mirror(m.iarea);
  std::vector<double> step_q(ni);  // each interface's springs' stable step; their minimum below
  host_for("fdem::build_interfaces", ni, [&](int q) {
    const auto& iq = map.material.empty() ? im : c.interface_materials[map.material[q]];
    const double kmax = std::max(iq.kn, iq.ks);
    double xa[D][D], xb[D][D], n[D], ap;
    for (int k = 0; k < 2 * D; ++k) if_h(q, k) = mesh.ifaces[static_cast<size_t>(q) * 2 * D + k];
    for (int k = 0; k < D; ++k)
      for (int i = 0; i < D; ++i) {
        xa[k][i] = mesh.X[static_cast<size_t>(if_h(q, k)) * D + i];
        xb[k][i] = xa[k][i];
      }
    interface_frame<D>(xa, xb, m.thickness, n, ap);
    ia_h(q) = ap;
    double sq = std::numeric_limits<double>::infinity();
    for (int k = 0; k < D; ++k) {
      const double w = std::sqrt(kmax * ap * (1 / mass[if_h(q, k)] + 1 / mass[if_h(q, D + k)]));
      sq = std::min(sq, 2.0 / w);
    }
    step_q[q] = sq;
  });
  for (int q = 0; q < ni; ++q) step = std::min(step, step_q[q]);
  Kokkos::deep_copy(m.iface, if_h);
  Kokkos::deep_copy(m.iarea, ia_h);
  start_interface_friction<D>(c, map, m);
  return step;
}

template <int D>
void build_interface_chunks(const HostMesh& mesh, Model<D>& m) {
  const int ni = m.ni, ne = m.ne;
  if (ni == 0) return;
  bool ordered = kChunk > 1 && mesh.iface_elems.size() == 2 * static_cast<size_t>(ni);
  for (int q = 1; ordered && q < ni; ++q) ordered = mesh.iface_elems[2 * q] >= mesh.iface_elems[2 * (q - 1)];
  if (!ordered) return;
  const int nbc = (ne + kChunk - 1) / kChunk;
  m.ichunk = Kokkos::View<int*>("fdem::ichunk", nbc + 1);
  auto ic_h = mirror(m.ichunk);
  int q = 0;
  for (int c = 0; c <= nbc; ++c) {
    const long e0 = std::min(static_cast<long>(c) * kChunk, static_cast<long>(ne));
    while (q < ni && mesh.iface_elems[2 * static_cast<size_t>(q)] < e0) ++q;
    ic_h(c) = c == nbc ? ni : q;
  }
  Kokkos::deep_copy(m.ichunk, ic_h);
}

template <int D>
Simulation<D>::Simulation(const Case& given, const HostMesh& mesh) {
  if (mesh.dim != D) throw InputError(given.file + ": mesh dimension does not match 'dimension'");
  using setup_times::Phase;
  Phase build("model_build");  // what the phases below do not cover
  // The derived values (a run has filled them already; a case built in code may not have).
  Case c = given;
  resolve_defaults(c, mesh);
  m.nn = mesh.num_nodes();
  m.ne = mesh.num_elems();
  m.ni = mesh.num_ifaces();
  if (mesh.owned_nodes >= 0) {  // one part of a decomposed run (src/parallel/decompose.hpp)
    m.nn_own = mesh.owned_nodes;
    m.ne_own = mesh.owned_elems;
    m.ni_own = mesh.owned_ifaces;
    m.ne_bulk = mesh.bulk_elems;
  }
  m.thickness = D == 2 ? c.thickness : 1.0;
  m.plane_stress = D == 2 && c.plane_stress;
  m.mixed_precision = c.mixed_precision;

  const MaterialTable mats = build_materials<D>(c, mesh, m);
  Phase elements("model_elements");
  build_nodes<D>(mesh, m);
  const ElementSetup el = build_elements<D>(c, mesh, mats, m);
  elements.stop();
  double emin = std::numeric_limits<double>::infinity();
  for (const auto& bm : c.materials) emin = std::min(emin, bm.E);
  energy_floor_ = 0.5 * emin * 1e-12 * el.volume;  // the strain energy at strain 1e-6
  StepContributions& sc = step_sources_;
  sc.bulk = el.bulk_step;
  sc.bulk_element = el.bulk_element;

  Phase interfaces("model_interfaces");
  sc.interfaces = build_interfaces<D>(c, mesh, el.mass, m);
  coh0_ = m.coh;
  cuts_.configure(c.rebalance_above, c.work_model);
  build_interface_chunks<D>(mesh, m);
  interfaces.stop();

  platens_.build(c, mesh, el.mass, m, sc);

  loads_.build(c, mesh, m, prm_);

  if (contact_wanted(c, mesh)) {
    Phase contact("contact_setup");
    contact_ = std::make_unique<ContactSystem<D>>(c, mesh, m, el.mass);
    mu0_ = contact_->law.mu;
    sc.has_contact = true;
    sc.contact = contact_->stable_step();
    // with contact, the platens act on every surface node, crack faces included: their springs
    // count with each node's largest possible area
    platens_.contact_step(m, contact_->take_potential_area(), el.mass, sc);
    platens_.follow_surfaces(m, *contact_, t);
    sc.may_meet = contact_meet_ = contact_->may_meet();
  }
  force_pass_contributes_ = parts_.force_pass_contributes(contact_ != nullptr);

  sc.dt_cap = c.dt;
  sc.safety = c.safety_factor;
  const TimeStep ts = decide_stable_step(sc);
  stable = ts.stable;
  dt = ts.dt;
  check_step_count(c.file, dt, c.end_time, c.max_steps, stable);

  prm_.alpha = c.local_damping;
  prm_.cmass = c.mass_damping;
  scatter_ = ForceScatter<D>(m.f);
}

#define FDEM_BUILDERS(D)                                                                                    \
  template MaterialTable build_materials<D>(const Case&, const HostMesh&, Model<D>&);                      \
  template void build_nodes<D>(const HostMesh&, Model<D>&);                                                \
  template ElementSetup build_elements<D>(const Case&, const HostMesh&, const MaterialTable&, Model<D>&);   \
  template double build_interfaces<D>(const Case&, const HostMesh&, const std::vector<double>&, Model<D>&); \
  template void build_interface_chunks<D>(const HostMesh&, Model<D>&);                                     \
  template Simulation<D>::Simulation(const Case&, const HostMesh&);
FDEM_BUILDERS(2)
FDEM_BUILDERS(3)
#undef FDEM_BUILDERS

}  // namespace fdem
