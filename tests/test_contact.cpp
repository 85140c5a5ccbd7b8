// Contact between deformable bodies (docs/theory.md section 6b; src/solver/contact_system.hpp,
// kernels/contact.hpp): the broad phase against brute force, a block on an inclined plane, two
// blocks meeting head-on, a sphere bouncing off a wall (Hertz), a fully cracked block settling into
// a heap, and the stick-slip rule along a precut crack.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "solver/simulation.hpp"
#include "scenes.hpp"
#include "solver_fixtures.hpp"

namespace {

using namespace fdem;
using fdem_test::fail_all_interfaces;

const double kPi = std::acos(-1.0);

// ---- helpers ----

// Nodes of the elements of one region.
std::vector<int> region_nodes(const HostMesh& m, const std::string& region) {
  const int r = m.region_index(region);
  std::set<int> s;
  for (int e = 0; e < m.num_elems(); ++e)
    if (m.elem_region[e] == r)
      for (int a = 0; a <= m.dim; ++a) s.insert(m.elems[static_cast<size_t>(e) * (m.dim + 1) + a]);
  return {s.begin(), s.end()};
}

template <int D>
struct HostState {
  decltype(Kokkos::create_mirror_view(Kokkos::View<double* [D]>())) x, v;
  decltype(Kokkos::create_mirror_view(Kokkos::View<double*>())) mass;
  explicit HostState(const Simulation<D>& s)
      : x(Kokkos::create_mirror_view(s.m.x)), v(Kokkos::create_mirror_view(s.m.v)),
        mass(Kokkos::create_mirror_view(s.m.mass)) {
    Kokkos::deep_copy(mass, s.m.mass);
    pull(s);
  }
  void pull(const Simulation<D>& s) {
    Kokkos::deep_copy(x, s.m.x);
    Kokkos::deep_copy(v, s.m.v);
  }
  // centre of mass (pos = true) or mean velocity of a node list
  std::array<double, 3> mean(const std::vector<int>& nodes, bool pos) const {
    std::array<double, 3> r{0, 0, 0};
    double mt = 0;
    for (int i : nodes) {
      for (int k = 0; k < D; ++k) r[k] += mass(i) * (pos ? x(i, k) : v(i, k));
      mt += mass(i);
    }
    for (auto& c : r) c /= mt;
    return r;
  }
};

// ---- case keys ----

nlohmann::json contact_doc() {
  return nlohmann::json::parse(R"({
    "dimension": 2,
    "mesh": {"generator": "rectangle", "size": [0.1, 0.01], "cells": [10, 1]},
    "materials": {"rock": {"density": 2500, "E": 30e9, "nu": 0.2}},
    "regions": {"body": "rock"},
    "interface_materials": {"cif": {"kn": 6e13, "ks": 2.5e13, "ft": 3e6, "c": 9e6, "phi_deg": 30,
                                    "Gnc": 50, "Gsc": 1000}},
    "fracture": {"regions": ["body"], "interface_material": "cif"},
    "time": {"end_time": 1e-3}
  })");
}

std::string contact_error(const nlohmann::json& doc) {
  try {
    parse_case(doc, "c.json");
  } catch (const InputError& e) {
    return e.what();
  }
  return "<no error>";
}

TEST(ContactCase, DefaultsDerivedAndWrittenToTheResolvedCase) {
  const Case c = parse_case(contact_doc(), "c.json");
  EXPECT_EQ(c.contact.enabled, -1);
  EXPECT_EQ(c.contact.kn, 0.0);
  EXPECT_NEAR(c.contact.friction, std::tan(30 * kPi / 180), 1e-12);  // from the fracture material
  EXPECT_EQ(c.resolved["contact"]["enabled"], "auto");
  const Case r = parse_case(c.resolved, "c.json");  // the resolved case is a fixed point
  EXPECT_EQ(r.resolved, c.resolved);
  auto doc = contact_doc();
  doc["contact"] = {{"enabled", false}, {"kn", 1e12}, {"friction", 0.6}, {"cohesion", 1e5}, {"skin", 1e-4}};
  const Case d = parse_case(doc, "c.json");
  EXPECT_EQ(d.contact.enabled, 0);
  EXPECT_EQ(d.contact.kn, 1e12);
  EXPECT_EQ(d.contact.friction, 0.6);
  EXPECT_EQ(d.contact.cohesion, 1e5);
  EXPECT_EQ(d.contact.skin, 1e-4);
  doc.erase("fracture");
  doc.erase("interface_materials");
  doc.erase("contact");
  EXPECT_EQ(parse_case(doc, "c.json").contact.friction, 0.0);
}

TEST(ContactCase, BadValuesNameTheKey) {
  auto doc = contact_doc();
  doc["contact"] = {{"enabled", 1}};
  EXPECT_NE(contact_error(doc).find("contact.enabled"), std::string::npos) << contact_error(doc);
  doc["contact"] = {{"friction", -0.1}};
  EXPECT_NE(contact_error(doc).find("contact.friction"), std::string::npos) << contact_error(doc);
  doc["contact"] = {{"frction", 0.1}};
  EXPECT_NE(contact_error(doc).find("did you mean 'friction'"), std::string::npos) << contact_error(doc);
}

TEST(ContactCase, EnabledRule) {
  auto c = fdem_test::basic_case(2);
  HostMesh one = generate_crossed_rectangle(0, 0, 1, 1, 2, 2, "body");
  EXPECT_FALSE(contact_wanted(c, one));  // one intact body, no interfaces
  HostMesh two = merge_meshes(one, generate_crossed_rectangle(2, 0, 1, 1, 2, 2, "b"), "a", "b");
  EXPECT_TRUE(contact_wanted(c, two));
  HostMesh cracked = one;
  insert_interfaces(cracked, {true});
  EXPECT_TRUE(contact_wanted(c, cracked));
  c.contact.enabled = 0;
  EXPECT_FALSE(contact_wanted(c, two));
  c.contact.enabled = 1;
  EXPECT_TRUE(contact_wanted(c, one));
  Simulation<2> sim(c, one);  // on, but nothing can meet: no work
  ASSERT_NE(sim.contact(), nullptr);
  EXPECT_FALSE(sim.contact()->may_meet());
  for (int s = 0; s < 10; ++s) sim.step();
  EXPECT_EQ(sim.contact()->builds(), 0);
}

// ---- 1. broad phase against brute force ----

// Distance from p to a segment (2D) or triangle (3D).
double point_face_distance(const double* p, const double (*v)[3], int d) {
  auto sub = [](const double* a, const double* b, double* r) {
    for (int k = 0; k < 3; ++k) r[k] = a[k] - b[k];
  };
  auto dot = [](const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
  double q[3];  // closest point
  if (d == 2) {
    double t[3], w[3];
    sub(v[1], v[0], t);
    sub(p, v[0], w);
    const double s = std::clamp(dot(w, t) / dot(t, t), 0.0, 1.0);
    for (int k = 0; k < 3; ++k) q[k] = v[0][k] + s * t[k];
  } else {  // Ericson, Real-Time Collision Detection 5.1.5
    const double *a = v[0], *b = v[1], *c = v[2];
    double ab[3], ac[3], ap[3], bp[3], cp[3];
    sub(b, a, ab);
    sub(c, a, ac);
    sub(p, a, ap);
    const double d1 = dot(ab, ap), d2 = dot(ac, ap);
    sub(p, b, bp);
    const double d3 = dot(ab, bp), d4 = dot(ac, bp);
    sub(p, c, cp);
    const double d5 = dot(ab, cp), d6 = dot(ac, cp);
    const double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
    if (d1 <= 0 && d2 <= 0) {
      for (int k = 0; k < 3; ++k) q[k] = a[k];
    } else if (d3 >= 0 && d4 <= d3) {
      for (int k = 0; k < 3; ++k) q[k] = b[k];
    } else if (vc <= 0 && d1 >= 0 && d3 <= 0) {
      const double s = d1 / (d1 - d3);
      for (int k = 0; k < 3; ++k) q[k] = a[k] + s * ab[k];
    } else if (d6 >= 0 && d5 <= d6) {
      for (int k = 0; k < 3; ++k) q[k] = c[k];
    } else if (vb <= 0 && d2 >= 0 && d6 <= 0) {
      const double s = d2 / (d2 - d6);
      for (int k = 0; k < 3; ++k) q[k] = a[k] + s * ac[k];
    } else if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
      const double s = (d4 - d3) / ((d4 - d3) + (d5 - d6));
      for (int k = 0; k < 3; ++k) q[k] = b[k] + s * (c[k] - b[k]);
    } else {
      const double den = 1.0 / (va + vb + vc);
      const double s = vb * den, t = vc * den;
      for (int k = 0; k < 3; ++k) q[k] = a[k] + s * ab[k] + t * ac[k];
    }
  }
  double r[3];
  sub(p, q, r);
  return std::sqrt(dot(r, r));
}

struct BroadResult {
  long within = 0, missed = 0, aabb = 0, candidates = 0;
};

// np random points and nf random faces (size 0.002 .. 0.03) in the unit box; clustered: around
// five centres (spread 0.03), with 1 % of the faces and points far away (up to 50 units).
template <int D>
BroadResult broad_phase_run(bool clustered, unsigned seed, int np, int nf, double r, double tol = -1) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::normal_distribution<double> G(0.0, 0.03);
  double centres[5][3];
  for (auto& c : centres)
    for (double& x : c) x = U(rng);
  auto place = [&](double* p) {
    if (!clustered) {
      for (int k = 0; k < D; ++k) p[k] = U(rng);
    } else if (U(rng) < 0.01) {
      for (int k = 0; k < D; ++k) p[k] = 50.0 * U(rng);
    } else {
      const auto& c = centres[rng() % 5];
      for (int k = 0; k < D; ++k) p[k] = c[k] + G(rng);
    }
  };
  const int nn = np + nf * D;
  Kokkos::View<double* [D]> x("x", nn);
  Kokkos::View<int* [D]> fnode("fnode", nf);
  Kokkos::View<int*> points("points", np), faces("faces", nf);
  auto xh = Kokkos::create_mirror_view(x);
  auto fh = Kokkos::create_mirror_view(fnode);
  auto ph = Kokkos::create_mirror_view(points);
  auto ffh = Kokkos::create_mirror_view(faces);
  for (int i = 0; i < np; ++i) {
    double p[3] = {0, 0, 0};
    place(p);
    for (int k = 0; k < D; ++k) xh(i, k) = p[k];
    ph(i) = i;
  }
  for (int f = 0; f < nf; ++f) {
    double c[3] = {0, 0, 0};
    place(c);
    const double size = 0.002 + 0.028 * U(rng);
    for (int a = 0; a < D; ++a) {
      const int n = np + f * D + a;
      for (int k = 0; k < D; ++k) xh(n, k) = c[k] + size * (U(rng) - 0.5);
      fh(f, a) = n;
    }
    ffh(f) = f;
  }
  Kokkos::deep_copy(x, xh);
  Kokkos::deep_copy(fnode, fh);
  Kokkos::deep_copy(points, ph);
  Kokkos::deep_copy(faces, ffh);

  SearchSet<D> S;
  S.x = x;
  S.points = points;
  S.np = np;
  S.fnode.outer = fnode;  // (every face an outer one)
  S.fnode.nb = S.fnode.nf = nf;
  S.faces = faces;
  S.nf = nf;
  S.radius = r;
  S.tol = tol;
  PairFilter<D> F;  // geometry only
  CellGrid<D> g;
  const long cap = 4L * nf;
  g.count = Kokkos::View<int*>("count", cap);
  g.offset = Kokkos::View<int*>("offset", cap + 1);
  g.faces = Kokkos::View<int*>("cell_faces", nf);
  g.box = Kokkos::View<double* [2 * D]>("cell_box", nf);
  const ContactBox<D> box = search_bounds<D>(S);
  grid_geometry<D>(g, box, r, cap);
  grid_bin<D>(g, S);
  Kokkos::View<int*> off("off", nn + 1);
  const int total = candidates_count<D>(g, S, F, off, nn);
  Kokkos::View<int*> pf("pf", std::max(total, 1));
  candidates_fill<D>(g, S, F, off, pf);
  auto offh = Kokkos::create_mirror_view(off);
  auto pfh = Kokkos::create_mirror_view(pf);
  Kokkos::deep_copy(offh, off);
  Kokkos::deep_copy(pfh, pf);

  BroadResult res;
  res.candidates = total;
  for (int i = 0; i < np; ++i) {
    std::set<int> cand(&pfh(offh(i)), &pfh(0) + offh(i + 1));
    const double p[3] = {xh(i, 0), xh(i, 1), D == 3 ? xh(i, 2) : 0.0};
    for (int f = 0; f < nf; ++f) {
      double v[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
      double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
      for (int a = 0; a < D; ++a)
        for (int k = 0; k < D; ++k) {
          v[a][k] = xh(fh(f, a), k);
          lo[k] = std::min(lo[k], v[a][k]);
          hi[k] = std::max(hi[k], v[a][k]);
        }
      bool in_box = true;
      for (int k = 0; k < D; ++k) in_box = in_box && p[k] >= lo[k] - r && p[k] <= hi[k] + r;
      if (in_box) ++res.aabb;
      if (point_face_distance(p, v, D) <= r) {
        ++res.within;
        if (!cand.count(f)) ++res.missed;
      }
    }
  }
  return res;
}

template <int D>
void broad_phase_test() {
  for (bool clustered : {false, true}) {
    const double radius = D == 2 ? 0.01 : 0.04;
    const BroadResult r = broad_phase_run<D>(clustered, clustered ? 11u : 7u, 1500, 1500, radius);
    std::printf("%dD %s: %ld pairs within %g, %ld candidates\n", D, clustered ? "clustered" : "uniform",
                r.within, radius, r.candidates);
    EXPECT_EQ(r.missed, 0) << (clustered ? "clustered" : "uniform");
    EXPECT_GT(r.within, 100) << "the sets must be dense enough to have pairs within the distance";
    // the candidates are exactly the point / grown-box pairs (nothing lost in the grid)
    EXPECT_EQ(r.candidates, r.aabb);
    // with the distance test (face_within, tol = 0: no edge margin): exactly the pairs within
    // the distance (to round-off), fewer than the boxes give
    const BroadResult t = broad_phase_run<D>(clustered, clustered ? 11u : 7u, 1500, 1500, radius, 0.0);
    std::printf("%dD %s, distance test: %ld candidates (box test: %ld)\n", D, clustered ? "clustered" : "uniform",
                t.candidates, t.aabb);
    EXPECT_EQ(t.missed, 0);
    EXPECT_EQ(t.within, r.within);
    EXPECT_LE(t.candidates, t.within + t.within / 1000);
    EXPECT_LT(t.candidates, t.aabb);
    // with the contact's edge margin (tol = 0.01): nothing missed, between the two
    const BroadResult m = broad_phase_run<D>(clustered, clustered ? 11u : 7u, 1500, 1500, radius, 0.01);
    EXPECT_EQ(m.missed, 0);
    EXPECT_GE(m.candidates, t.candidates);
    EXPECT_LE(m.candidates, m.aabb);
  }
}

TEST(ContactBroadPhase, FindsEveryPairWithinTheSearchDistance2D) { broad_phase_test<2>(); }
TEST(ContactBroadPhase, FindsEveryPairWithinTheSearchDistance3D) { broad_phase_test<3>(); }

// ---- 6. stick-slip along a precut crack, prescribed motion ----

// Two square blocks joined by one interface (x = d), failed at the start. The left block is
// pressed into the right one by g0, then slid along the crack (y) up, down and up again, then
// pulled off; positions and velocities are prescribed and only the contact acts, its candidate
// lists rebuilt every 7 steps. The crack carries four node-on-face contacts (each crack node
// against the opposite face), each with the node's contact area A = (d + h) / 4 times the fade
// w = contact_fade(s) of its projection (two of them slide past the end of their face by u and
// back). The force on the left block must follow, to round-off, the rule of contact_pair per
// contact: normal force K_n A w ge with the depth ge = g0 kept while w falls and shrunk as w rises
// so that the normal energy does not grow (ge <- ge sqrt(w_old / w_new)); the shear force scaled
// with w while it falls and kept while it rises, then F_s <- clip(F_s - K_s A w du, mu F_n + c A w).
// The dissipation (the spring energy lost to the change of w: the shear spring's, and the normal
// spring's 0.5 K_n A (w_old - w) ge^2 while w falls; and while slipping the spring's energy before
// minus after plus the work of du against the mean of the old and new shear forces) and the
// stored energy must match the same rule.
TEST(ContactStickSlip, ShearForceFollowsTheCoulombRuleExactly) {
  const double d = 0.01, h = 0.01, kn = 1e12, ks = 4e11, mu = 0.5, coh = 1e4, g0 = 1e-7;
  auto c = fdem_test::basic_case(2, 1e9, 0.25, 2500);
  c.interface_materials = {fdem_test::strong_interface(kn, ks)};
  c.fracture_material = 0;
  c.contact.kn = kn;
  c.contact.ks = ks;
  c.contact.friction = mu;
  c.contact.cohesion = coh;
  Simulation<2> sim(c, fdem_test::block_bar(2, d, h));
  ContactSystem<2>* ct = sim.contact();
  ASSERT_NE(ct, nullptr);
  EXPECT_FALSE(ct->may_meet());  // one intact body: nothing to do
  fail_all_interfaces(sim);
  EXPECT_EQ(ct->handed_over(), 1);
  EXPECT_TRUE(ct->may_meet());
  const double tol = ct->law.tol, A = (d + h) / 4;

  auto X = Kokkos::create_mirror_view(sim.m.X);
  Kokkos::deep_copy(X, sim.m.X);
  auto x = Kokkos::create_mirror_view(sim.m.x);
  auto v = Kokkos::create_mirror_view(sim.m.v);
  auto f = Kokkos::create_mirror_view(sim.m.f);
  const double dt = 1e-6;
  int step = 0;
  // left block (nodes 0-3) at offset (gx, uy), moving at (vx, vy) over the last step
  auto drive = [&](double gx, double uy, double vx, double vy, double& Fx, double& Fy) {
    for (int i = 0; i < 8; ++i) {
      const bool left = i < 4;
      x(i, 0) = X(i, 0) + (left ? gx : 0.0);
      x(i, 1) = X(i, 1) + (left ? uy : 0.0);
      v(i, 0) = left ? vx : 0.0;
      v(i, 1) = left ? vy : 0.0;
    }
    Kokkos::deep_copy(sim.m.x, x);
    Kokkos::deep_copy(sim.m.v, v);
    Kokkos::deep_copy(sim.m.f, 0.0);
    if (++step % 7 == 0) ct->build(sim.m);  // history must survive rebuilds
    ct->update(sim.m, dt);
    Kokkos::deep_copy(f, sim.m.f);
    Fx = Fy = 0;
    double sx = 0, sy = 0;
    for (int i = 0; i < 8; ++i) {
      if (i < 4) {
        Fx += f(i, 0);
        Fy += f(i, 1);
      }
      sx += f(i, 0);
      sy += f(i, 1);
    }
    EXPECT_NEAR(sx, 0.0, 1e-9 * (std::fabs(Fx) + 1)) << "action = reaction";
    EXPECT_NEAR(sy, 0.0, 1e-9 * (std::fabs(Fy) + 1));
  };
  double Fx, Fy;
  const int n1 = 20;
  for (int s = 1; s <= n1; ++s) drive(g0 * s / n1, 0.0, g0 / n1 / dt, 0.0, Fx, Fy);
  EXPECT_NEAR(Fx, -4 * kn * A * g0, 1e-9 * kn * A * g0);
  EXPECT_EQ(ct->active_contacts(), 4);
  // slide: up to 5e-7, down to 0, up to 3e-7 (steps of 1e-8); slip starts near 1.5e-7
  std::vector<double> path;
  for (int s = 1; s <= 50; ++s) path.push_back(1e-8 * s);
  for (int s = 49; s >= 0; --s) path.push_back(1e-8 * s);
  for (int s = 1; s <= 30; ++s) path.push_back(1e-8 * s);
  // the rule per contact: two contacts in full (w = 1), two past their face's end (w = fade)
  double u = 0, Fs[2] = {0, 0}, ge[2] = {g0, g0}, diss = 0, worst = 0, worst_n = 0, peak = 0, w[2] = {1, 1};
  int slipping = 0, rises = 0;
  for (double un : path) {
    const double du = un - u;
    drive(g0, un, 0.0, du / dt, Fx, Fy);
    u = un;
    const double w_old = w[1];
    w[1] = contact_fade(-u / h, tol);
    double Fn_total = 0, Fs_total = 0;
    for (int k = 0; k < 2; ++k) {
      const double wo = k == 1 ? w_old : 1.0, Awo = A * wo, Aw = A * w[k];
      if (w[k] > wo) {  // the weight rises: the normal energy may not grow with it
        ge[k] *= std::sqrt(wo / w[k]);
        ++rises;
      } else {  // it falls at the same depth: the normal spring's energy is released
        diss += 2 * 0.5 * kn * (Awo - Aw) * ge[k] * ge[k];
      }
      // the shear spring shrinks with a falling weight and keeps its force with a rising one;
      // either way the energy it loses is released
      const double fs0 = w[k] < wo ? Fs[k] * w[k] / wo : Fs[k];
      diss += 2 * 0.5 * (Fs[k] * Fs[k] / Awo - fs0 * fs0 / Aw) / ks;
      const double Fn = kn * Aw * ge[k], lim = mu * Fn + coh * Aw;
      double trial = fs0 - ks * Aw * du;  // on the left block (opposes its motion)
      if (std::fabs(trial) > lim) {
        trial = trial > 0 ? lim : -lim;
        diss += 2 * (0.5 * (fs0 * fs0 - lim * lim) / (ks * Aw) - 0.5 * (fs0 + trial) * du);
        ++slipping;
      }
      Fs[k] = trial;
      Fn_total += 2 * Fn;
      Fs_total += 2 * Fs[k];
    }
    worst = std::max(worst, std::fabs(Fy - Fs_total));
    worst_n = std::max(worst_n, std::fabs(Fx + Fn_total));
    peak = std::max(peak, std::fabs(Fy));
  }
  const double lim_full = 4 * (mu * kn * A * g0 + coh * A);
  EXPECT_LT(worst, 1e-9 * lim_full) << "shear force against the stick-slip rule";
  EXPECT_LT(worst_n, 1e-9 * kn * A * g0) << "normal force";
  EXPECT_GT(peak, 0.99 * lim_full);
  EXPECT_GT(slipping, 40);
  EXPECT_GT(rises, 10);      // the end contacts came back onto their faces
  EXPECT_LT(w[1], 1.0);      // and slid past their face's end again
  EXPECT_LT(ge[1], g0);      // the depth they lost going out is not given back
  EXPECT_NEAR(ct->dissipated(), diss, 1e-9 * diss);
  double stored = 0;
  for (int k = 0; k < 2; ++k) {
    const double Aw = A * w[k];
    stored += 2 * (0.5 * kn * Aw * ge[k] * ge[k] + 0.5 * Fs[k] * Fs[k] / (ks * Aw));
  }
  EXPECT_NEAR(ct->elastic_energy(), stored, 1e-9 * stored);
  // pull apart: no tension, the shear springs' energy is released (dissipated)
  drive(-1e-7, u, -2e-7 / dt, 0.0, Fx, Fy);
  EXPECT_EQ(Fx, 0.0);
  EXPECT_EQ(Fy, 0.0);
  EXPECT_EQ(ct->active_contacts(), 0);
  double released = 0;
  for (int k = 0; k < 2; ++k) released += 2 * 0.5 * Fs[k] * Fs[k] / (ks * A * w[k]);
  EXPECT_NEAR(ct->dissipated(), diss + released, 1e-9 * diss);
  EXPECT_EQ(ct->elastic_energy(), 0.0);
}

// ---- 2. block on an inclined plane ----

// A square block on a fixed plane, gravity tilted by theta. Settled first (damping, high friction),
// then released without damping: below the friction angle it stays put; above it slides with
// acceleration g (sin theta - mu cos theta), within 2 %.
struct SlopeResult {
  double accel = 0, moved = 0, drop = 0;  // fitted acceleration, slid distance, normal motion
};

SlopeResult slope_run(double theta_deg, double mu, double t_run) {
  const double g = 9.81, th = theta_deg * kPi / 180;
  HostMesh plane = generate_crossed_rectangle(0, -0.005, 0.06, 0.005, 24, 2, "plane");
  HostMesh block = generate_crossed_rectangle(0.005, 0.0, 0.01, 0.01, 2, 2, "block");
  HostMesh mesh = merge_meshes(plane, block, "plane", "block");
  auto c = fdem_test::basic_case(2, 1e8, 0.25, 2500);
  c.region_material = {{"plane", 0}, {"block", 0}};
  VelocityBC fix;
  fix.set = "plane.all";
  fix.active = {true, true, false};
  c.velocity_bcs = {fix};
  c.gravity = {g * std::sin(th), -g * std::cos(th), 0};
  c.local_damping = 0.7;
  c.contact.friction = 10.0;  // settle without sliding
  Simulation<2> sim(c, mesh);
  ContactSystem<2>* ct = sim.contact();
  EXPECT_NE(ct, nullptr);
  EXPECT_EQ(ct->bodies(), 2);
  const auto nodes = region_nodes(mesh, "block");
  HostState<2> hs(sim);
  while (sim.t < 0.01) sim.step();
  hs.pull(sim);
  EXPECT_LT(std::fabs(hs.mean(nodes, false)[0]), 1e-4) << "not settled";
  sim.set_damping(0.0, 0.0);
  ct->law.mu = mu;
  const double t0 = sim.t, x0 = hs.mean(nodes, true)[0], y0 = hs.mean(nodes, true)[1];
  // least-squares fit of x(t) = a0 + a1 t + a2 t^2 / 2
  double S[3][3] = {}, b[3] = {};
  while (sim.t < t0 + t_run) {
    sim.step();
    if (sim.step_count % 50) continue;
    hs.pull(sim);
    const double t = sim.t - t0, y = hs.mean(nodes, true)[0] - x0;
    const double phi[3] = {1, t, 0.5 * t * t};
    for (int i = 0; i < 3; ++i) {
      b[i] += phi[i] * y;
      for (int j = 0; j < 3; ++j) S[i][j] += phi[i] * phi[j];
    }
  }
  hs.pull(sim);
  SlopeResult r;
  r.moved = hs.mean(nodes, true)[0] - x0;
  // solve the 3x3 normal equations (Cramer)
  auto det3 = [](double A[3][3]) {
    return A[0][0] * (A[1][1] * A[2][2] - A[1][2] * A[2][1]) - A[0][1] * (A[1][0] * A[2][2] - A[1][2] * A[2][0]) +
           A[0][2] * (A[1][0] * A[2][1] - A[1][1] * A[2][0]);
  };
  double A2[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) A2[i][j] = j == 2 ? b[i] : S[i][j];
  r.accel = det3(A2) / det3(S);
  r.drop = hs.mean(nodes, true)[1] - y0;
  return r;
}

TEST(ContactInclinedPlane, BlockStaysBelowTheFrictionAngle) {
  const SlopeResult r = slope_run(20.0, 0.5, 0.03);  // tan 20 deg = 0.36 < 0.5
  // sliding at even a tenth of g (sin - mu cos) of a looser contact would move it 0.4 mm
  EXPECT_LT(std::fabs(r.moved), 1e-6) << "moved " << r.moved << " m";
}

TEST(ContactInclinedPlane, BlockSlidesAboveTheFrictionAngleWithCoulombAcceleration) {
  const double theta = 30.0, mu = 0.3, g = 9.81;
  const double want = g * (std::sin(theta * kPi / 180) - mu * std::cos(theta * kPi / 180));
  const SlopeResult r = slope_run(theta, mu, 0.04);
  EXPECT_NEAR(r.accel / want, 1.0, 0.02) << "a = " << r.accel << ", want " << want;
  EXPECT_GT(r.moved, 0.001) << "slid less than half a plane element";
  EXPECT_LT(std::fabs(r.drop), 1e-6) << "left the plane or sank into it";
}

// ---- 3. two blocks meeting head-on ----

// Different sizes and speeds; no friction, no damping. Momentum conserved to round-off at every
// step; energy (kinetic + strain + contact) within 1 % through the impact; the blocks separate.
template <int D>
void head_on(const HostMesh& a, const HostMesh& b, double va, double vb) {
  HostMesh mesh = merge_meshes(a, b, "a", "b");
  auto c = fdem_test::basic_case(D, 1e7, 0.25, 1000);
  c.region_material = {{"a", 0}, {"b", 0}};
  c.initial_velocities = {InitialVelocity{"a", {va, 0, 0}}, InitialVelocity{"b", {vb, 0, 0}}};
  c.contact.friction = 0.0;
  // The penalty springs switch on and off within a step; the leap-frog's energy error at the
  // switch scales with (omega dt)^2: 1.5 % at the default safety factor 0.5, 0.1-0.5 % at 0.25.
  c.safety_factor = 0.25;
  Simulation<D> sim(c, mesh);
  ASSERT_NE(sim.contact(), nullptr);
  HostState<D> hs(sim);
  std::vector<int> all(mesh.num_nodes());
  for (int i = 0; i < mesh.num_nodes(); ++i) all[i] = i;
  const auto na = region_nodes(mesh, "a"), nb = region_nodes(mesh, "b");
  double mtot = 0;
  for (int i : all) mtot += hs.mass(i);
  auto momentum = [&]() {
    hs.pull(sim);
    std::array<double, 3> p = hs.mean(all, false);
    for (double& q : p) q *= mtot;
    return p;
  };
  const auto p0 = momentum();
  const double scale = mtot * std::max(std::fabs(va), std::fabs(vb));
  sim.step(true);
  const double e0 = sim.energies().kinetic + sim.energies().strain + sim.energies().contact_elastic;
  double worst_e = 0, worst_p = 0, peak_contact = 0;
  int contacts = 0;
  const double t_end = 3e-3;
  while (sim.t < t_end) {
    sim.step(true);
    const auto& e = sim.energies();
    const double et = e.kinetic + e.strain + e.contact_elastic;
    worst_e = std::max(worst_e, std::fabs(et - e0) / e0);
    peak_contact = std::max(peak_contact, e.contact_elastic);
    contacts = std::max(contacts, sim.contact()->active_contacts());
    const auto p = momentum();
    for (int k = 0; k < D; ++k) worst_p = std::max(worst_p, std::fabs(p[k] - p0[k]) / scale);
  }
  EXPECT_GT(contacts, 0) << "the blocks never met";
  EXPECT_GT(peak_contact, 0.0);
  EXPECT_LT(worst_p, 1e-12) << "momentum";
  EXPECT_LT(worst_e, 0.01) << "energy through the impact";
  // after the impact the blocks move apart
  hs.pull(sim);
  EXPECT_LT(hs.mean(na, false)[0], hs.mean(nb, false)[0] + 0.0) << "not separating";
  EXPECT_EQ(sim.contact()->active_contacts(), 0);
}

TEST(ContactHeadOn, MomentumAndEnergyConserved2D) {
  head_on<2>(generate_crossed_rectangle(0, 0, 0.02, 0.01, 8, 4, "a"),
             generate_crossed_rectangle(0.0202, 0, 0.01, 0.01, 4, 4, "b"), 0.6, -0.4);
}

TEST(ContactHeadOn, MomentumAndEnergyConserved3D) {
  head_on<3>(generate_box({0, 0, 0}, {0.02, 0.01, 0.01}, 4, 2, 2, "a"),
             generate_box({0.0202, 0, 0}, {0.01, 0.01, 0.01}, 2, 2, 2, "b"), 0.6, -0.4);
}

// ---- 4. sphere bouncing off a wall: Hertz contact time ----

// A sphere (R, E, nu) hits a stiff, heavy wall (100 E, 100 rho: a half-space that does not move)
// at speed V. Hertz: contact time t_c = 2.868 (m^2 / (R E*^2 V))^(1/5), 1/E* = (1 - nu^2)/E +
// (1 - nu^2)/E_wall.
TEST(ContactSphere, BouncesOffAWallAfterTheHertzContactTime) {
  const double R = 0.05, h = R / 6, E = 1e7, nu = 0.25, rho = 1000, V = 2.0, gap = 2e-4;
  HostMesh ball = generate_sphere({0, 0, R + gap}, R, h, "ball");
  HostMesh wall = generate_box({-0.03, -0.03, -0.02}, {0.06, 0.06, 0.02}, 3, 3, 1, "wall");
  HostMesh mesh = merge_meshes(wall, ball, "wall", "ball");
  auto c = fdem_test::basic_case(3, E, nu, rho);
  c.materials.push_back(BulkMaterial{"steel", 100 * rho, 100 * E, nu});
  c.region_material = {{"ball", 0}, {"wall", 1}};
  VelocityBC fix;
  fix.set = "wall.zmin";
  fix.active = {true, true, true};
  c.velocity_bcs = {fix};
  c.initial_velocities = {InitialVelocity{"ball", {0, 0, -V}}};
  c.contact.kn = 40 * E / h;  // stiff against the ball, not the wall
  c.contact.friction = 0.0;
  Simulation<3> sim(c, mesh);
  ContactSystem<3>* ct = sim.contact();
  ASSERT_NE(ct, nullptr);
  HostState<3> hs(sim);
  const auto nodes = region_nodes(mesh, "ball");
  double m = 0;
  for (int i : nodes) m += hs.mass(i);
  const double Es = 1.0 / ((1 - nu * nu) / E + (1 - nu * nu) / (100 * E));
  const double tc = 2.868 * std::pow(m * m / (R * Es * Es * V), 0.2);
  // contact time: from the first to the last step with a contact force
  double t_in = -1, t_out = -1;
  while (sim.t < 2 * tc) {
    const double t = sim.t;
    sim.step();
    if (ct->active_contacts() > 0) {
      if (t_in < 0) t_in = t;
      t_out = t + sim.dt;
    }
  }
  ASSERT_GT(t_in, 0) << "no contact";
  ASSERT_LT(t_out, 2 * tc - 10 * sim.dt) << "no rebound";
  const double dur = t_out - t_in;
  std::printf("sphere: contact time %.4g s, Hertz %.4g s (ratio %.3f)\n", dur, tc, dur / tc);
  EXPECT_NEAR(dur / tc, 1.0, 0.1) << "contact time " << dur << " s, Hertz " << tc << " s";
  hs.pull(sim);
  const double vout = hs.mean(nodes, false)[2];
  EXPECT_GT(vout, 0.8 * V) << "rebound speed";
  EXPECT_LT(vout, 1.0 * V);
}

// ---- 5. fully cracked block settles into a heap ----

// Every interface of a block failed at the start: every element is a free piece. Under gravity,
// with friction 0.5 and local damping, the pieces slide off each other's 45-degree faces and the
// block collapses onto a fixed floor. Every 2000 steps and at the end no node lies inside an
// element of another piece deeper than 1 % of the element size; at the end the heap has settled
// (kinetic energy below 0.1 % of the work of gravity) and the energy balance closes within 2 %.
template <int D>
double max_penetration(const Simulation<D>& sim, const HostMesh& mesh, const std::vector<int>& piece) {
  auto x = Kokkos::create_mirror_view(sim.m.x);
  Kokkos::deep_copy(x, sim.m.x);
  const int ne = mesh.num_elems(), nn = mesh.num_nodes();
  std::vector<int> node_piece(nn, -1);
  for (int e = 0; e < ne; ++e)
    for (int a = 0; a <= D; ++a) node_piece[mesh.elems[static_cast<size_t>(e) * (D + 1) + a]] = piece[e];
  double worst = 0;
  for (int e = 0; e < ne; ++e) {
    const int* en = &mesh.elems[static_cast<size_t>(e) * (D + 1)];
    // inward normals and offsets of the element's faces: inside <=> all distances > 0
    double nrm[D + 1][D], off[D + 1], lo[D], hi[D];
    for (int k = 0; k < D; ++k) {
      lo[k] = 1e300;
      hi[k] = -1e300;
      for (int a = 0; a <= D; ++a) {
        lo[k] = std::min(lo[k], x(en[a], k));
        hi[k] = std::max(hi[k], x(en[a], k));
      }
    }
    for (int skip = 0; skip <= D; ++skip) {
      int idx[D], c = 0;
      for (int a = 0; a <= D; ++a)
        if (a != skip) idx[c++] = en[a];
      double n[D];
      if constexpr (D == 2) {
        const double tx = x(idx[1], 0) - x(idx[0], 0), ty = x(idx[1], 1) - x(idx[0], 1);
        n[0] = -ty;
        n[1] = tx;
      } else {
        double a[3], b[3];
        for (int k = 0; k < 3; ++k) {
          a[k] = x(idx[1], k) - x(idx[0], k);
          b[k] = x(idx[2], k) - x(idx[0], k);
        }
        n[0] = a[1] * b[2] - a[2] * b[1];
        n[1] = a[2] * b[0] - a[0] * b[2];
        n[2] = a[0] * b[1] - a[1] * b[0];
      }
      double len = 0;
      for (int k = 0; k < D; ++k) len += n[k] * n[k];
      len = std::sqrt(len);
      double dopp = 0;  // orient towards the opposite node
      for (int k = 0; k < D; ++k) dopp += n[k] * (x(en[skip], k) - x(idx[0], k));
      const double sg = dopp > 0 ? 1.0 : -1.0;
      for (int k = 0; k < D; ++k) nrm[skip][k] = sg * n[k] / len;
      off[skip] = 0;
      for (int k = 0; k < D; ++k) off[skip] += nrm[skip][k] * x(idx[0], k);
    }
    for (int i = 0; i < nn; ++i) {
      if (node_piece[i] == piece[e]) continue;
      bool in = true;
      for (int k = 0; k < D && in; ++k) in = x(i, k) > lo[k] && x(i, k) < hi[k];
      if (!in) continue;
      double depth = 1e300;
      for (int f = 0; f <= D; ++f) {
        double s = -off[f];
        for (int k = 0; k < D; ++k) s += nrm[f][k] * x(i, k);
        depth = std::min(depth, s);
      }
      worst = std::max(worst, depth);
    }
  }
  return worst;
}

template <int D>
void heap_test(HostMesh block, HostMesh floor, double hsize, double t_end, double damping) {
  insert_interfaces(block, {true});
  HostMesh mesh = merge_meshes(floor, block, "floor", "block");
  auto c = fdem_test::basic_case(D, 1e7, 0.25, 2000);
  c.region_material = {{"floor", 0}, {"block", 0}};
  // interface (and so contact) stiffness 2 E / h: stiff enough (the weight sinks the pieces
  // into each other by 1e-4 h), soft enough for a larger time step
  InterfaceMaterial im = fdem_test::strong_interface(2 * 1e7 / hsize, 0.8 * 1e7 / hsize);
  c.interface_materials = {im};
  c.fracture_material = 0;
  c.contact.friction = 0.5;
  VelocityBC fix;
  fix.set = "floor.all";
  fix.active = {true, true, true};
  c.velocity_bcs = {fix};
  c.gravity = {0, 0, 0};
  c.gravity[D - 1] = -9.81;
  c.local_damping = damping;
  Simulation<D> sim(c, mesh);
  ASSERT_NE(sim.contact(), nullptr);
  fail_all_interfaces(sim);
  EXPECT_EQ(sim.contact()->handed_over(), sim.m.ni);
  const auto nodes = region_nodes(mesh, "block");
  HostState<D> hs(sim);
  const double z0 = hs.mean(nodes, true)[D - 1];
  double worst = 0;
  long checks = 0;
  // runs to t_end, then on until settled (kinetic energy below 0.1 % of the work of gravity) or
  // 4 t_end: the pieces tumble chaotically, and when the last one comes to rest varies with the
  // thread schedule (atomic sums in another order: measured 4e-8 to 1.6e-3 of the work at t_end;
  // in 2D one run in six still had 3e-3 at 2 t_end)
  // "settled" means at three checks in a row (6000 steps): a piece resting on an edge can still
  // topple after one quiet check (measured: 3e-4 of the work at a check, 3e-2 at the next)
  int quiet = 0;
  auto settled = [&] { return quiet >= 3; };
  while (sim.t < t_end || (!settled() && sim.t < 4 * t_end)) {
    sim.step(sim.step_count % 500 == 0);
    if (sim.step_count % 2000 == 0) {
      quiet = sim.energies().kinetic < 1e-3 * sim.energies().work_external ? quiet + 1 : 0;
      sim.check_stability();
      // pieces: floor elements are one piece, every block element its own
      std::vector<int> piece(mesh.num_elems());
      const int rf = mesh.region_index("floor");
      for (int e = 0; e < mesh.num_elems(); ++e) piece[e] = mesh.elem_region[e] == rf ? -1 : e;
      worst = std::max(worst, max_penetration<D>(sim, mesh, piece));
      ++checks;
    }
  }
  sim.step(true);
  hs.pull(sim);
  const double z1 = hs.mean(nodes, true)[D - 1];
  const Energies& e = sim.energies();
  std::printf("%dD heap: deepest penetration %.3g h, centre of mass down by %.3g h, kinetic energy "
              "%.3g of the work of gravity at %.3g s, balance error %.3g, friction %.3g J\n",
              D, worst / hsize, (z0 - z1) / hsize, e.kinetic / e.work_external, sim.t,
              e.balance_error / e.work_external, e.friction);
  EXPECT_GT(checks, 3);
  EXPECT_LT(worst, 0.01 * hsize) << "deepest node inside another piece";
  EXPECT_LT(z1, z0 - 0.05 * hsize) << "the cracked block did not collapse";
  EXPECT_TRUE(settled()) << "kinetic energy not below 1e-3 of the work of gravity at three checks in a row";
  EXPECT_LT(e.kinetic, 1e-3 * e.work_external) << "not settled";
  // The energy balance closes to a few per mille, not to round-off: the fade and facing weights of
  // a contact (kernels/contact.hpp) depend on positions and the force does not include their
  // derivatives; contact_pair keeps that from adding energy (a contact's energy grows only by the
  // work done on it), not from taking some. Measured over 16 runs with 2 threads: 3D -0.1 % to
  // +1.9 % of the work of gravity, 2D -0.5 % to -0.3 % (before those rules 3D reached +4.5 %).
  // A blow-up is far outside the bound (an experiment that let pieces pass through each other
  // near shared vertices gave 91 % by 0.04 s in 2D).
  EXPECT_LT(std::fabs(e.balance_error), (D == 3 ? 0.05 : 0.02) * e.work_external) << "energy balance";
  EXPECT_GT(sim.contact()->active_contacts(), 0);
  EXPECT_GT(e.friction, 0.0);
}

TEST(ContactHeap, FullyCrackedBlockSettlesWithoutInterpenetration2D) {
  heap_test<2>(generate_crossed_rectangle(0, 0, 0.04, 0.04, 4, 4, "block"),
               generate_crossed_rectangle(-0.06, -0.01, 0.16, 0.01, 16, 1, "floor"), 0.01, 0.25, 0.5);
}

TEST(ContactHeap, FullyCrackedBlockSettlesWithoutInterpenetration3D) {
  heap_test<3>(generate_box({0, 0, 0}, {0.04, 0.04, 0.04}, 2, 2, 2, "block"),
               generate_box({-0.04, -0.04, -0.01}, {0.12, 0.12, 0.01}, 3, 3, 1, "floor"), 0.02, 1.0, 0.7);
}


// A block cracked into single elements, every node given a random velocity, no damping, no
// gravity, frictionless: a conservative system, so kinetic + strain + contact energy must stay at
// the initial kinetic energy while the fragments rattle against each other (many corner contacts:
// up to 6 copies of a vertex in 2D, about 20 in 3D). FDEM_FRAG_TRACE=1 prints the trace.
template <int D>
void rattle_test(HostMesh block, double hsize, double v0, double friction, long steps, double safety) {
  insert_interfaces(block, {true});
  auto c = fdem_test::basic_case(D, 1e7, 0.25, 2000);
  c.region_material = {{"block", 0}};
  InterfaceMaterial im = fdem_test::strong_interface(2 * 1e7 / hsize, 0.8 * 1e7 / hsize);
  c.interface_materials = {im};
  c.fracture_material = 0;
  c.contact.friction = friction;
  c.local_damping = 0.0;
  c.safety_factor = safety;
  Simulation<D> sim(c, block);
  ASSERT_NE(sim.contact(), nullptr);
  fail_all_interfaces(sim);
  {
    auto v = Kokkos::create_mirror_view(sim.m.v);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-v0, v0);
    for (int i = 0; i < sim.m.nn; ++i)
      for (int k = 0; k < D; ++k) v(i, k) = u(rng);
    Kokkos::deep_copy(sim.m.v, v);
    sim.reset_energy_reference();
  }
  sim.step(true);
  const double e0 = sim.energies().kinetic + sim.energies().strain + sim.energies().contact_elastic;
  const bool trace = std::getenv("FDEM_FRAG_TRACE") != nullptr;
  double worst = 0, worst_t = 0;
  for (long n = 1; n <= steps; ++n) {
    const bool sample = n % 50 == 0 || n == steps;
    sim.step(sample);
    if (!sample) continue;
    const Energies& e = sim.energies();
    const double tot = e.kinetic + e.strain + e.contact_elastic;
    if (std::fabs(tot - e0 + e.friction) > std::fabs(worst)) {
      worst = tot - e0 + e.friction;
      worst_t = sim.t;
    }
    if (trace)
      std::printf("step %ld t %.4g kin %.4g strain %.4g contact %.4g friction %.4g total-e0 %.3g active %ld\n", n,
                  sim.t, e.kinetic / e0, e.strain / e0, e.contact_elastic / e0, e.friction / e0, (tot - e0) / e0,
                  static_cast<long>(sim.contact()->active_contacts()));
    if (!(std::fabs(tot) < 100 * e0)) break;  // blown up
  }
  std::printf("%dD rattle (friction %g, safety %g): %ld steps, dt %.3g s, worst energy change %.3g of the initial "
              "energy at t = %.3g s\n", D, friction, safety, steps, sim.dt, worst / e0, worst_t);
  EXPECT_LT(std::fabs(worst), 0.02 * e0) << "energy of the rattling fragments not conserved";
}

TEST(ContactRattle, UndampedFragmentsKeepTheirEnergy2D) {
  rattle_test<2>(generate_crossed_rectangle(0, 0, 0.04, 0.04, 4, 4, "block"), 0.01, 1.0, 0.0, 20000, 0.2);
}

TEST(ContactRattle, UndampedFragmentsKeepTheirEnergy3D) {
  rattle_test<3>(generate_box({0, 0, 0}, {0.04, 0.04, 0.04}, 2, 2, 2, "block"), 0.02, 1.0, 0.0, 20000, 0.2);
}

// With friction the energy the slip dissipates is booked, and the balance must close as well:
// the slip is booked as the shear spring's energy before minus after plus the work of the relative
// displacement against the mean of the old and new shear forces (contact_pair). Booked as
// lim * (trial - lim) / (K_s A), which is first order in dt, the same rattle with friction 1 lost
// 14 % of its energy in 2D (5 % with 0.3; 4 % at a quarter of the step); now 0.35 %.
TEST(ContactRattle, FrictionDissipationClosesTheBalance2D) {
  rattle_test<2>(generate_crossed_rectangle(0, 0, 0.04, 0.04, 4, 4, "block"), 0.01, 1.0, 1.0, 20000, 0.2);
}

TEST(ContactRattle, FrictionDissipationClosesTheBalance3D) {
  rattle_test<3>(generate_box({0, 0, 0}, {0.04, 0.04, 0.04}, 2, 2, 2, "block"), 0.02, 1.0, 1.0, 20000, 0.2);
}

}  // namespace
