#include "solver/simulation.hpp"

#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <sstream>

#include "common/error.hpp"
#include "solver/state_io.hpp"

namespace fdem {

namespace {

template <int D>
double det(const double (&A)[D][D]) {
  if constexpr (D == 2) {
    return A[0][0] * A[1][1] - A[0][1] * A[1][0];
  } else {
    return A[0][0] * (A[1][1] * A[2][2] - A[1][2] * A[2][1]) -
           A[0][1] * (A[1][0] * A[2][2] - A[1][2] * A[2][0]) +
           A[0][2] * (A[1][0] * A[2][1] - A[1][1] * A[2][0]);
  }
}

template <int D>
void inverse(const double (&A)[D][D], double (&B)[D][D]) {
  const double d = det<D>(A);
  if constexpr (D == 2) {
    B[0][0] = A[1][1] / d; B[0][1] = -A[0][1] / d;
    B[1][0] = -A[1][0] / d; B[1][1] = A[0][0] / d;
  } else {
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        const int i1 = (j + 1) % 3, i2 = (j + 2) % 3, j1 = (i + 1) % 3, j2 = (i + 2) % 3;
        B[i][j] = (A[i1][j1] * A[i2][j2] - A[i1][j2] * A[i2][j1]) / d;
      }
  }
}

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
      meas = 0.5 * std::sqrt(std::pow(a[1] * b[2] - a[2] * b[1], 2) +
                             std::pow(a[2] * b[0] - a[0] * b[2], 2) +
                             std::pow(a[0] * b[1] - a[1] * b[0], 2));
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
Simulation<D>::Simulation(const Case& c, const HostMesh& mesh) {
  if (mesh.dim != D) throw InputError(c.file + ": mesh dimension does not match 'dimension'");
  const int nn = mesh.num_nodes(), ne = mesh.num_elems(), ni = mesh.num_ifaces();
  m.nn = nn;
  m.ne = ne;
  m.ni = ni;
  m.thickness = D == 2 ? c.thickness : 1.0;
  m.plane_stress = D == 2 && c.plane_stress;

  // ---- materials: region -> material index; Lame constants (plane-stress corrected) ----
  const int nmat = static_cast<int>(c.materials.size());
  m.mat = Kokkos::View<double* [3]>("fdem::mat", nmat);
  auto mat_h = mirror(m.mat);
  std::vector<double> cp(nmat), rho(nmat);
  for (int k = 0; k < nmat; ++k) {
    const auto& bm = c.materials[k];
    double lam = bm.E * bm.nu / ((1 + bm.nu) * (1 - 2 * bm.nu));
    const double mu = bm.E / (2 * (1 + bm.nu));
    if (m.plane_stress) lam = 2 * lam * mu / (lam + 2 * mu);
    mat_h(k, 0) = lam;
    mat_h(k, 1) = mu;
    mat_h(k, 2) = bm.density;
    rho[k] = bm.density;
    cp[k] = std::sqrt((lam + 2 * mu) / bm.density);
  }
  Kokkos::deep_copy(m.mat, mat_h);
  std::vector<int> region_mat(mesh.region_names.size(), -1);
  for (size_t r = 0; r < mesh.region_names.size(); ++r) {
    auto it = c.region_material.find(mesh.region_names[r]);
    if (it == c.region_material.end()) {
      if (nmat == 1) {
        region_mat[r] = 0;
      } else {
        throw InputError(c.file + ": regions: mesh region '" + mesh.region_names[r] +
                         "' has no material");
      }
    } else {
      region_mat[r] = it->second;
    }
  }

  // ---- nodes ----
  m.X = Kokkos::View<double* [D]>("fdem::X", nn);
  m.x = Kokkos::View<double* [D]>("fdem::x", nn);
  m.v = Kokkos::View<double* [D]>("fdem::v", nn);
  m.f = Kokkos::View<double* [D]>("fdem::f", nn);
  m.mass = Kokkos::View<double*>("fdem::mass", nn);
  auto X_h = mirror(m.X);
  for (int i = 0; i < nn; ++i)
    for (int k = 0; k < D; ++k) X_h(i, k) = mesh.X[static_cast<size_t>(i) * D + k];
  Kokkos::deep_copy(m.X, X_h);
  Kokkos::deep_copy(m.x, X_h);

  // ---- elements: reference gradients, volumes, lumped masses, bulk stable step ----
  m.elem = Kokkos::View<int* [D + 1]>("fdem::elem", ne);
  m.grad = Kokkos::View<double* [D][D]>("fdem::grad", ne);
  m.vol0 = Kokkos::View<double*>("fdem::vol0", ne);
  m.emat = Kokkos::View<int*>("fdem::emat", ne);
  auto elem_h = mirror(m.elem);
  auto grad_h = mirror(m.grad);
  auto vol_h = mirror(m.vol0);
  auto emat_h = mirror(m.emat);
  std::vector<double> mass(nn, 0.0);
  double fact = 1;
  for (int k = 2; k <= D; ++k) fact *= k;
  stable.bulk = std::numeric_limits<double>::infinity();
  for (int e = 0; e < ne; ++e) {
    double xe[D + 1][D], A[D][D], B[D][D];
    for (int a = 0; a < D + 1; ++a) {
      elem_h(e, a) = mesh.elems[static_cast<size_t>(e) * (D + 1) + a];
      for (int k = 0; k < D; ++k) xe[a][k] = mesh.X[static_cast<size_t>(elem_h(e, a)) * D + k];
    }
    for (int i = 0; i < D; ++i)
      for (int b = 0; b < D; ++b) A[i][b] = xe[b + 1][i] - xe[0][i];
    const double dA = det<D>(A);
    if (!(dA > 0)) {
      std::ostringstream os;
      os << c.file << ": element " << e << " is inverted or degenerate (signed measure "
         << dA / fact << ")";
      throw InputError(os.str());
    }
    inverse<D>(A, B);  // rows of B are the gradients of N_1..N_D
    for (int b = 0; b < D; ++b)
      for (int j = 0; j < D; ++j) grad_h(e, b, j) = B[b][j];
    const double meas = dA / fact;
    vol_h(e) = meas * m.thickness;
    const int mt = region_mat[mesh.elem_region[e]];
    emat_h(e) = mt;
    for (int a = 0; a < D + 1; ++a) mass[elem_h(e, a)] += rho[mt] * vol_h(e) / (D + 1);
    const double h = D * meas / largest_face<D>(xe);  // shortest altitude
    const double dte = h / cp[mt];
    if (dte < stable.bulk) {
      stable.bulk = dte;
      stable.bulk_element = e;
    }
  }
  double volume = 0, emin = std::numeric_limits<double>::infinity();
  for (int e = 0; e < ne; ++e) volume += vol_h(e);
  for (const auto& bm : c.materials) emin = std::min(emin, bm.E);
  energy_floor_ = 0.5 * emin * 1e-12 * volume;
  Kokkos::deep_copy(m.elem, elem_h);
  Kokkos::deep_copy(m.grad, grad_h);
  Kokkos::deep_copy(m.vol0, vol_h);
  Kokkos::deep_copy(m.emat, emat_h);
  auto mass_h = mirror(m.mass);
  for (int i = 0; i < nn; ++i) mass_h(i) = mass[i] > 0 ? mass[i] : 1.0;  // orphan nodes: inert
  Kokkos::deep_copy(m.mass, mass_h);

  // ---- interfaces ----
  stable.springs = std::numeric_limits<double>::infinity();
  m.iface = Kokkos::View<int* [2 * D]>("fdem::iface", ni);
  m.ihist = Kokkos::View<double* [D][4]>("fdem::ihist", ni);
  m.iarea = Kokkos::View<double*>("fdem::iarea", ni);
  m.icontact = Kokkos::View<int*>("fdem::icontact", ni);
  if (ni > 0) {
    if (c.fracture_material < 0) throw InputError(c.file + ": fracture: no interface material");
    const auto& im = c.interface_materials[c.fracture_material];
    m.coh = CohesiveParams{im.kn, im.ks, im.ft, im.c, std::tan(im.phi), im.Gnc, im.Gsc, im.eta};
    coh0_ = m.coh;
    auto if_h = mirror(m.iface);
    auto ia_h = mirror(m.iarea);
    const double kmax = std::max(im.kn, im.ks);
    for (int q = 0; q < ni; ++q) {
      double xa[D][D], xb[D][D], n[D], ap;
      for (int k = 0; k < 2 * D; ++k) if_h(q, k) = mesh.ifaces[static_cast<size_t>(q) * 2 * D + k];
      for (int k = 0; k < D; ++k)
        for (int i = 0; i < D; ++i) {
          xa[k][i] = mesh.X[static_cast<size_t>(if_h(q, k)) * D + i];
          xb[k][i] = xa[k][i];
        }
      interface_frame<D>(xa, xb, m.thickness, n, ap);
      ia_h(q) = ap;
      for (int k = 0; k < D; ++k) {
        const double w = std::sqrt(kmax * ap * (1 / mass[if_h(q, k)] + 1 / mass[if_h(q, D + k)]));
        stable.springs = std::min(stable.springs, 2.0 / w);
      }
    }
    Kokkos::deep_copy(m.iface, if_h);
    Kokkos::deep_copy(m.iarea, ia_h);
    // fused force pass (host backends): interfaces in order of their side-A element
    bool ordered = kChunk > 1 && mesh.iface_elems.size() == 2 * static_cast<size_t>(ni);
    for (int q = 1; ordered && q < ni; ++q) ordered = mesh.iface_elems[2 * q] >= mesh.iface_elems[2 * (q - 1)];
    if (ordered) {
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
  }

  // ---- outer boundary (platen contact) ----
  if (!c.platens.empty()) {
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
        meas = 0.5 * std::sqrt(std::pow(a[1] * b[2] - a[2] * b[1], 2) +
                               std::pow(a[2] * b[0] - a[0] * b[2], 2) +
                               std::pow(a[0] * b[1] - a[1] * b[0], 2));
      }
      for (int k = 0; k < D; ++k) area[faces[fi * D + k]] += meas / D;
    }
    m.nb = static_cast<int>(area.size());
    m.bnode = Kokkos::View<int*>("fdem::bnode", m.nb);
    m.barea = Kokkos::View<double*>("fdem::barea", nn);
    auto bn_h = mirror(m.bnode);
    auto ba_h = mirror(m.barea);
    int b = 0;
    for (const auto& [node, a] : area) {
      bn_h(b) = node;
      ba_h(node) = a;
      ++b;
    }
    Kokkos::deep_copy(m.bnode, bn_h);
    Kokkos::deep_copy(m.barea, ba_h);

    if (static_cast<int>(c.platens.size()) > kMaxPlatens)
      throw InputError(c.file + ": platens: at most " + std::to_string(kMaxPlatens) + " allowed");
    // default platen stiffness: the interface stiffness, else 10 E / mean element size
    double kn_default = 0, ks_ratio = 0.4;
    if (c.fracture_material >= 0) {
      kn_default = c.interface_materials[c.fracture_material].kn;
      ks_ratio = c.interface_materials[c.fracture_material].ks / kn_default;
    } else {
      double emax = 0, nu = 0.25;
      for (const auto& bm : c.materials)
        if (bm.E > emax) { emax = bm.E; nu = bm.nu; }
      const auto q = mesh_quality(mesh);
      kn_default = 10 * emax / q.mean_size;
      ks_ratio = 1.0 / (2 * (1 + nu));
    }
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
      }
      P.kn = ps.kn > 0 ? ps.kn : kn_default;
      P.ks = ps.ks > 0 ? ps.ks : P.kn * ks_ratio;
      P.mu = ps.friction;
      P.coh = ps.cohesion;
      platen_names_.push_back(ps.name);
      for (int bb = 0; bb < m.nb; ++bb) {
        const double w = std::sqrt(std::max(P.kn, P.ks) * ba_h(bn_h(bb)) / mass[bn_h(bb)]);
        stable.springs = std::min(stable.springs, 2.0 / w);
      }
    }
    m.platen_fs = Kokkos::View<double** [D]>("fdem::platen_fs", m.platens.count, nn);
    m.platen_g0 = Kokkos::View<double**>("fdem::platen_g0", m.platens.count, nn);
  }
  m.platen_acc = Kokkos::View<double* [kPlatenAcc]>("fdem::platen_acc", std::max(1, m.platens.count));
  platen_acc_host_ = Kokkos::create_mirror_view(m.platen_acc);

  // ---- velocity BCs: per node one entry of the BC table (merged where sets overlap) ----
  std::vector<BCDev> table;
  std::vector<int> node_bc(nn, -1);
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
    const int id = static_cast<int>(table.size());
    table.push_back(d);
    bc_names_.push_back(bc.set);
    const auto& nodes = mesh.node_sets.at(bc.set);
    Kokkos::View<int*> nv("fdem::bc_nodes", nodes.size());
    auto nv_h = mirror(nv);
    for (size_t j = 0; j < nodes.size(); ++j) {
      const int i = nodes[j];
      nv_h(j) = i;
      if (node_bc[i] < 0) {
        node_bc[i] = id;
      } else {
        auto key = std::make_pair(node_bc[i], id);
        auto it = merged.find(key);
        if (it == merged.end()) {
          BCDev md = table[node_bc[i]];
          md.mask |= d.mask;
          for (int k = 0; k < D; ++k)
            if (d.mask >> k & 1) md.vel[k] = d.vel[k];
          md.ramp = std::max(md.ramp, d.ramp);
          it = merged.emplace(key, static_cast<int>(table.size())).first;
          table.push_back(md);
        }
        node_bc[i] = it->second;
      }
    }
    Kokkos::deep_copy(nv, nv_h);
    bc_nodes_.push_back(nv);
  }
  reactions_.assign(bc_nodes_.size(), {0, 0, 0});
  m.bcs = Kokkos::View<BCDev*>("fdem::bcs", table.size());
  auto bcs_h = mirror(m.bcs);
  for (size_t b = 0; b < table.size(); ++b) bcs_h(b) = table[b];
  Kokkos::deep_copy(m.bcs, bcs_h);
  m.node_bc = Kokkos::View<int*>("fdem::node_bc", nn);
  auto nbc_h = mirror(m.node_bc);
  for (int i = 0; i < nn; ++i) nbc_h(i) = node_bc[i];
  Kokkos::deep_copy(m.node_bc, nbc_h);

  // ---- point loads (total force shared by the set's nodes), gravity, initial velocity ----
  if (!c.point_loads.empty()) {
    m.fext = Kokkos::View<double* [D]>("fdem::fext", nn);
    auto fe_h = mirror(m.fext);
    for (const auto& pl : c.point_loads) {
      const auto& nodes = mesh.node_sets.at(pl.set);
      for (int i : nodes)
        for (int k = 0; k < D; ++k) fe_h(i, k) += pl.force[k] / static_cast<double>(nodes.size());
    }
    Kokkos::deep_copy(m.fext, fe_h);
  } else {
    m.fext = Kokkos::View<double* [D]>("fdem::fext", 0);
  }
  for (int k = 0; k < 3; ++k) gravity_[k] = c.gravity[k];
  if (!c.initial_velocities.empty()) {
    auto v_h = mirror(m.v);
    for (const auto& iv : c.initial_velocities) {
      const int r = iv.region == "all" ? -1 : mesh.region_index(iv.region);
      for (int e = 0; e < ne; ++e)
        if (r < 0 || mesh.elem_region[e] == r)
          for (int a = 0; a < D + 1; ++a)
            for (int k = 0; k < D; ++k) v_h(elem_h(e, a), k) = iv.velocity[k];
    }
    Kokkos::deep_copy(m.v, v_h);
  }

  // Velocity BCs hold from the start: v(-dt/2) of a constrained component is its prescribed value
  // (0 for a ramp), so the run does not begin with an impulse.
  if (!table.empty()) {
    auto v_h = mirror(m.v);
    Kokkos::deep_copy(v_h, m.v);
    for (int i = 0; i < nn; ++i) {
      if (node_bc[i] < 0) continue;
      const BCDev& b = table[node_bc[i]];
      for (int k = 0; k < D; ++k)
        if (b.mask >> k & 1) v_h(i, k) = b.ramp > 0 ? 0.0 : b.vel[k];
    }
    Kokkos::deep_copy(m.v, v_h);
  }

  // ---- contact between bodies and fragments ----
  stable.springs_contact = stable.springs;
  if (contact_wanted(c, mesh)) {
    contact_ = std::make_unique<ContactSystem<D>>(c, mesh, m, mass);
    mu0_ = contact_->law.mu;
    stable.springs_contact = std::min(stable.springs, contact_->stable_step());
    // with contact, the platens act on every surface node, crack faces included: their springs
    // count with each node's largest possible area
    const std::vector<double>& amax = contact_->potential_area();
    for (int p = 0; p < m.platens.count; ++p) {
      const PlatenDev& P = m.platens.p[p];
      for (int i = 0; i < nn; ++i)
        if (amax[i] > 0 && mass[i] > 0)
          stable.springs_contact =
              std::min(stable.springs_contact, 2.0 / std::sqrt(std::max(P.kn, P.ks) * amax[i] / mass[i]));
    }
    sync_platen_nodes();
  }

  // ---- time step ----
  // Until surfaces can meet (a single body whose interfaces are all intact) the contact springs
  // and the platens' springs on crack faces act on nothing: the step is set without them and
  // shortened on the step on which the first surfaces can meet (apply_contact_step).
  auto combine = [&](double springs) {
    return 1.0 / std::sqrt(1.0 / (stable.bulk * stable.bulk) +
                           (std::isfinite(springs) ? 1.0 / (springs * springs) : 0.0));
  };
  stable.critical_contact = combine(stable.springs_contact);
  stable.contact_pending = contact_ && !contact_->may_meet() && stable.springs_contact < stable.springs;
  if (!stable.contact_pending) stable.springs = stable.springs_contact;
  stable.critical = combine(stable.springs);
  safety_ = c.safety_factor;
  dt_cap_ = c.dt;
  dt = c.safety_factor * stable.critical;
  if (c.dt > 0 && c.dt < dt) dt = c.dt;

  prm_.alpha = c.local_damping;
  prm_.cmass = c.mass_damping;
  for (int k = 0; k < 3; ++k) prm_.gravity[k] = c.gravity[k];
  prm_.has_fext = m.fext.extent(0) > 0;
  scatter_ = ForceScatter<D>(m.f);
}

template <int D>
void Simulation<D>::set_strength_reduction(double factor) {
  if (!(factor > 0) || !std::isfinite(factor))
    throw InputError("strength reduction factor must be positive and finite (got " + std::to_string(factor) + ")");
  srf_ = factor;
  m.coh.ft = coh0_.ft / factor;
  m.coh.c = coh0_.c / factor;
  m.coh.tanphi = coh0_.tanphi / factor;
  m.coh.rescale = srf_hist_ / factor;
  if (contact_) contact_->law.mu = mu0_ / factor;
}

template <int D>
void Simulation<D>::step(bool sample) {
  sample = sample || !have_reference_;
  Kokkos::Timer clock;
  auto lap = [&clock](double& phase) {  // the phase's kernels finish before its clock stops
    Kokkos::fence();
    phase += clock.seconds();
    clock.reset();
  };
  compute_forces<D>(m, scatter_, /*contribute=*/!contact_);
  if (m.coh.rescale != 1.0) {  // the histories now follow the present strength
    m.coh.rescale = 1.0;
    srf_hist_ = srf_;
  }
  lap(phase_times_.forces);
  apply_platens<D>(m, t, dt);
  lap(phase_times_.platens);
  if (contact_) {
    contact_->update(m, dt, scatter_);  // into the force kernel's scatter view, then one contribute
    Kokkos::Experimental::contribute(m.f, scatter_);
    if (contact_->surface_version() != platen_surface_version_) sync_platen_nodes();
    if (stable.contact_pending && contact_->may_meet()) apply_contact_step();
    lap(phase_times_.contact);
  }
  if (sample_reactions_) {
    for (size_t b = 0; b < bc_nodes_.size(); ++b) {
      double s[3] = {0, 0, 0};
      node_list_force<D>(m, bc_nodes_[b], s);
      for (int k = 0; k < 3; ++k) reactions_[b][k] = -s[k];
    }
  }
  Energies e;
  e.time = t;
  e.step = step_count;
  if (sample) {  // state at time t: positions x(n), forces and interface history at x(n)
    e.strain = strain_energy<D>(m);
    if (m.ni > 0) {
      const auto is = interface_state<D>(m);
      e.interface_elastic = is.v[0];
      e.fracture = is.v[1];
      e.damaged = static_cast<long>(is.v[2]);
      e.failed = static_cast<long>(is.v[3]);
    }
    e.contact_elastic = platen_energy<D>(m, t) + (contact_ ? contact_->elastic_energy() : 0.0);
  }
  lap(phase_times_.ledger);
  const NodeSums w = update_nodes_now(sample);
  lap(phase_times_.nodes);
  if (sample) {
    // Works done by time t: everything before this step plus half of this step's increment
    // (the increments are centred on x(n)).
    Kokkos::deep_copy(platen_acc_host_, m.platen_acc);
    double wp = 0;
    for (int p = 0; p < m.platens.count; ++p) {
      double inc = 0;
      for (int k = 0; k < 3; ++k) inc += platen_acc_host_(p, k) * m.platens.p[p].vel[k] * dt;
      wp += platen_acc_host_(p, 3) - 0.5 * inc;
      e.friction += platen_acc_host_(p, 4);
    }
    if (contact_) e.friction += contact_->dissipated();
    e.kinetic = w.v[2];
    for (int k = 0; k < 3; ++k) e.momentum[k] = w.v[5 + k];
    e.damping = work_damping_ + 0.5 * w.v[0];
    e.work_external = wp + work_bc_ + 0.5 * w.v[1] + w.v[3] + w.v[4];
    const double now = e.kinetic + e.strain + e.interface_elastic + e.contact_elastic +
                       e.fracture + e.damping + e.friction;
    if (!have_reference_) {
      reference_ = now - e.work_external;
      have_reference_ = true;
    }
    e.balance_error = now - e.work_external - reference_;
    e.scale = std::max({std::fabs(now), std::fabs(reference_) + std::fabs(e.work_external),
                        energy_floor_, 1e-300});
    energies_ = e;
  }
  work_damping_ += w.v[0];
  work_bc_ += w.v[1];
  t += dt;
  ++step_count;
  lap(phase_times_.ledger);
  ++phase_times_.steps;
}

template <int D>
double Simulation<D>::contact_step(double dt_now) const {
  // the same fraction of the critical step as before; a case's time.dt stays the limit
  double next = dt_now * stable.critical_contact / stable.critical;
  if (dt_cap_ > 0) next = std::max(next, std::min({dt_now, dt_cap_, safety_ * stable.critical_contact}));
  return std::min(next, dt_now);
}

template <int D>
void Simulation<D>::take_contact_step() {
  dt = contact_step(dt);
  stable.springs = stable.springs_contact;
  stable.critical = stable.critical_contact;
  stable.contact_pending = false;
}

template <int D>
void Simulation<D>::apply_contact_step() {
  // Leap-frog with a step change at x(n): v(n+1/2) = v(n-1/2) + (dt_old + dt_new) / 2 a(n),
  // x(n+1) = x(n) + dt_new v(n+1/2). The contact forces of this step are already in m.f.
  dt_before_change_ = dt;
  dt_changed_at_ = step_count;
  take_contact_step();
  dtv_next_ = 0.5 * (dt_before_change_ + dt);
}

template <int D>
void Simulation<D>::sync_platen_nodes() {
  platen_surface_version_ = contact_->surface_version();
  if (m.platens.count == 0) return;
  const int ns = contact_->surface_nodes();
  m.bnode = contact_->surface_node_list();  // its first ns entries
  m.nb = ns;
  // A node's platen area grows when faces around it become surfaces (from 0 for a node of a crack
  // face just handed over). Its stored energy may not grow with it: a node in a platen's penalty
  // zone keeps its normal energy (the allowance g0 takes the rest: a crack face node can be well
  // below the plate when it becomes a surface, having slid there along failed interfaces, 0.2 mm
  // in the 2D impact at 15 m/s, h = 8 mm), and its shear spring keeps its force (the energy that
  // loses is dissipated), as contact_pair does for contacts.
  auto bnode = m.bnode;
  auto barea = m.barea;
  auto narea = contact_->surface().narea;
  auto x = m.x;
  auto fs = m.platen_fs;
  auto g0 = m.platen_g0;
  auto acc = m.platen_acc;
  const auto ps = m.platens;
  const double tn = t;
  Kokkos::parallel_for(
      "fdem::platen_nodes", Kokkos::RangePolicy<ExecSpace>(0, ns), KOKKOS_LAMBDA(const int b) {
        const int i = bnode(b);
        const double A0 = barea(i), A1 = 2.0 * narea(i);  // contact area: half the node's share
        if (!(A1 > A0)) return;
        for (int p = 0; p < ps.count; ++p) {
          const PlatenDev& P = ps.p[p];
          double g = 0, f2 = 0;
          for (int k = 0; k < D; ++k) {
            g += (x(i, k) - (P.p0[k] + P.vel[k] * tn)) * P.n[k];
            f2 += fs(p, i, k) * fs(p, i, k);
          }
          const double ge = g - g0(p, i);
          if (ge < 0.0) g0(p, i) = g - ge * kmath::sqrt(A0 / A1);
          if (f2 > 0.0) Kokkos::atomic_add(&acc(p, 4), 0.5 * f2 * (1.0 / A0 - 1.0 / A1) / P.ks);
        }
        barea(i) = A1;
      });
}

template <int D>
NodeSums Simulation<D>::update_nodes_now(bool sample) {
  prm_.t = t;
  prm_.dt = dt;
  prm_.dtv = dtv_next_ > 0 ? dtv_next_ : dt;
  dtv_next_ = 0;
  const bool damp = !skips.damping || prm_.alpha != 0.0 || prm_.cmass != 0.0;
  if (sample) return damp ? update_nodes<D, true, true>(m, prm_) : update_nodes<D, true, false>(m, prm_);
  return damp ? update_nodes<D, false, true>(m, prm_) : update_nodes<D, false, false>(m, prm_);
}

template <int D>
void Simulation<D>::check_finite() {
  auto x = m.x;
  auto v = m.v;
  int bad = m.nn;
  Kokkos::parallel_reduce(
      "fdem::check_finite", Kokkos::RangePolicy<ExecSpace>(0, m.nn),
      KOKKOS_LAMBDA(const int i, int& first) {
        bool ok = true;
        for (int k = 0; k < D; ++k) {  // x - x is 0 for finite x, NaN for NaN and inf
          const double dx = x(i, k) - x(i, k), dv = v(i, k) - v(i, k);
          ok = ok && dx == 0.0 && dv == 0.0;
        }
        if (!ok && i < first) first = i;
      },
      Kokkos::Min<int>(bad));
  if (bad < m.nn) {
    auto X_h = Kokkos::create_mirror_view(m.X);
    Kokkos::deep_copy(X_h, m.X);
    std::ostringstream os;
    os << "state became non-finite at step " << step_count << ", time " << t << " s: node " << bad
       << " at (";
    for (int k = 0; k < D; ++k) os << (k ? ", " : "") << X_h(bad, k);
    os << ") (reference position). The time step " << dt << " s may be above the stable limit "
       << stable.critical << " s.";
    throw NumericalError(os.str());
  }
}

// Signed measure (2D: twice the area, 3D: six times the volume) of the simplex with edge vectors a.
template <int D>
KOKKOS_INLINE_FUNCTION double simplex_orientation(const double (&a)[D][D]) {
  if constexpr (D == 2) {
    return a[0][0] * a[1][1] - a[0][1] * a[1][0];
  } else {
    return a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
           a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
  }
}

template <int D>
long Simulation<D>::check_inverted(std::string* where) {
  auto x = m.x;
  auto X = m.X;
  auto elem = m.elem;
  const int ne = m.ne;
  auto inverted = KOKKOS_LAMBDA(const int e) {
    double a[D][D], b[D][D];
    for (int q = 0; q < D; ++q)
      for (int k = 0; k < D; ++k) {
        a[q][k] = x(elem(e, q + 1), k) - x(elem(e, 0), k);
        b[q][k] = X(elem(e, q + 1), k) - X(elem(e, 0), k);
      }
    return !(simplex_orientation<D>(a) * simplex_orientation<D>(b) > 0.0);
  };
  int count = 0, first = ne;
  Kokkos::parallel_reduce(
      "fdem::check_inverted", Kokkos::RangePolicy<ExecSpace>(0, ne),
      KOKKOS_LAMBDA(const int e, int& n) { n += inverted(e) ? 1 : 0; }, count);
  if (count > 0)
    Kokkos::parallel_reduce(
        "fdem::check_inverted_first", Kokkos::RangePolicy<ExecSpace>(0, ne),
        KOKKOS_LAMBDA(const int e, int& f) {
          if (inverted(e) && e < f) f = e;
        },
        Kokkos::Min<int>(first));
  if (count > 0 && where) {
    auto X_h = Kokkos::create_mirror_view(m.X);
    auto x_h = Kokkos::create_mirror_view(m.x);
    auto el_h = Kokkos::create_mirror_view(m.elem);
    Kokkos::deep_copy(X_h, m.X);
    Kokkos::deep_copy(x_h, m.x);
    Kokkos::deep_copy(el_h, m.elem);
    double c0[3] = {0, 0, 0}, c1[3] = {0, 0, 0};
    for (int a = 0; a <= D; ++a)
      for (int k = 0; k < D; ++k) {
        c0[k] += X_h(el_h(first, a), k) / (D + 1);
        c1[k] += x_h(el_h(first, a), k) / (D + 1);
      }
    std::ostringstream os;
    os << count << " element(s) turned inside out at step " << step_count << ", time " << t
       << " s; the first, element " << first << ", has its centroid at (";
    for (int k = 0; k < D; ++k) os << (k ? ", " : "") << c1[k];
    os << ") (reference (";
    for (int k = 0; k < D; ++k) os << (k ? ", " : "") << c0[k];
    os << "))";
    *where = os.str();
  }
  return count;
}

template <int D>
void Simulation<D>::check_stability() {
  check_finite();
  if (!warned_inverted_) {  // reported once per run (St Venant-Kirchhoff elements can be crushed
                            // inside out by violent compression; the run goes on)
    std::string where;
    if (check_inverted(&where) > 0) {
      std::fprintf(stderr, "fdem: warning: %s. An inverted element usually means a load or an impact too "
                   "violent for the mesh, or an unstable step.\n", where.c_str());
      warned_inverted_ = true;
    }
  }
  const Energies& e = energies_;
  if (!std::isfinite(e.kinetic) || !std::isfinite(e.strain)) {
    std::ostringstream os;
    os << "energy became non-finite at step " << step_count << ", time " << t << " s";
    throw NumericalError(os.str());
  }
  if (step_count > 10 && e.balance_error > 0.5 * e.scale) {
    std::ostringstream os;
    os << "energy balance blew up at step " << step_count << ", time " << t
       << " s: the energy in the system exceeds the work done on it by " << e.balance_error
       << " J (" << 100 * e.balance_error / e.scale << " % of " << e.scale << " J). The time step "
       << dt << " s is " << dt / stable.critical << " times the estimated critical step "
       << stable.critical << " s.";
    throw NumericalError(os.str());
  }
}

template <int D>
std::array<double, 3> Simulation<D>::platen_force(int p) const {
  Kokkos::deep_copy(platen_acc_host_, m.platen_acc);
  return {platen_acc_host_(p, 0), platen_acc_host_(p, 1), platen_acc_host_(p, 2)};
}

template <int D>
double Simulation<D>::platen_displacement(int p, double at) const {
  const auto& P = m.platens.p[p];
  return std::sqrt(P.vel[0] * P.vel[0] + P.vel[1] * P.vel[1] + P.vel[2] * P.vel[2]) * at;
}

template <int D>
void Simulation<D>::download(std::vector<double>& x, std::vector<double>& u, std::vector<double>& v,
                             std::vector<double>& stress, std::vector<double>& damage) {
  auto x_h = Kokkos::create_mirror_view(m.x);
  auto X_h = Kokkos::create_mirror_view(m.X);
  auto v_h = Kokkos::create_mirror_view(m.v);
  Kokkos::deep_copy(x_h, m.x);
  Kokkos::deep_copy(X_h, m.X);
  Kokkos::deep_copy(v_h, m.v);
  x.resize(static_cast<size_t>(m.nn) * D);
  u.resize(x.size());
  v.resize(x.size());
  for (int i = 0; i < m.nn; ++i)
    for (int k = 0; k < D; ++k) {
      x[static_cast<size_t>(i) * D + k] = x_h(i, k);
      u[static_cast<size_t>(i) * D + k] = x_h(i, k) - X_h(i, k);
      v[static_cast<size_t>(i) * D + k] = v_h(i, k);
    }
  Kokkos::View<double* [6]> s("fdem::stress", m.ne);
  element_stress<D>(m, s);
  auto s_h = Kokkos::create_mirror_view(s);
  Kokkos::deep_copy(s_h, s);
  stress.resize(static_cast<size_t>(m.ne) * 6);
  for (int e = 0; e < m.ne; ++e)
    for (int c = 0; c < 6; ++c) stress[static_cast<size_t>(e) * 6 + c] = s_h(e, c);
  Kokkos::View<double*> d("fdem::damage", m.ni);
  interface_damage<D>(m, d);
  auto d_h = Kokkos::create_mirror_view(d);
  Kokkos::deep_copy(d_h, d);
  damage.assign(d_h.data(), d_h.data() + m.ni);
}

std::vector<double> energies_to_vector(const Energies& e) {
  return {e.time, static_cast<double>(e.step), e.kinetic, e.strain, e.interface_elastic,
          e.contact_elastic, e.fracture, e.damping, e.friction, e.work_external, e.balance_error,
          e.scale, static_cast<double>(e.damaged), static_cast<double>(e.failed)};
}
Energies energies_from_vector(const std::vector<double>& v) {
  Energies e;
  e.time = v[0];
  e.step = static_cast<long>(v[1]);
  e.kinetic = v[2];
  e.strain = v[3];
  e.interface_elastic = v[4];
  e.contact_elastic = v[5];
  e.fracture = v[6];
  e.damping = v[7];
  e.friction = v[8];
  e.work_external = v[9];
  e.balance_error = v[10];
  e.scale = v[11];
  e.damaged = static_cast<long>(v[12]);
  e.failed = static_cast<long>(v[13]);
  return e;
}

template <int D>
void Simulation<D>::save_state(StateArrays& s) const {
  s.put("simulation/time", t);
  s.put("simulation/dt", dt);
  s.put_int("simulation/contact_step_pending", stable.contact_pending);
  s.put_int("simulation/dt_changed_at", dt_changed_at_);
  s.put("simulation/dt_before_change", dt_before_change_);
  s.put_int("simulation/step", step_count);
  s.put("simulation/work_damping", work_damping_);
  s.put("simulation/work_bc", work_bc_);
  s.put("simulation/energy_reference", reference_);
  s.put_int("simulation/have_reference", have_reference_);
  s.f64["simulation/energies"] = energies_to_vector(energies_);
  s.f64["simulation/damping"] = {prm_.alpha, prm_.cmass};
  s.f64["model/cohesive"] = {m.coh.kn, m.coh.ks, m.coh.ft, m.coh.c, m.coh.tanphi, m.coh.Gnc, m.coh.Gsc, m.coh.eta};
  s.f64["simulation/strength_reduction"] = {srf_, srf_hist_, m.coh.rescale};
  save_view(s, "model/x", m.x);
  save_view(s, "model/v", m.v);
  save_view(s, "model/f", m.f);
  save_view(s, "model/ihist", m.ihist);
  save_view(s, "model/icontact", m.icontact);
  if (m.icontact_pending.data()) save_view(s, "model/icontact_pending", m.icontact_pending);
  save_view(s, "model/platen_fs", m.platen_fs);
  save_view(s, "model/platen_g0", m.platen_g0);
  if (m.barea.extent(0) > 0) save_view(s, "model/platen_area", m.barea);
  save_view(s, "model/platen_acc", m.platen_acc);
  if (contact_) contact_->save_state(s);
}

template <int D>
void Simulation<D>::load_state(const StateArrays& s) {
  const double saved_dt = s.get("simulation/dt");
  // The step of this case at the checkpoint: before or after contact's stable step applied
  // (checkpoints written before that was lazy have no flag: the contact step from the start).
  const bool pending = s.has("simulation/contact_step_pending") && s.get_int("simulation/contact_step_pending") != 0;
  if (stable.contact_pending && !pending) {
    take_contact_step();
    if (saved_dt != dt)
      throw InputError("checkpoint '" + s.file + "': time step " + std::to_string(saved_dt) +
                       " s differs from this case's " + std::to_string(dt) + " s (contact on)");
  } else if (saved_dt != dt || pending != stable.contact_pending) {
    throw InputError("checkpoint '" + s.file + "': time step " + std::to_string(saved_dt) +
                     " s differs from this case's " + std::to_string(dt) + " s");
  }
  if (s.has("simulation/dt_changed_at")) {
    dt_changed_at_ = static_cast<long>(s.get_int("simulation/dt_changed_at"));
    dt_before_change_ = s.get("simulation/dt_before_change");
  }
  t = s.get("simulation/time");
  step_count = static_cast<long>(s.get_int("simulation/step"));
  work_damping_ = s.get("simulation/work_damping");
  work_bc_ = s.get("simulation/work_bc");
  reference_ = s.get("simulation/energy_reference");
  have_reference_ = s.get_int("simulation/have_reference") != 0;
  energies_ = energies_from_vector(s.array("simulation/energies", kEnergyFieldCount));
  const auto& damp = s.array("simulation/damping", 2);
  prm_.alpha = damp[0];
  prm_.cmass = damp[1];
  const auto& ch = s.array("model/cohesive", 8);
  m.coh = CohesiveParams{ch[0], ch[1], ch[2], ch[3], ch[4], ch[5], ch[6], ch[7]};
  if (s.has("simulation/strength_reduction")) {  // older checkpoints: no reduction applied yet
    const auto& sr = s.array("simulation/strength_reduction", 3);
    srf_ = sr[0];
    srf_hist_ = sr[1];
    m.coh.rescale = sr[2];
  }
  load_view(s, "model/x", m.x);
  load_view(s, "model/v", m.v);
  load_view(s, "model/f", m.f);
  load_view(s, "model/ihist", m.ihist);
  load_view(s, "model/icontact", m.icontact);
  if (m.icontact_pending.data()) load_view(s, "model/icontact_pending", m.icontact_pending);
  load_view(s, "model/platen_fs", m.platen_fs);
  load_view(s, "model/platen_g0", m.platen_g0);
  if (m.barea.extent(0) > 0) load_view(s, "model/platen_area", m.barea);
  load_view(s, "model/platen_acc", m.platen_acc);
  if (contact_ && !s.has("contact/pair_count"))
    throw InputError("checkpoint '" + s.file + "' has no contact state but this case has contact");
  if (!contact_ && s.has("contact/pair_count"))
    throw InputError("checkpoint '" + s.file + "' has contact state but this case has no contact");
  if (contact_) {
    contact_->load_state(s, m);
    sync_platen_nodes();
    contact_->law.mu = mu0_ / srf_;
  }
}

template class Simulation<2>;
template class Simulation<3>;

}  // namespace fdem
