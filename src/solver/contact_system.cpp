#include "solver/contact_system.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <unordered_map>

#include "common/error.hpp"
#include "solver/state_io.hpp"
#include "kernels/step.hpp"

namespace fdem {

namespace {

// Union-find with path halving.
struct UnionFind {
  std::vector<int> p;
  explicit UnionFind(int n) : p(n) { std::iota(p.begin(), p.end(), 0); }
  int find(int a) {
    while (p[a] != a) {
      p[a] = p[p[a]];
      a = p[a];
    }
    return a;
  }
  void unite(int a, int b) {
    a = find(a);
    b = find(b);
    if (a != b) p[std::max(a, b)] = std::min(a, b);
  }
};

// Connected pieces of the mesh: elements joined by shared nodes or by interfaces.
int count_bodies(const HostMesh& mesh) {
  const int nn = mesh.num_nodes(), ne = mesh.num_elems(), ni = mesh.num_ifaces(), d = mesh.dim;
  UnionFind uf(nn);
  for (int e = 0; e < ne; ++e)
    for (int a = 1; a <= d; ++a)
      uf.unite(mesh.elems[static_cast<size_t>(e) * (d + 1)], mesh.elems[static_cast<size_t>(e) * (d + 1) + a]);
  for (int q = 0; q < ni; ++q)
    for (int k = 0; k < d; ++k)
      uf.unite(mesh.ifaces[static_cast<size_t>(q) * 2 * d + k], mesh.ifaces[static_cast<size_t>(q) * 2 * d + d + k]);
  std::vector<char> seen(nn, 0);
  int n = 0;
  for (int e = 0; e < ne; ++e) {
    const int r = uf.find(mesh.elems[static_cast<size_t>(e) * (d + 1)]);
    if (!seen[r]) {
      seen[r] = 1;
      ++n;
    }
  }
  return n;
}

struct KeyHash {
  size_t operator()(const std::array<int, 3>& k) const {
    uint64_t h = 1469598103934665603ull;
    for (int v : k) {
      h ^= static_cast<uint64_t>(static_cast<uint32_t>(v));
      h *= 1099511628211ull;
    }
    return static_cast<size_t>(h);
  }
};

// d = 2 or 3 (the dimension). The first d entries are sorted by compare-and-swap: std::sort here
// made g++ 12, as nvcc's host compiler, report a false -Warray-bounds in its insertion sort.
std::array<int, 3> sorted_key(const int* nodes, int d) {
  std::array<int, 3> k{nodes[0], nodes[1], d == 3 ? nodes[2] : -1};
  auto order = [&k](int a, int b) {
    if (k[b] < k[a]) std::swap(k[a], k[b]);
  };
  order(0, 1);
  if (d == 3) {
    order(1, 2);
    order(0, 1);
  }
  return k;
}

template <class V>
auto mirror(const V& v) {
  return Kokkos::create_mirror_view(v);
}

}  // namespace

bool contact_wanted(const Case& c, const HostMesh& mesh) {
  if (c.contact.enabled >= 0) return c.contact.enabled == 1;
  return mesh.num_ifaces() > 0 || count_bodies(mesh) > 1;
}

template <int D>
ContactSystem<D>::ContactSystem(const Case& c, const HostMesh& mesh, Model<D>& m,
                                const std::vector<double>& mass) {
  if (mesh.dim != D) throw InputError(c.file + ": contact: mesh dimension does not match");
  nn_ = mesh.num_nodes();
  ni_ = mesh.num_ifaces();
  const int ne = mesh.num_elems();
  const double thick = D == 2 ? c.thickness : 1.0;

  // ---- parameters (docs/case-format.md, "contact") ----
  const MeshQuality mq = mesh_quality(mesh);
  const double hmean = mq.mean_size;
  double kn = c.contact.kn, ks = c.contact.ks, mu = c.contact.friction;
  double ks_ratio;
  if (c.fracture_material >= 0) {
    const auto& im = c.interface_materials[c.fracture_material];
    if (!(kn > 0)) kn = im.kn;
    ks_ratio = im.ks / im.kn;
    if (mu < 0) mu = std::tan(im.phi);
  } else {
    double emax = 0, nu = 0.25;
    for (const auto& bm : c.materials)
      if (bm.E > emax) {
        emax = bm.E;
        nu = bm.nu;
      }
    if (!(kn > 0)) kn = 10 * emax / hmean;
    ks_ratio = 1.0 / (2 * (1 + nu));
    if (mu < 0) mu = 0.0;
  }
  if (!(ks > 0)) ks = kn * ks_ratio;
  law.kn = kn;
  law.ks = ks;
  law.mu = mu;
  law.coh = c.contact.cohesion;
  // A node deeper than a quarter of the thinnest element behind a face is not in contact with it
  // (it would be nearer the face's back side); coplanar faces are within 30 degrees.
  law.dpen = 0.25 * (mq.min_size > 0 ? mq.min_size : hmean);
  law.tol = 0.01;
  law.cos_same = std::cos(30.0 * M_PI / 180.0);
  skin = c.contact.skin > 0 ? c.contact.skin : 0.1 * hmean;
  radius = law.dpen + skin;

  // ---- faces: outer boundary (owner found by their node set), then both faces of each interface
  const std::vector<int> bf = boundary_faces(mesh);
  const int nbf = static_cast<int>(bf.size()) / D;
  nf_ = nbf + 2 * ni_;
  std::vector<int> fnode(static_cast<size_t>(nf_) * D), fowner(nf_, -1), fiface(nf_, -1);
  std::copy(bf.begin(), bf.end(), fnode.begin());
  {
    std::unordered_map<std::array<int, 3>, int, KeyHash> key_to_face;
    key_to_face.reserve(static_cast<size_t>(nbf) * 2);
    for (int f = 0; f < nbf; ++f) key_to_face[sorted_key(&bf[static_cast<size_t>(f) * D], D)] = f;
    const int npe = D + 1;
    for (int e = 0; e < ne && !key_to_face.empty(); ++e)
      for (int skip = 0; skip < npe; ++skip) {
        int nodes[3] = {-1, -1, -1}, c2 = 0;
        for (int a = 0; a < npe; ++a)
          if (a != skip) nodes[c2++] = mesh.elems[static_cast<size_t>(e) * npe + a];
        auto it = key_to_face.find(sorted_key(nodes, D));
        if (it != key_to_face.end()) fowner[it->second] = e;
      }
  }
  // interface faces: A side in its stored order (normal from A to B: outward of A); B side
  // reversed (outward of B)
  std::unordered_map<std::array<int, 3>, int, KeyHash> elem_of_face;
  // the owners given with the interfaces, if every one of them holds its face's nodes
  auto holds = [&](int e, const int* nodes) {
    if (e < 0 || e >= ne) return false;
    for (int k = 0; k < D; ++k) {
      bool found = false;
      for (int a = 0; a <= D; ++a) found = found || mesh.elems[static_cast<size_t>(e) * (D + 1) + a] == nodes[k];
      if (!found) return false;
    }
    return true;
  };
  bool have_owner = static_cast<int>(mesh.iface_elems.size()) == 2 * ni_;
  for (int q = 0; q < ni_ && have_owner; ++q) {
    const int* in = &mesh.ifaces[static_cast<size_t>(q) * 2 * D];
    have_owner = holds(mesh.iface_elems[2 * static_cast<size_t>(q)], in) &&
                 holds(mesh.iface_elems[2 * static_cast<size_t>(q) + 1], in + D);
  }
  if (!have_owner && ni_ > 0) {
    const int npe = D + 1;
    for (int e = 0; e < ne; ++e)
      for (int skip = 0; skip < npe; ++skip) {
        int nodes[3] = {-1, -1, -1}, c2 = 0;
        for (int a = 0; a < npe; ++a)
          if (a != skip) nodes[c2++] = mesh.elems[static_cast<size_t>(e) * npe + a];
        elem_of_face[sorted_key(nodes, D)] = e;
      }
  }
  for (int q = 0; q < ni_; ++q) {
    const int* in = &mesh.ifaces[static_cast<size_t>(q) * 2 * D];
    const int fa = nbf + 2 * q, fb = fa + 1;
    for (int k = 0; k < D; ++k) fnode[static_cast<size_t>(fa) * D + k] = in[k];
    if (D == 2) {
      fnode[static_cast<size_t>(fb) * D + 0] = in[D + 1];
      fnode[static_cast<size_t>(fb) * D + 1] = in[D + 0];
    } else {
      fnode[static_cast<size_t>(fb) * D + 0] = in[D + 0];
      fnode[static_cast<size_t>(fb) * D + 1] = in[D + 2];
      fnode[static_cast<size_t>(fb) * D + 2] = in[D + 1];
    }
    fiface[fa] = fiface[fb] = q;
    if (have_owner) {
      fowner[fa] = mesh.iface_elems[2 * static_cast<size_t>(q)];
      fowner[fb] = mesh.iface_elems[2 * static_cast<size_t>(q) + 1];
    } else {
      auto ia = elem_of_face.find(sorted_key(in, D));
      auto ib = elem_of_face.find(sorted_key(in + D, D));
      if (ia == elem_of_face.end() || ib == elem_of_face.end())
        throw InputError(c.file + ": contact: interface " + std::to_string(q) + " has no element on a side");
      fowner[fa] = ia->second;
      fowner[fb] = ib->second;
    }
  }
  for (int f = 0; f < nf_; ++f)
    if (fowner[f] < 0) throw InputError(c.file + ": contact: face " + std::to_string(f) + " has no element");

  // reference measure share of each face node, node -> faces, stable step
  std::vector<double> share(nf_);
  std::vector<int> nfcount(nn_ + 1, 0);
  std::vector<double> area(nn_, 0.0);
  for (int f = 0; f < nf_; ++f) {
    double xf[D][D], n[D];
    for (int a = 0; a < D; ++a)
      for (int k = 0; k < D; ++k) xf[a][k] = mesh.X[static_cast<size_t>(fnode[static_cast<size_t>(f) * D + a]) * D + k];
    const double meas = face_normal<D>(xf, n) * thick;
    share[f] = meas / D;
    for (int a = 0; a < D; ++a) {
      const int i = fnode[static_cast<size_t>(f) * D + a];
      ++nfcount[i + 1];
      area[i] += share[f];
    }
  }
  for (int i = 0; i < nn_; ++i) nfcount[i + 1] += nfcount[i];
  std::vector<int> nface(nfcount[nn_]);
  {
    std::vector<int> cur(nfcount.begin(), nfcount.end() - 1);
    for (int f = 0; f < nf_; ++f)
      for (int a = 0; a < D; ++a) nface[cur[fnode[static_cast<size_t>(f) * D + a]]++] = f;
  }
  potential_area_ = area;
  // Stable step of the contact springs: omega^2 = 2 max(K_n, K_s) A_i / m_i with A_i the node's
  // share of every face it can ever be part of (about twice its contact area: room for two
  // contacts at full weight) and the factor 2 for the mass on the other side: a contact between
  // two copies of one vertex (a node at the corner of the other's face) acts on both nodes,
  // whose relative motion has omega^2 = K A (1 / m_s + 1 / m_v), as the interface springs'
  // estimate has. Without that factor, two such copies pressing into each other's faces made
  // the reduced compression case (safety factor 0.5) oscillate with a period of two steps and
  // blow up at 2.7 ms. The price: a 29 % smaller step where contact sets it (the 3D impact).
  stable_ = std::numeric_limits<double>::infinity();
  const double kmax = std::max(law.kn, law.ks);
  for (int i = 0; i < nn_; ++i)
    if (area[i] > 0 && mass[i] > 0) stable_ = std::min(stable_, 2.0 / std::sqrt(2.0 * kmax * area[i] / mass[i]));

  // ---- vertex groups (copies of one mesh vertex, joined through interface node pairs) ----
  std::vector<int> vgrp(nn_);
  std::vector<int> goff, gent, gcoff, gcopy;
  {
    UnionFind uf(nn_);
    for (int q = 0; q < ni_; ++q)
      for (int k = 0; k < D; ++k)
        uf.unite(mesh.ifaces[static_cast<size_t>(q) * 2 * D + k], mesh.ifaces[static_cast<size_t>(q) * 2 * D + D + k]);
    for (int i = 0; i < nn_; ++i) vgrp[i] = uf.find(i);
    // groups that have interface pairs: their entries (q * D + k) and their copies
    std::vector<int> gid(nn_, -1);
    std::vector<std::vector<int>> ent, cop;
    for (int q = 0; q < ni_; ++q)
      for (int k = 0; k < D; ++k) {
        const int r = vgrp[mesh.ifaces[static_cast<size_t>(q) * 2 * D + k]];
        if (gid[r] < 0) {
          gid[r] = static_cast<int>(ent.size());
          ent.emplace_back();
          cop.emplace_back();
        }
        ent[gid[r]].push_back(q * D + k);
      }
    for (int i = 0; i < nn_; ++i)
      if (gid[vgrp[i]] >= 0) cop[gid[vgrp[i]]].push_back(i);
    ngroups_ = static_cast<int>(ent.size());
    goff.push_back(0);
    gcoff.push_back(0);
    for (int g = 0; g < ngroups_; ++g) {
      gent.insert(gent.end(), ent[g].begin(), ent[g].end());
      gcopy.insert(gcopy.end(), cop[g].begin(), cop[g].end());
      goff.push_back(static_cast<int>(gent.size()));
      gcoff.push_back(static_cast<int>(gcopy.size()));
    }
  }
  bodies_ = count_bodies(mesh);
  may_meet_ = bodies_ > 1;

  // ---- upload ----
  auto upload_int = [](const std::vector<int>& v, const char* name) {
    Kokkos::View<int*> d(std::string(name), v.size());
    auto h = mirror(d);
    for (size_t i = 0; i < v.size(); ++i) h(i) = v[i];
    Kokkos::deep_copy(d, h);
    return d;
  };
  surf_.fnode = Kokkos::View<int* [D]>("fdem::contact::fnode", nf_);
  {
    auto h = mirror(surf_.fnode);
    for (int f = 0; f < nf_; ++f)
      for (int a = 0; a < D; ++a) h(f, a) = fnode[static_cast<size_t>(f) * D + a];
    Kokkos::deep_copy(surf_.fnode, h);
  }
  surf_.fslot = Kokkos::View<int*>("fdem::contact::fslot", nf_);
  surf_.fshare = Kokkos::View<double*>("fdem::contact::fshare", nf_);
  {
    auto h = mirror(surf_.fshare);
    for (int f = 0; f < nf_; ++f) h(f) = share[f];
    Kokkos::deep_copy(surf_.fshare, h);
  }
  surf_.factive = Kokkos::View<int*>("fdem::contact::factive", nf_);
  surf_.nfoff = upload_int(nfcount, "fdem::contact::nfoff");
  surf_.nface = upload_int(nface, "fdem::contact::nface");
  surf_.vgrp = upload_int(vgrp, "fdem::contact::vgrp");
  {
    std::vector<int> id(nn_);
    std::iota(id.begin(), id.end(), 0);
    surf_.clus = upload_int(id, "fdem::contact::clus");
  }
  surf_.fiface = upload_int(fiface, "fdem::contact::fiface");
  surf_.nb = nbf;
  surf_.narea = Kokkos::View<double*>("fdem::contact::narea", nn_);
  goff_ = upload_int(goff, "fdem::contact::goff");
  gent_ = upload_int(gent, "fdem::contact::gent");
  gcopy_off_ = upload_int(gcoff, "fdem::contact::gcopy_off");
  gcopy_ = upload_int(gcopy, "fdem::contact::gcopy");
  filter_.use = true;
  filter_.elem = m.elem;
  filter_.fowner = upload_int(fowner, "fdem::contact::fowner");
  surf_.elem = m.elem;
  surf_.fowner = filter_.fowner;
  surf_.efree = Kokkos::View<int*>("fdem::contact::efree", ne);
  ne_ = ne;
  filter_.fiface = surf_.fiface;
  filter_.nb = nbf;
  filter_.vgrp = surf_.vgrp;
  filter_.clus = surf_.clus;

  afaces_ = Kokkos::View<int*>("fdem::contact::afaces", nf_);
  slaves_ = Kokkos::View<int*>("fdem::contact::nodes", nn_);
  mark_ = Kokkos::View<int*>("fdem::contact::mark", nn_);
  xb_ = Kokkos::View<double* [D]>("fdem::contact::xb", nn_);
  cell_cap_ = std::max<long>(64, 4L * nf_);
  grid_.count = Kokkos::View<int*>("fdem::contact::cell_count", cell_cap_);
  grid_.offset = Kokkos::View<int*>("fdem::contact::cell_offset", cell_cap_ + 1);
  grid_.faces = Kokkos::View<int*>("fdem::contact::cell_faces", nf_);
  for (PairList<D>* p : {&cur_, &next_}) p->off = Kokkos::View<int*>("fdem::contact::pair_off", nn_ + 1);

  m.contact_handover = true;
  m.handover_slip = law.dpen;
  m.icontact_pending = Kokkos::View<int>("fdem::icontact_pending");
  // Failed, parted interfaces are handed over every 25 steps (a failed interface keeps its
  // compression penalty until then): each handover refreshes the surfaces and rebuilds the
  // candidate lists, which in the 3D impact at 20 m/s (h = 8 mm) happened 356 times in 4625 steps
  // when checked every step, a quarter of the run time (78 builds and 35 % less time at 50 steps;
  // fragments, energy balance and handed-over count alike). On GPUs the check also costs a copy
  // of the pending flag to the host.
  check_every_ = 25;
  refresh_surfaces(m);
}

template <int D>
void ContactSystem<D>::refresh_surfaces(const Model<D>& m) {
  // active faces: outer boundary, and faces of handed-over interfaces
  auto factive = surf_.factive;
  auto fiface = surf_.fiface;
  auto icontact = m.icontact;
  Kokkos::parallel_for(
      "fdem::contact::factive", Kokkos::RangePolicy<ExecSpace>(0, nf_), KOKKOS_LAMBDA(const int f) {
        const int q = fiface(f);
        factive(f) = q < 0 ? 1 : (icontact(q) ? 1 : 0);
      });
  // clusters: within each vertex group, copies joined by intact interface pairs share the
  // smallest node id
  if (ngroups_ > 0) {
    auto goff = goff_;
    auto gent = gent_;
    auto gcoff = gcopy_off_;
    auto gcopy = gcopy_;
    auto clus = surf_.clus;
    auto iface = m.iface;
    Kokkos::parallel_for(
        "fdem::contact::clusters", Kokkos::RangePolicy<ExecSpace>(0, ngroups_), KOKKOS_LAMBDA(const int g) {
          for (int c = gcoff(g); c < gcoff(g + 1); ++c) clus(gcopy(c)) = gcopy(c);
          bool changed = true;
          while (changed) {
            changed = false;
            for (int t = goff(g); t < goff(g + 1); ++t) {
              const int q = gent(t) / D, k = gent(t) % D;
              if (icontact(q)) continue;
              const int a = iface(q, k), b = iface(q, D + k);
              const int ca = clus(a), cb = clus(b);
              if (ca != cb) {
                const int lo = ca < cb ? ca : cb;
                clus(a) = lo;
                clus(b) = lo;
                changed = true;
              }
            }
          }
        });
  }
  // compact lists of active faces and of their nodes
  auto afaces = afaces_;
  int na = 0;
  Kokkos::parallel_scan(
      "fdem::contact::active_faces", Kokkos::RangePolicy<ExecSpace>(0, nf_),
      KOKKOS_LAMBDA(const int f, int& upd, const bool final) {
        if (factive(f)) {
          if (final) afaces(upd) = f;
          ++upd;
        }
      },
      na);
  na_ = na;
  if (static_cast<int>(surf_.fgeo.extent(0)) < na_)  // grows with the surfaces (with headroom)
    surf_.fgeo = Kokkos::View<double**>("fdem::contact::fgeo", std::min(nf_, 3 * na_ / 2 + 64), FaceGeo<D>::size);
  {
    auto fslot = surf_.fslot;
    Kokkos::parallel_for(
        "fdem::contact::face_slots", Kokkos::RangePolicy<ExecSpace>(0, na_),
        KOKKOS_LAMBDA(const int i) { fslot(afaces(i)) = i; });
  }
  auto mark = mark_;
  auto fnode = surf_.fnode;
  Kokkos::deep_copy(mark, 0);
  Kokkos::parallel_for(
      "fdem::contact::mark_nodes", Kokkos::RangePolicy<ExecSpace>(0, na_), KOKKOS_LAMBDA(const int i) {
        for (int a = 0; a < D; ++a) Kokkos::atomic_exchange(&mark(fnode(afaces(i), a)), 1);
      });
  // free elements: all D + 1 faces active
  auto efree = surf_.efree;
  auto fowner = surf_.fowner;
  Kokkos::deep_copy(efree, 0);
  Kokkos::parallel_for(
      "fdem::contact::free_count", Kokkos::RangePolicy<ExecSpace>(0, na_), KOKKOS_LAMBDA(const int i) {
        Kokkos::atomic_add(&efree(fowner(afaces(i))), 1);
      });
  int nfree = 0;
  Kokkos::parallel_reduce(
      "fdem::contact::free_flag", Kokkos::RangePolicy<ExecSpace>(0, ne_),
      KOKKOS_LAMBDA(const int e, int& cnt) {
        efree(e) = efree(e) == D + 1 ? 1 : 0;
        cnt += efree(e);
      },
      nfree);
  nfree_ = nfree;
  if (nfree_ > 0 && surf_.eplane.extent(0) == 0)
    surf_.eplane = Kokkos::View<double* [D + 1][D + 1]>("fdem::contact::eplane", ne_);
  // contact area of each node: half its share of its active faces
  auto narea = surf_.narea;
  auto fshare = surf_.fshare;
  // (per node over its faces in a fixed order: the same sums whatever the threads)
  auto nfoff = surf_.nfoff;
  auto nface = surf_.nface;
  Kokkos::parallel_for(
      "fdem::contact::node_area", Kokkos::RangePolicy<ExecSpace>(0, nn_), KOKKOS_LAMBDA(const int i) {
        double a = 0.0;
        for (int j = nfoff(i); j < nfoff(i + 1); ++j)
          if (factive(nface(j))) a += 0.5 * fshare(nface(j));
        narea(i) = a;
      });
  auto slaves = slaves_;
  int ns = 0;
  Kokkos::parallel_scan(
      "fdem::contact::surface_nodes", Kokkos::RangePolicy<ExecSpace>(0, nn_),
      KOKKOS_LAMBDA(const int i, int& upd, const bool final) {
        if (mark(i)) {
          if (final) slaves(upd) = i;
          ++upd;
        }
      },
      ns);
  ns_ = ns;
  need_build_ = true;
  ++surface_version_;
}

template <int D>
void ContactSystem<D>::check_failures(const Model<D>& m) {
  if (ni_ == 0) return;
  auto icontact = m.icontact;
  auto ihist = m.ihist;
  auto iface = m.iface;
  auto x = m.x;
  const double slip = m.handover_slip;
  int n = 0;
  Kokkos::parallel_reduce(
      "fdem::contact::handover", Kokkos::RangePolicy<ExecSpace>(0, ni_),
      KOKKOS_LAMBDA(const int q, int& cnt) {
        if (icontact(q)) return;
        bool all = true;
        for (int k = 0; k < D; ++k)
          all = all && cohesive_damage(load_point(ihist, q, k)) >= 1.0;
        if (!all) return;
        double xa[D][D], xb[D][D];
        for (int k = 0; k < D; ++k)
          for (int i = 0; i < D; ++i) {
            xa[k][i] = x(iface(q, k), i);
            xb[k][i] = x(iface(q, D + k), i);
          }
        CohesivePoint h[D];
        for (int k = 0; k < D; ++k) h[k] = load_point(ihist, q, k);
        if (interface_parted<D>(xa, xb, slip) || interface_apart<D>(xa, xb, h)) {
          icontact(q) = 1;
          ++cnt;
        }
      },
      n);
  Kokkos::deep_copy(m.icontact_pending, 0);
  if (n > 0) {
    handed_ += n;
    may_meet_ = true;
    refresh_surfaces(m);
  }
}

template <int D>
void ContactSystem<D>::build(const Model<D>& m) {
  SearchSet<D> S;
  S.x = m.x;
  S.points = slaves_;
  S.np = ns_;
  S.fnode = surf_.fnode;
  S.faces = afaces_;
  S.nf = na_;
  S.radius = radius;
  S.tol = law.tol;  // the distance test of face_within
  const ContactBox<D> box = search_bounds<D>(S);
  bool finite = std::isfinite(box.ext);
  for (int k = 0; k < D; ++k) finite = finite && std::isfinite(box.lo[k]) && std::isfinite(box.hi[k]);
  if (!finite) {  // a non-finite state: no contacts (the solver's stability check reports it)
    Kokkos::deep_copy(cur_.off, 0);
    cur_.size = 0;
    need_build_ = true;
    return;
  }
  grid_geometry<D>(grid_, box, radius, cell_cap_);
  grid_bin<D>(grid_, S);
  const int total = candidates_count<D>(grid_, S, filter_, next_.off, nn_);
  if (total > next_.capacity) {  // grow with headroom (the only allocation during a run)
    const int cap = static_cast<int>(std::min<long>(std::numeric_limits<int>::max(), 3L * total / 2 + 64));
    next_.face = Kokkos::View<int*>("fdem::contact::pair_face", cap);
    next_.fn = Kokkos::View<double*>("fdem::contact::pair_fn", cap);
    next_.ac = Kokkos::View<double*>("fdem::contact::pair_ac", cap);
    next_.g0 = Kokkos::View<double*>("fdem::contact::pair_g0", cap);
    next_.fs = Kokkos::View<double* [D]>("fdem::contact::pair_fs", cap);
    next_.capacity = cap;
  }
  if (total > static_cast<int>(scratch_.g.extent(0))) {
    const int cap = next_.capacity;
    scratch_.g = Kokkos::View<double*>("fdem::contact::scratch_g", cap);
    scratch_.phi = Kokkos::View<double*>("fdem::contact::scratch_phi", cap);
    scratch_.depth = Kokkos::View<double*>("fdem::contact::scratch_depth", cap);
    scratch_.w = Kokkos::View<double*>("fdem::contact::scratch_w", cap);
    scratch_.rel = Kokkos::View<double*>("fdem::contact::scratch_rel", cap);
    scratch_.n = Kokkos::View<double* [D]>("fdem::contact::scratch_n", cap);
  }
  candidates_fill<D>(grid_, S, filter_, next_.off, next_.face);
  next_.size = total;
  transfer_history<D>(cur_, next_, slaves_, ns_, filter_);
  std::swap(cur_, next_);
  auto x = m.x;
  auto xb = xb_;
  auto pts = slaves_;
  Kokkos::parallel_for(
      "fdem::contact::record", Kokkos::RangePolicy<ExecSpace>(0, ns_), KOKKOS_LAMBDA(const int i) {
        const int s = pts(i);
        for (int k = 0; k < D; ++k) xb(s, k) = x(s, k);
      });
  need_build_ = false;
  ++builds_;
}

template <int D>
void ContactSystem<D>::update(const Model<D>& m, double dt) {
  if (own_scatter_size_ != m.f.extent(0)) {
    own_scatter_ = Scatter(m.f);
    own_scatter_size_ = m.f.extent(0);
  }
  own_scatter_.reset();
  update(m, dt, own_scatter_);
  auto f = m.f;
  Kokkos::Experimental::contribute(f, own_scatter_);
}

template <int D>
void ContactSystem<D>::update(const Model<D>& m, double dt, Scatter& sf) {
  if (ni_ > 0 && ++since_check_ >= check_every_) {
    since_check_ = 0;
    int pending = 0;
    Kokkos::deep_copy(pending, m.icontact_pending);
    if (pending) check_failures(m);
  }
  if (!may_meet_ || ns_ == 0 || na_ == 0) {
    active_ = 0;
    return;
  }
  if (need_build_) build(m);
  face_geometry<D>(m.x, surf_, afaces_, na_);
  if (nfree_ > 0) element_planes<D>(m.x, surf_, ne_);
  // Frictionless contact skips the shear springs. On the first step without friction after steps
  // with it, the full kernel runs once more: it sets every stored shear force to zero (and counts
  // the spring energy of contacts that end), so that the skipped kernel's zero history is exact.
  const bool fric = law.mu != 0.0 || law.coh != 0.0;
  const bool full = !skip_frictionless || fric || friction_before_;
  friction_before_ = fric || !skip_frictionless;
  const ContactSums r = full ? contact_forces<D, true>(m, slaves_, ns_, cur_, scratch_, surf_, law, dt, xb_, sf)
                             : contact_forces<D, false>(m, slaves_, ns_, cur_, scratch_, surf_, law, dt, xb_, sf);
  dissipated_ += r.dissipated;
  active_ = static_cast<int>(r.active);
  // Verlet test for the next step: the lists stay valid while no surface node has moved more than
  // half the skin since the build; the displacement at the next step is bounded by this one plus
  // a step at (twice) the largest speed.
  need_build_ = std::sqrt(r.d2max) + 2.0 * std::sqrt(r.v2max) * dt > 0.5 * skin;
}

template <int D>
double ContactSystem<D>::elastic_energy() const {
  if (!may_meet_ || ns_ == 0 || cur_.size == 0) return 0.0;
  return contact_energy<D>(cur_, slaves_, ns_, law);
}

template <int D>
void ContactSystem<D>::save_state(StateArrays& s) const {
  const std::pair<int, int> used(0, cur_.size);
  s.put_int("contact/pair_count", cur_.size);
  save_view(s, "contact/pair_off", cur_.off);
  if (cur_.size > 0) {
    save_view(s, "contact/pair_face", Kokkos::subview(cur_.face, used));
    save_view(s, "contact/pair_fn", Kokkos::subview(cur_.fn, used));
    save_view(s, "contact/pair_ac", Kokkos::subview(cur_.ac, used));
    save_view(s, "contact/pair_g0", Kokkos::subview(cur_.g0, used));
    save_view(s, "contact/pair_fs", Kokkos::subview(cur_.fs, used, Kokkos::ALL));
  } else {
    s.i64["contact/pair_face"] = {};
    for (const char* n : {"contact/pair_fn", "contact/pair_ac", "contact/pair_g0", "contact/pair_fs"}) s.f64[n] = {};
  }
  save_view(s, "contact/xb", xb_);
  save_view(s, "contact/node_area", surf_.narea);
  s.put_int("contact/may_meet", may_meet_);
  s.put_int("contact/need_build", need_build_);
  s.put_int("contact/since_check", since_check_);
  s.put_int("contact/active", active_);
  s.put_int("contact/builds", builds_);
  s.put_int("contact/handed_over", handed_);
  s.put("contact/dissipated", dissipated_);
  // for people reading the file (not read back)
  s.put_int("contact/surface_nodes", ns_);
  s.put_int("contact/active_faces", na_);
}

template <int D>
void ContactSystem<D>::load_state(const StateArrays& s, const Model<D>& m) {
  refresh_surfaces(m);  // active faces, clusters, surface nodes from m.icontact
  const long long n = s.get_int("contact/pair_count");
  if (n < 0 || n > std::numeric_limits<int>::max())
    throw InputError("checkpoint '" + s.file + "': contact/pair_count out of range");
  const int size = static_cast<int>(n);
  load_view(s, "contact/pair_off", cur_.off);
  const int cap = std::max(size, 1);
  cur_.face = Kokkos::View<int*>("fdem::contact::pair_face", cap);
  cur_.fn = Kokkos::View<double*>("fdem::contact::pair_fn", cap);
  cur_.ac = Kokkos::View<double*>("fdem::contact::pair_ac", cap);
  cur_.g0 = Kokkos::View<double*>("fdem::contact::pair_g0", cap);
  cur_.fs = Kokkos::View<double* [D]>("fdem::contact::pair_fs", cap);
  cur_.capacity = cap;
  cur_.size = size;
  const std::pair<int, int> used(0, size);
  load_view(s, "contact/pair_face", Kokkos::subview(cur_.face, used));
  load_view(s, "contact/pair_fn", Kokkos::subview(cur_.fn, used));
  load_view(s, "contact/pair_ac", Kokkos::subview(cur_.ac, used));
  load_view(s, "contact/pair_g0", Kokkos::subview(cur_.g0, used));
  load_view(s, "contact/pair_fs", Kokkos::subview(cur_.fs, used, Kokkos::ALL));
  {  // the list must be one the search could have built: offsets rising to size, faces in range
    auto off = Kokkos::create_mirror_view(cur_.off);
    Kokkos::deep_copy(off, cur_.off);
    auto face = Kokkos::create_mirror_view(cur_.face);
    Kokkos::deep_copy(face, cur_.face);
    bool ok = off(0) == 0 && off(nn_) == size;
    for (int i = 0; i < nn_ && ok; ++i) ok = off(i) <= off(i + 1);
    for (int j = 0; j < size && ok; ++j) ok = face(j) >= 0 && face(j) < nf_;
    if (!ok) throw InputError("checkpoint '" + s.file + "': contact pair list is inconsistent");
  }
  scratch_.g = Kokkos::View<double*>("fdem::contact::scratch_g", cap);
  scratch_.phi = Kokkos::View<double*>("fdem::contact::scratch_phi", cap);
  scratch_.depth = Kokkos::View<double*>("fdem::contact::scratch_depth", cap);
  scratch_.w = Kokkos::View<double*>("fdem::contact::scratch_w", cap);
  scratch_.rel = Kokkos::View<double*>("fdem::contact::scratch_rel", cap);
  scratch_.n = Kokkos::View<double* [D]>("fdem::contact::scratch_n", cap);
  load_view(s, "contact/xb", xb_);
  load_view(s, "contact/node_area", surf_.narea);
  may_meet_ = s.get_int("contact/may_meet") != 0;
  need_build_ = s.get_int("contact/need_build") != 0;
  since_check_ = static_cast<int>(s.get_int("contact/since_check"));
  active_ = static_cast<int>(s.get_int("contact/active"));
  builds_ = s.get_int("contact/builds");
  handed_ = s.get_int("contact/handed_over");
  dissipated_ = s.get("contact/dissipated");
}

template class ContactSystem<2>;
template class ContactSystem<3>;

}  // namespace fdem
