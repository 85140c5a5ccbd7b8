// Interface materials by place and random strength (docs/case-format.md, "fracture"): which
// interface takes which material, the weaker material failing first at its own strength, the
// scatter's statistics and determinism, and the reader's messages.
#include <gtest/gtest.h>

#include <hdf5.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/error.hpp"
#include "io/case.hpp"
#include "kernels/cohesive.hpp"
#include "solver/interface_materials.hpp"
#include "solver/simulation.hpp"
#include "solver_fixtures.hpp"
#include "test_files.hpp"

namespace {

using namespace fdem;
using json = nlohmann::json;

InterfaceMaterial material(const std::string& name, double ft) {
  InterfaceMaterial m;
  m.name = name;
  m.kn = 30e9 / (0.1 * 0.01);
  m.ks = m.kn / 2.4;
  m.ft = ft;
  m.c = 2 * ft;
  m.phi = 0.5;
  m.Gnc = 20;
  m.Gsc = 200;
  return m;
}

// A bar of 6 blocks (side 10 mm): blocks 0-2 in region "a", 3-5 in region "b". Interfaces 0, 1
// join a to a, 2 joins a to b, 3 and 4 join b to b.
HostMesh two_region_bar() {
  HostMesh mesh = fdem_test::block_bar(6, 0.01, 0.01);
  mesh.region_names = {"a", "b"};
  for (size_t e = 0; e < mesh.elem_region.size(); ++e) mesh.elem_region[e] = e < 6 ? 0 : 1;
  return mesh;
}

// Materials: 0 "default" (8 MPa), 1 "weak_b" (ft_b), 2 "itz" (ft_itz); region b takes weak_b, the
// pair (a, b) takes itz.
Case two_region_case(double ft_b, double ft_itz) {
  Case c = fdem_test::basic_case(2, 30e9, 0.2, 2500);
  c.region_material = {{"a", 0}, {"b", 0}};
  c.interface_materials = {material("default", 8e6), material("weak_b", ft_b), material("itz", ft_itz)};
  c.fracture_material = 0;
  c.fracturable_regions = {"a", "b"};
  c.region_iface_material = {{"b", 1}};
  c.pair_iface_material = {{{"a", "b"}, 2}};
  return c;
}

TEST(InterfaceMaterials, RegionAndPairRulesPickEachInterfacesMaterial) {
  const HostMesh mesh = two_region_bar();
  const Case c = two_region_case(2e6, 4e6);
  const InterfaceMaterialMap map = interface_material_map(c, mesh);
  EXPECT_EQ(map.material, (std::vector<int>{0, 0, 2, 1, 1}));
  EXPECT_EQ(map.count, (std::vector<long>{2, 2, 1}));
  EXPECT_TRUE(map.scale.empty());
  const json r = interface_material_report(c, map);
  EXPECT_EQ(r["interfaces_per_material"]["default"], 2);
  EXPECT_EQ(r["interfaces_per_material"]["weak_b"], 2);
  EXPECT_EQ(r["interfaces_per_material"]["itz"], 1);
  // one material, no scatter: no map (the one-material kernel)
  Case one = c;
  one.region_iface_material.clear();
  one.pair_iface_material.clear();
  const InterfaceMaterialMap none = interface_material_map(one, mesh);
  EXPECT_TRUE(none.material.empty());
  EXPECT_EQ(none.count, (std::vector<long>{5, 0, 0}));
}

// Pulls the bar (left end fixed) slowly with local damping until the first interface has failed.
// Returns the peak reaction (N per m of thickness) and the damage of each interface at the end.
double pull_until_failure(const Case& given, std::vector<double>& damage) {
  Case c = given;
  VelocityBC fixed, pulled;
  fixed.set = "left";
  fixed.active = {true, true, false};
  pulled.set = "right";
  pulled.active = {true, false, false};
  pulled.velocity = {0.004, 0, 0};
  pulled.ramp_time = 2e-5;
  c.velocity_bcs = {fixed, pulled};
  c.local_damping = 0.7;
  Simulation<2> sim(c, two_region_bar());
  sim.set_sample_reactions(true);
  double peak = 0;
  for (int s = 0; s < 400000 && sim.t < 5e-3; ++s) {
    sim.step(s % 10 == 0);
    if (s % 10 == 0) {
      peak = std::max(peak, -sim.reactions()[0][0]);
      if (sim.energies().failed >= 1) break;
    }
  }
  auto h = Kokkos::create_mirror_view(sim.m.ihist);
  Kokkos::deep_copy(h, sim.m.ihist);
  damage.assign(sim.m.ni, 0.0);
  for (int q = 0; q < sim.m.ni; ++q)
    for (int k = 0; k < 2; ++k) damage[q] = std::max(damage[q], cohesive_damage(load_point(h, q, k)));
  return peak;
}

// The weaker interface material fails first, at its own strength (stress = force / height).
// A rule that applies to no interface is named in a warning (the run goes on); rules in use are not.
TEST(InterfaceMaterials, RulesThatApplyToNoInterfaceAreNamed) {
  HostMesh mesh = two_region_bar();
  const Case c = two_region_case(2e6, 4e6);
  EXPECT_TRUE(unused_material_rules(c, mesh).empty());
  // region b is the last block alone: no interface has both sides in it; the pair (a, b) has one
  for (size_t e = 0; e < mesh.elem_region.size(); ++e) mesh.elem_region[e] = e < 10 ? 0 : 1;
  Case more = c;
  more.file = "t.json";
  more.pair_iface_material[{"b", "ghost"}] = 2;  // a region the mesh does not have
  const std::vector<std::string> w = unused_material_rules(more, mesh);
  ASSERT_EQ(w.size(), 2u);
  EXPECT_NE(w[0].find("t.json: fracture.region_materials.b: no interface has both sides in region 'b'"),
            std::string::npos) << w[0];
  EXPECT_NE(w[0].find("a warning"), std::string::npos) << w[0];
  EXPECT_NE(w[1].find("fracture.pair_materials [b, ghost]"), std::string::npos) << w[1];
}

// A part of a run over processes draws each interface's factor from the whole mesh's index of the
// interface (HostMesh::iface_ids), so the field is the same on any number of processes.
TEST(InterfaceMaterials, ScatterOfAPartIsDrawnFromTheWholeMeshIndex) {
  const HostMesh whole = two_region_bar();
  Case c = two_region_case(2e6, 4e6);
  c.scatter.distribution = "weibull";
  c.scatter.modulus = 5;
  c.scatter.seed = 11;
  const InterfaceMaterialMap all = interface_material_map(c, whole);
  HostMesh part = whole;
  part.iface_ids = {4, 3, 2, 1, 0};  // its interfaces in another order (their geometry aside)
  const InterfaceMaterialMap mine = interface_material_map(c, part);
  ASSERT_EQ(mine.scale.size(), 5u);
  for (int q = 0; q < 5; ++q) EXPECT_EQ(mine.scale[q], all.scale[4 - q]) << q;
  EXPECT_NE(all.scale[0], all.scale[4]);
}

TEST(InterfaceMaterials, WeakerMaterialFailsFirstAtItsStrength) {
  std::vector<double> d;
  // region b weakest (2 MPa): one of its interfaces (3, 4) fails, no other initiates
  const double peak_b = pull_until_failure(two_region_case(2e6, 4e6), d);
  EXPECT_NEAR(peak_b / 0.01, 2e6, 0.02 * 2e6);
  EXPECT_GT(std::max(d[3], d[4]), 0.99);
  for (int q : {0, 1, 2}) EXPECT_EQ(d[q], 0.0) << "interface " << q;
  // the pair (a, b) weakest (1.5 MPa): interface 2 fails
  const double peak_itz = pull_until_failure(two_region_case(4e6, 1.5e6), d);
  EXPECT_NEAR(peak_itz / 0.01, 1.5e6, 0.01 * 1.5e6);
  EXPECT_GT(d[2], 0.99);
  for (int q : {0, 1, 3, 4}) EXPECT_EQ(d[q], 0.0) << "interface " << q;
}

// Weibull and truncated normal factors: mean 1 and the distribution's coefficient of variation,
// the same factor for the same (seed, interface), another field for another seed.
TEST(InterfaceMaterials, ScatterHasMeanOneTheStatedSpreadAndIsReproducible) {
  const long n = 200000;
  auto stats = [n](const StrengthScatter& s, double& mean, double& cov, double& lo, double& hi) {
    double sum = 0, sum2 = 0;
    lo = 1e300;
    hi = 0;
    for (long q = 0; q < n; ++q) {
      const double w = strength_factor(s, q);
      sum += w;
      sum2 += w * w;
      lo = std::min(lo, w);
      hi = std::max(hi, w);
    }
    mean = sum / n;
    cov = std::sqrt(sum2 / n - mean * mean) / mean;
  };
  double mean, cov, lo, hi;
  for (double m : {2.0, 5.0, 10.0}) {
    StrengthScatter s;
    s.distribution = "weibull";
    s.modulus = m;
    s.seed = 42;
    stats(s, mean, cov, lo, hi);
    const double g1 = std::tgamma(1 + 1 / m), g2 = std::tgamma(1 + 2 / m);
    EXPECT_NEAR(mean, 1.0, 0.01) << "m = " << m;
    EXPECT_NEAR(cov, std::sqrt(g2 / (g1 * g1) - 1), 0.01) << "m = " << m;
    EXPECT_GT(lo, 0.0);
  }
  StrengthScatter nrm;
  nrm.distribution = "normal";
  nrm.cov = 0.3;
  nrm.lower = 0.5;
  nrm.upper = 1.5;
  stats(nrm, mean, cov, lo, hi);
  // symmetric truncation: the truncated mean is 1, the bounds hold as given; the spread shrinks
  // below 0.3 (truncated at 1.67 standard deviations: 0.3 * 0.7958 = 0.2388)
  EXPECT_NEAR(mean, 1.0, 0.005);
  EXPECT_GE(lo, 0.5);
  EXPECT_LE(hi, 1.5);
  EXPECT_NEAR(cov, 0.2388, 0.005);
  // reproducible per (seed, q); another seed, another field
  StrengthScatter s;
  s.distribution = "weibull";
  s.modulus = 5;
  s.seed = 7;
  const double w3 = strength_factor(s, 3);
  EXPECT_EQ(strength_factor(s, 3), w3);
  s.seed = 8;
  EXPECT_NE(strength_factor(s, 3), w3);
}

// A scatter changes each interface's strength by its factor: a bar whose weak region has a
// strength scatter fails at the weakest of its interfaces' strengths.
// A correlated scatter (fracture.scatter.correlation_length): the underlying normal field has
// mean 0, variance 1 and the correlation exp(-r^2 / l^2) at r = l / 2, l, 2 l (over 40 000 pairs
// in a square 60 l wide: the field's spatial averages, one realisation of its 256 modes); the
// factors keep the distribution's mean 1 and coefficient of variation; the same seed gives the
// same field, another seed another.
TEST(InterfaceMaterials, CorrelatedScatterHasItsCorrelationLengthAndDistribution) {
  StrengthScatter s{"weibull", 5, 0, 0.1, 10, 7, false};
  s.correlation_length = 0.01;
  const double l = s.correlation_length, side = 60 * l;
  const CorrelatedField g(s, 2);
  const int n = 40000;
  for (double r : {0.5 * l, l, 2 * l}) {
    double sum = 0, sum2 = 0, prod = 0;
    for (int i = 0; i < n; ++i) {
      // points on a low-discrepancy sequence, each with a partner at distance r in a turning direction
      const double x[2] = {side * std::fmod(i * 0.7548776662, 1.0), side * std::fmod(i * 0.5698402910, 1.0)};
      const double th = 2.399963 * i;
      const double y[2] = {x[0] + r * std::cos(th), x[1] + r * std::sin(th)};
      const double a = g.gaussian(x), b = g.gaussian(y);
      sum += a;
      sum2 += a * a;
      prod += a * b;
    }
    EXPECT_NEAR(sum / n, 0.0, 0.05);
    EXPECT_NEAR(sum2 / n, 1.0, 0.08);
    std::printf("correlated field: r / l = %.1f: mean %.4f, variance %.4f, correlation %.4f (target %.4f)\n",
                r / l, sum / n, sum2 / n, prod / n, std::exp(-r * r / (l * l)));
    EXPECT_NEAR(prod / n, std::exp(-r * r / (l * l)), 0.06) << "r = " << r;
  }
  // the factors: Weibull m = 5 (mean 1, cov 0.2291) and the truncated normal's mean 1
  double m1 = 0, m2 = 0;
  for (int i = 0; i < n; ++i) {
    const double x[2] = {side * std::fmod(i * 0.7548776662, 1.0), side * std::fmod(i * 0.5698402910, 1.0)};
    const double w = factor_from_gaussian(s, g.gaussian(x));
    m1 += w / n;
    m2 += w * w / n;
  }
  std::printf("correlated Weibull m = 5: mean %.4f, cov %.4f (0.2291)\n", m1, std::sqrt(m2 - m1 * m1) / m1);
  EXPECT_NEAR(m1, 1.0, 0.03);
  EXPECT_NEAR(std::sqrt(m2 - m1 * m1) / m1, 0.2291, 0.03);
  const StrengthScatter tn{"normal", 0, 0.3, 0.5, 1.5, 7, false};
  double mt = 0;
  for (int i = 0; i < 2001; ++i) {
    const double w = factor_from_gaussian(tn, -4.0 + 0.004 * i);
    EXPECT_GE(w, 0.5 - 1e-9);  // within the truncation (symmetric about 1: the mean is 1 already)
    EXPECT_LE(w, 1.5 + 1e-9);
    mt += w * std::exp(-0.5 * std::pow(-4.0 + 0.004 * i, 2)) * 0.004 / std::sqrt(2 * M_PI);
  }
  EXPECT_NEAR(mt, 1.0, 1e-3);  // the mean over the normal field's distribution
  // reproducible, and another seed is another field
  const double p[2] = {0.123, 0.456};
  EXPECT_EQ(CorrelatedField(s, 2).gaussian(p), g.gaussian(p));
  StrengthScatter s2 = s;
  s2.seed = 8;
  EXPECT_NE(CorrelatedField(s2, 2).gaussian(p), g.gaussian(p));
}

TEST(InterfaceMaterials, ScatteredBarFailsAtItsWeakestInterface) {
  Case c = two_region_case(2e6, 8e6);
  c.region_iface_material.clear();
  c.pair_iface_material.clear();
  c.fracture_material = 1;  // every interface 2 MPa before the scatter
  c.scatter.distribution = "weibull";
  c.scatter.modulus = 5;
  c.scatter.seed = 3;
  double wmin = 1e300;
  int qmin = -1;
  for (int q = 0; q < 5; ++q)
    if (strength_factor(c.scatter, q) < wmin) {
      wmin = strength_factor(c.scatter, q);
      qmin = q;
    }
  std::vector<double> d;
  const double peak = pull_until_failure(c, d);
  // float storage of the factor: relative rounding 6e-8
  EXPECT_NEAR(peak / 0.01, 2e6 * wmin, 0.01 * 2e6 * wmin);
  EXPECT_GT(d[qmin], 0.99);
}

// The reader: the rules and the scatter parse; bad names and values give messages naming the key.
TEST(InterfaceMaterials, CaseReaderReadsRulesAndNamesBadOnes) {
  json doc = json::parse(R"({
    "name": "t", "dimension": 2,
    "mesh": {"generator": "rectangle", "origin": [0, 0], "size": [0.1, 0.01], "cells": [10, 1]},
    "materials": {"rock": {"density": 2500, "E": 30e9, "nu": 0.2}},
    "regions": {"body": "rock", "other": "rock"},
    "interface_materials": {
      "a": {"kn": 6e13, "ks": 2.5e13, "ft": 3e6, "c": 9e6, "phi_deg": 30, "Gnc": 50, "Gsc": 1000},
      "b": {"kn": 6e13, "ks": 2.5e13, "ft": 1e6, "c": 3e6, "phi_deg": 30, "Gnc": 20, "Gsc": 400}},
    "fracture": {"regions": ["body"], "interface_material": "a",
                 "region_materials": {"other": "b"},
                 "pair_materials": [{"regions": ["other", "body"], "material": "b"}],
                 "scatter": {"distribution": "weibull", "modulus": 5, "seed": 9, "energy": true}},
    "time": {"end_time": 1e-3}
  })");
  const Case c = parse_case(doc, "t.json", {});
  EXPECT_EQ(c.region_iface_material.at("other"), 1);
  EXPECT_EQ(c.pair_iface_material.at({"body", "other"}), 1);  // ordered key
  EXPECT_EQ(c.scatter.distribution, "weibull");
  EXPECT_EQ(c.scatter.modulus, 5);
  EXPECT_EQ(c.scatter.seed, 9u);
  EXPECT_TRUE(c.scatter.energy);
  auto error_of = [&](const std::string& key, const json& value) {
    json d = doc;
    d["fracture"][key] = value;
    try {
      parse_case(d, "t.json", {});
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("<no error>");
  };
  auto has = [](const std::string& msg, const std::string& part) {
    return msg.find(part) != std::string::npos;
  };
  std::string e = error_of("region_materials", json{{"other", "c"}});
  EXPECT_TRUE(has(e, "fracture.region_materials.other") && has(e, "unknown interface material 'c'")) << e;
  e = error_of("region_materials", json{{"nowhere", "a"}});
  EXPECT_TRUE(has(e, "fracture.region_materials.nowhere") && has(e, "no material")) << e;
  e = error_of("pair_materials", json::parse(R"([{"regions": ["body", "body"], "material": "a"}])"));
  EXPECT_TRUE(has(e, "fracture.pair_materials.0.regions") && has(e, "the same")) << e;
  e = error_of("pair_materials", json::parse(R"([{"regions": ["body"], "material": "a"}])"));
  EXPECT_TRUE(has(e, "two region names")) << e;
  e = error_of("pair_materials", json::parse(R"([{"regions": ["body", "other"], "material": "a"},
                                                 {"regions": ["other", "body"], "material": "b"}])"));
  EXPECT_TRUE(has(e, "fracture.pair_materials.1") && has(e, "twice")) << e;
  e = error_of("scatter", json{{"distribution", "gamma"}});
  EXPECT_TRUE(has(e, "fracture.scatter.distribution") && has(e, "weibull")) << e;
  e = error_of("scatter", json{{"distribution", "weibull"}, {"modulus", 0.1}});
  EXPECT_TRUE(has(e, "fracture.scatter.modulus")) << e;
  e = error_of("scatter", json{{"distribution", "normal"}, {"cov", 0.2}, {"lower", 1.5}});
  EXPECT_TRUE(has(e, "fracture.scatter.lower")) << e;
  e = error_of("scatter", json{{"distribution", "weibull"}, {"modulus", 5}, {"correlation_length", 0}});
  EXPECT_TRUE(has(e, "fracture.scatter.correlation_length")) << e;
}

// `fdem check` counts the interfaces per material on a Gmsh mesh of two regions; `fdem run`
// writes the material index and the strength factor of every interface into the snapshots.
TEST(InterfaceMaterials, CheckCountsThemAndSnapshotsShowThem) {
  const std::string dir = fdem::test::scratch_dir("ifmat", "cli");
  std::filesystem::create_directories(dir);
  json doc = json::parse(R"({
    "name": "two_regions", "dimension": 2,
    "analysis": {"plane": "stress", "thickness": 0.01},
    "materials": {"rock": {"density": 2500, "E": 30e9, "nu": 0.2}},
    "regions": {"rock": "rock", "weak": "rock"},
    "interface_materials": {
      "strong": {"kn": 1e12, "ks": 4e11, "ft": 8e6, "c": 16e6, "phi_deg": 30, "Gnc": 50, "Gsc": 1000},
      "weak_if": {"kn": 1e12, "ks": 4e11, "ft": 2e6, "c": 4e6, "phi_deg": 30, "Gnc": 20, "Gsc": 400},
      "itz": {"kn": 1e12, "ks": 4e11, "ft": 4e6, "c": 8e6, "phi_deg": 30, "Gnc": 20, "Gsc": 400}},
    "fracture": {"regions": ["rock", "weak"], "interface_material": "strong",
                 "region_materials": {"weak": "weak_if"},
                 "pair_materials": [{"regions": ["weak", "rock"], "material": "itz"}],
                 "scatter": {"distribution": "weibull", "modulus": 5, "seed": 3}},
    "boundary": {"fixed": [{"set": "left", "components": "xy"}],
                 "velocity": [{"set": "right", "velocity": [0.05, 0], "components": "x", "ramp_time": 1e-4}]},
    "damping": {"local": 0.7},
    "time": {"end_time": 5e-4, "safety_factor": 0.5},
    "output": {"history_rows": 10, "snapshot_count": 2}
  })");
  doc["mesh"] = {{"file", std::string(FDEM_TEST_DATA) + "/two_regions_v41.msh"}};
  std::ofstream(dir + "/case.json") << doc.dump(2);
  const std::string env = "env OMP_NUM_THREADS=1 OMP_PROC_BIND=false ";
  ASSERT_EQ(fdem::test::system_status(env + FDEM_BINARY + " check " + dir + "/case.json > " + dir +
                                      "/check.log 2>&1"),
            0)
      << fdem::test::slurp(dir + "/check.log");
  const std::string log = fdem::test::slurp(dir + "/check.log");
  const json r = json::parse(log.substr(0, log.rfind('}') + 1));
  const json& per = r["interfaces"]["interfaces_per_material"];
  // the mesh's 4 edges on x = 1 join the regions; the rest lie inside one of them
  EXPECT_EQ(per["itz"], 4);
  // the unnamed physical curve 17 of the mesh is that line: its 4 interfaces, by surface
  EXPECT_EQ(r["interfaces"]["interfaces_per_surface"]["group_17"], 4);
  EXPECT_EQ(per["strong"].get<long>() + per["weak_if"].get<long>() + 4, r["mesh"]["interfaces"].get<long>());
  EXPECT_GT(per["weak_if"].get<long>(), 10);
  EXPECT_NEAR(r["interfaces"]["strength_scatter"]["factor_mean"].get<double>(), 1.0, 0.1);

  ASSERT_EQ(fdem::test::system_status(env + FDEM_BINARY + " run " + dir + "/case.json --out " + dir +
                                      "/out --quiet > " + dir + "/run.log 2>&1"),
            0)
      << fdem::test::slurp(dir + "/run.log");
  const hid_t f = H5Fopen((dir + "/out/snapshots.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  const long ni = r["mesh"]["interfaces"].get<long>();
  std::vector<int> mat(ni, -1);
  std::vector<double> w(ni, -1);
  const hid_t dm = H5Dopen2(f, "/mesh/interface_material", H5P_DEFAULT);
  const hid_t dw = H5Dopen2(f, "/mesh/strength_factor", H5P_DEFAULT);
  ASSERT_GE(dm, 0);
  ASSERT_GE(dw, 0);
  ASSERT_GE(H5Dread(dm, H5T_NATIVE_INT, H5S_ALL, H5S_ALL, H5P_DEFAULT, mat.data()), 0);
  ASSERT_GE(H5Dread(dw, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, w.data()), 0);
  H5Dclose(dm);
  H5Dclose(dw);
  H5Fclose(f);
  long n_itz = 0;
  for (long q = 0; q < ni; ++q) {
    n_itz += mat[q] == 0;  // interface_material_names: itz, strong, weak_if (the reader sorts them)
    EXPECT_FLOAT_EQ(
        w[q], static_cast<float>(strength_factor(StrengthScatter{"weibull", 5, 0, 0.1, 10, 3, false}, q)));
  }
  EXPECT_EQ(n_itz, 4);
  const std::string xdmf = fdem::test::slurp(dir + "/out/snapshots.xdmf");
  EXPECT_NE(xdmf.find("/mesh/interface_material"), std::string::npos);
  EXPECT_NE(xdmf.find("/mesh/strength_factor"), std::string::npos);
  std::filesystem::remove_all(dir);
}

}  // namespace
