// Joints and pre-existing cracks on named surfaces (docs/case-format.md, "fracture.surfaces"):
// interfaces only on a Gmsh mesh's named curve or surface of an otherwise continuous body, with
// one node copy per side (one at a crack tip); "region.<name>" node sets; the direct shear of a
// joint, whose peak shear stress is c + sigma_n tan(phi) and whose residual one, from the peak
// through the handover to contact, sigma_n tan(phi_r) (docs/theory.md section 4).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/error.hpp"
#include "io/case.hpp"
#include "mesh/mesh.hpp"
#include "test_files.hpp"

namespace {

using json = nlohmann::json;

std::string data(const std::string& f) { return std::string(FDEM_TEST_DATA) + "/" + f; }

long facets(const fdem::HostMesh& m, const std::string& name) {
  return static_cast<long>(m.face_sets.at(name).size()) / m.dim;
}

// Distinct nodes of a face set.
long facet_nodes(const fdem::HostMesh& m, const std::string& name) {
  std::vector<int> n = m.face_sets.at(name);
  std::sort(n.begin(), n.end());
  return std::unique(n.begin(), n.end()) - n.begin();
}

// Interfaces of side A and B that share the node of pair k (a crack tip).
long shared_pairs(const fdem::HostMesh& m) {
  long n = 0;
  const int D = m.dim;
  for (int q = 0; q < m.num_ifaces(); ++q)
    for (int k = 0; k < D; ++k) n += m.ifaces[2 * D * q + k] == m.ifaces[2 * D * q + D + k];
  return n;
}

TEST(Joints, InterfacesOnlyOnTheNamedCurvesWithACopyPerSide2D) {
  const fdem::HostMesh read = fdem::read_gmsh(data("joint_square.geo"), 2);
  ASSERT_EQ(read.face_sets.count("joint"), 1u);
  ASSERT_EQ(read.face_sets.count("crack"), 1u);
  const long nj = facets(read, "joint"), nc = facets(read, "crack");
  EXPECT_EQ(nj, 10);  // 0.1 m at 0.01 m
  EXPECT_EQ(nc, 5);
  // continuous: no interface, the same nodes
  fdem::HostMesh none = read;
  fdem::insert_interfaces(none, {false, false});
  EXPECT_EQ(none.num_ifaces(), 0);
  EXPECT_EQ(none.num_nodes(), read.num_nodes());
  // the joint across the block: every node on it gets a second copy
  fdem::HostMesh joint = read;
  fdem::insert_interfaces(joint, {false, false}, {"joint"});
  EXPECT_EQ(joint.num_ifaces(), nj);
  EXPECT_EQ(joint.num_nodes(), read.num_nodes() + facet_nodes(read, "joint"));
  EXPECT_EQ(shared_pairs(joint), 0);
  EXPECT_EQ(joint.iface_sets.at("joint").size(), static_cast<size_t>(nj));
  EXPECT_TRUE(joint.iface_sets.at("crack").empty());
  EXPECT_TRUE(joint.face_sets.empty());
  // every interface joins the two regions: side A in one, side B in the other
  for (int q = 0; q < joint.num_ifaces(); ++q)
    EXPECT_NE(joint.elem_region[joint.iface_elems[2 * q]], joint.elem_region[joint.iface_elems[2 * q + 1]]);
  // the crack ends inside the block: its tip keeps one copy, shared by both sides
  fdem::HostMesh both = read;
  fdem::insert_interfaces(both, {false, false}, {"crack", "joint"});
  EXPECT_EQ(both.num_ifaces(), nj + nc);
  EXPECT_EQ(both.num_nodes(), read.num_nodes() + facet_nodes(read, "joint") + facet_nodes(read, "crack") - 1);
  EXPECT_EQ(shared_pairs(both), 1);
  EXPECT_EQ(both.iface_sets.at("crack").size(), static_cast<size_t>(nc));
  // a fracturable region cracks everywhere as before; the joint adds nothing there
  fdem::HostMesh frac = read, frac_joint = read;
  fdem::insert_interfaces(frac, {true, true});
  fdem::insert_interfaces(frac_joint, {true, true}, {"joint"});
  EXPECT_EQ(frac_joint.ifaces, frac.ifaces);
  EXPECT_EQ(frac_joint.num_nodes(), frac.num_nodes());
  EXPECT_EQ(frac_joint.iface_sets.at("joint").size(), static_cast<size_t>(nj));
  // region node sets: one side's copies only
  fdem::add_region_node_sets(joint, {"lower", "upper"});
  const auto& lo = joint.node_sets.at("region.lower");
  const auto& up = joint.node_sets.at("region.upper");
  std::vector<int> common;
  std::set_intersection(lo.begin(), lo.end(), up.begin(), up.end(), std::back_inserter(common));
  EXPECT_TRUE(common.empty());
  EXPECT_EQ(static_cast<long>(lo.size() + up.size()), joint.num_nodes());
  // names that are not there
  fdem::HostMesh bad = read;
  try {
    fdem::insert_interfaces(bad, {false, false}, {"jiont"});
    ADD_FAILURE() << "no error for an unknown face set";
  } catch (const fdem::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'jiont'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("'joint'"), std::string::npos) << e.what();
  }
  bad = read;
  EXPECT_THROW(fdem::insert_interfaces(bad, {false, false}, {"bottom"}),
               fdem::InputError);  // on the boundary
  EXPECT_THROW(fdem::add_region_node_sets(bad, {"middle"}), fdem::InputError);
}

TEST(Joints, InterfacesOnlyOnTheNamedSurface3D) {
  const fdem::HostMesh read = fdem::read_gmsh(data("joint_box.geo"), 3);
  const long nj = facets(read, "joint");
  EXPECT_GT(nj, 16);
  fdem::HostMesh joint = read;
  fdem::insert_interfaces(joint, {false, false}, {"joint"});
  EXPECT_EQ(joint.num_ifaces(), nj);
  EXPECT_EQ(joint.num_nodes(), read.num_nodes() + facet_nodes(read, "joint"));
  EXPECT_EQ(shared_pairs(joint), 0);
  // each interface lies in the plane z = 0.05, its normal along z
  for (int q = 0; q < joint.num_ifaces(); ++q)
    for (int k = 0; k < 6; ++k) EXPECT_NEAR(joint.X[3 * joint.ifaces[6 * q + k] + 2], 0.05, 1e-12);
}

// The case's keys: the messages name the key, the bad name and the names the mesh has.
std::string case_error(const std::string& text, const fdem::HostMesh* mesh = nullptr) {
  try {
    const fdem::Case c = fdem::parse_case(json::parse(text), "joints.json");
    if (mesh) fdem::check_case_against_mesh(c, *mesh);
  } catch (const fdem::InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Joints, CaseKeysAreCheckedAgainstTheMesh) {
  const std::string head =
      R"({"name": "j", "dimension": 2, "time": {"end_time": 1e-3}, "mesh": {"generator": "rectangle", "size": [1, 1], "cells": [2, 2]},
    "materials": {"rock": {"density": 2500, "E": 30e9, "nu": 0.2}}, "regions": {"lower": "rock", "upper": "rock"},
    "interface_materials": {"j": {"kn": 1e12, "ks": 1e12, "ft": 0, "c": 0, "phi_deg": 30},
                            "k": {"kn": 1e12, "ks": 1e12, "ft": 1e6, "c": 1e6, "phi_deg": 30, "Gnc": 10, "Gsc": 10}},)";
  const fdem::HostMesh mesh = fdem::read_gmsh(data("joint_square.geo"), 2);
  // a frictional joint needs no fracture energies; the surfaces alone need no fracturable region
  EXPECT_EQ(
      case_error(
          head + R"("fracture": {"regions": [], "interface_material": "j", "surfaces": {"joint": "j"}}})",
          &mesh),
      "");
  std::string e = case_error(
      head + R"("fracture": {"regions": [], "interface_material": "j", "surfaces": {"jiont": "j"}}})", &mesh);
  EXPECT_NE(e.find("fracture.surfaces.jiont"), std::string::npos) << e;
  EXPECT_NE(e.find("'joint'"), std::string::npos) << e;  // what the mesh has
  e = case_error(head + R"("fracture": {"regions": [], "interface_material": "j"}})");
  EXPECT_NE(e.find("fracture.regions"), std::string::npos) << e;
  e = case_error(head +
                 R"("fracture": {"regions": [], "interface_material": "j", "surfaces": {"joint": "nope"}}})");
  EXPECT_NE(e.find("fracture.surfaces.joint"), std::string::npos) << e;
  // a cohesive material still needs them
  e = case_error(
      R"({"name": "j", "dimension": 2, "time": {"end_time": 1e-3}, "mesh": {"generator": "rectangle", "size": [1, 1], "cells": [2, 2]},
    "materials": {"rock": {"density": 2500, "E": 30e9, "nu": 0.2}}, "regions": {"body": "rock"},
    "interface_materials": {"k": {"kn": 1e12, "ks": 1e12, "ft": 1e6, "c": 0, "phi_deg": 30}}})");
  EXPECT_NE(e.find("Gnc"), std::string::npos) << e;
  // region node sets name a region of the mesh
  e = case_error(head + R"("boundary": {"fixed": [{"set": "region.middle"}]}})", &mesh);
  EXPECT_NE(e.find("boundary.fixed.0.set"), std::string::npos) << e;
  EXPECT_NE(e.find("'middle'"), std::string::npos) << e;
  EXPECT_NE(e.find("'lower'"), std::string::npos) << e;
  EXPECT_EQ(case_error(head + R"("boundary": {"fixed": [{"set": "region.lower"}]}})", &mesh), "");
}

// Runs the shear box `doc` (its regions, materials and loads set) on joint_square.geo (2D, plane
// strain, thickness 1) or joint_box.geo (3D) until end_time, 4000 history rows, in dir/out.
// The two blocks of joint_square.geo / joint_box.geo (regions lower and upper) joined by the joint
// (interface material `joint`, on the surface "joint" only); the other interfaces' material
// (none inserted unless fracture.regions names the blocks) has phi `rock_phi_deg`; no damping.
json shear_box_case(const std::string& name, double rock_phi_deg, const json& joint) {
  json doc = json::parse(R"({
    "materials": {"rock": {"density": 2500, "E": 30e9, "nu": 0.2}},
    "regions": {"lower": "rock", "upper": "rock"},
    "interface_materials": {"rock_if": {"kn": 1e11, "ks": 1e11, "ft": 5e6, "c": 10e6, "Gnc": 10, "Gsc": 100}},
    "fracture": {"regions": [], "interface_material": "rock_if", "surfaces": {"joint": "joint_if"}},
    "damping": {"local": 0}
  })");
  doc["name"] = name;
  doc["interface_materials"]["rock_if"]["phi_deg"] = rock_phi_deg;
  doc["interface_materials"]["joint_if"] = joint;
  return doc;
}

void run_shear_box(json& doc, int dim, double end_time, const std::string& dir) {
  doc["dimension"] = dim;
  doc["mesh"] = {{"file", data(dim == 2 ? "joint_square.geo" : "joint_box.geo")}};
  if (dim == 2) doc["analysis"] = {{"plane", "strain"}, {"thickness", 1.0}};
  doc["time"] = {{"end_time", end_time}, {"safety_factor", 0.5}};
  doc["output"] = {{"history_rows", 4000}, {"snapshot_count", 0}};
  std::filesystem::create_directories(dir);
  std::ofstream(dir + "/case.json") << doc.dump(2);
  const std::string env = "env OMP_NUM_THREADS=1 OMP_PROC_BIND=false ";
  const int st = fdem::test::system_status(env + FDEM_BINARY + " run " + dir + "/case.json --out " + dir +
                                           "/out --quiet > " + dir + "/run.log 2>&1");
  EXPECT_EQ(st, 0) << fdem::test::slurp(dir + "/run.log");
}

// Direct shear of the joint between the two blocks of joint_square.geo / joint_box.geo in a
// rigid shear box: every node of the lower block fixed, every node of the upper block moving at
// (vx, -vy) (2D; (vx, 0, -vy) in 3D), so that the joint closes and slides uniformly. Returns the
// joint's shear and normal stress (the lower block's reactions over the joint's area) per
// history row. `joint`: the joint's interface material; the other interfaces' (none here, with
// "regions": []) has phi 20 degrees, so that the contact friction's default is not the joint's.
struct Stresses {
  double tau, sigma;
};

std::vector<Stresses> direct_shear(int dim, const json& joint, double vx, double vy, double end_time,
                                   const std::string& dir) {
  json doc = shear_box_case("direct_shear", 20, joint);
  const json v = dim == 2 ? json::array({vx, -vy}) : json::array({vx, 0.0, -vy});
  doc["boundary"] = {{"fixed", {{{"set", "region.lower"}}}},
                     {"velocity", {{{"set", "region.upper"}, {"velocity", v}}}}};
  run_shear_box(doc, dim, end_time, dir);
  // the lower block's reaction: x (shear), and y (2D) or z (3D) (normal)
  std::istringstream in(fdem::test::slurp(dir + "/out/history.csv"));
  std::string line;
  std::getline(in, line);
  std::vector<std::string> cols;
  {
    std::istringstream h(line);
    for (std::string s; std::getline(h, s, ',');) cols.push_back(s);
  }
  const std::string nname = std::string("region.lower_reaction_") + (dim == 2 ? "y" : "z") + " [N]";
  const long ix = std::find(cols.begin(), cols.end(), "region.lower_reaction_x [N]") - cols.begin();
  const long iy = std::find(cols.begin(), cols.end(), nname) - cols.begin();
  EXPECT_LT(ix, static_cast<long>(cols.size())) << line;
  EXPECT_LT(iy, static_cast<long>(cols.size())) << line;
  const double area = 0.1 * (dim == 2 ? 1.0 : 0.1);
  std::vector<Stresses> rows;
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::istringstream r(line);
    for (std::string s; std::getline(r, s, ',');) row.push_back(std::stod(s));
    if (static_cast<long>(row.size()) > std::max(ix, iy))
      rows.push_back({std::abs(row[ix]) / area, std::abs(row[iy]) / area});
  }
  return rows;
}

// A cohesive joint (c = 1 MPa, phi = 30 degrees): the peak shear stress is c + sigma_n tan(phi),
// sigma_n of the same history row, at normal stresses of about 1, 2 and 4 MPa at the peak.
void check_cohesive_joint(int dim) {
  const std::string dir = fdem::test::scratch_dir("joints", "shear" + std::to_string(dim));
  const double c = 1e6, tanphi = std::tan(30 * M_PI / 180), k = 1e11, vx = 0.01;
  const json joint = {{"kn", k},  {"ks", k},  {"ft", 1e6}, {"c", c}, {"phi_deg", 30},
                      {"Gnc", 1}, {"Gsc", 1}, {"law", "residual_friction"}};
  for (double s : {1e6, 2e6, 4e6}) {
    const double t_peak = (c + s * tanphi) / (k * vx);  // the slip and the closure at the peak
    const auto rows = direct_shear(dim, joint, vx, s / (k * t_peak), 1.3 * t_peak,
                                   dir + "/s" + std::to_string(static_cast<int>(s / 1e6)));
    ASSERT_FALSE(rows.empty());
    const Stresses p = *std::max_element(rows.begin(), rows.end(),
                                         [](const Stresses& a, const Stresses& b) { return a.tau < b.tau; });
    std::printf(
        "direct shear %dD, cohesive joint: sigma_n %.6g Pa, peak tau %.6g Pa, c + sigma_n tan(phi) %.6g Pa "
        "(%+.3f %%)\n",
        dim, p.sigma, p.tau, c + p.sigma * tanphi, 100 * (p.tau / (c + p.sigma * tanphi) - 1));
    EXPECT_NEAR(p.sigma, s, 0.02 * s);                       // the stress the test aims at
    EXPECT_NEAR(p.tau, c + p.sigma * tanphi, 0.01 * p.tau);  // Mohr-Coulomb peak within 1 %
    // failed: the joint slides at sigma_n tan(phi_r), phi_r = phi by default (the row's sigma_n:
    // the closure goes on)
    EXPECT_NEAR(rows.back().tau, rows.back().sigma * tanphi, 0.005 * rows.back().tau);
  }
  std::filesystem::remove_all(dir);
}

// The paper's law ("law": "paper"): a failed point carries no shear, so the joint that has just
// failed carries none until it slides by dpen (its faces then go to contact).
TEST(Joints, PaperLawCarriesNoShearOnceFailed2D) {
  const std::string dir = fdem::test::scratch_dir("joints", "paper_law");
  const double c = 1e6, tanphi = std::tan(30 * M_PI / 180), k = 1e11, vx = 0.01, s = 2e6;
  const json joint = {{"kn", k},      {"ks", k},      {"ft", 1e6},      {"c", c},
                      {"phi_deg", 30}, {"Gnc", 1}, {"Gsc", 1}, {"law", "paper"}};
  const double t_peak = (c + s * tanphi) / (k * vx);
  const auto rows = direct_shear(2, joint, vx, s / (k * t_peak), 1.3 * t_peak, dir);
  ASSERT_FALSE(rows.empty());
  const Stresses p = *std::max_element(rows.begin(), rows.end(),
                                       [](const Stresses& a, const Stresses& b) { return a.tau < b.tau; });
  EXPECT_NEAR(p.tau, c + p.sigma * tanphi, 0.01 * p.tau);
  EXPECT_LT(rows.back().tau, 0.01 * p.tau);
  std::filesystem::remove_all(dir);
}

// Direct shear at a constant normal stress, as a rock mechanics laboratory runs it: the lower
// block fixed, the upper block driven sideways (x prescribed on all its nodes, the rest free)
// under a point load on its top, ramped over 1 ms, while the drive ramps up over 4 ms to 0.1 m/s.
// The joint (c 1.5 MPa, phi 33 degrees, phi_r given) peaks at c + sigma_n tan(phi), softens, and
// slides at sigma_n tan(phi_r) through its handover to contact (at about 1.5 mm of slip: a
// quarter of the thinnest element, plus the steps to the next poll). `body`: the blocks' own
// interfaces (a strong material with phi 45 degrees, so that the contact law's default friction,
// tan 45, is not the joint's) are inserted too. The history every row (E_interface, E_contact,
// energy_error, W_external; shear and normal stress of the joint from the lower block's reactions).
struct ShearRun {
  std::vector<double> tau, sigma, e_interface, e_contact, error, work;
};

ShearRun constant_normal_shear(int dim, double sigma, double phi_r_deg, double end_time, bool body,
                               const std::string& dir) {
  const json joint = {{"kn", 1e11}, {"ks", 1e11}, {"ft", 1e6}, {"c", 1.5e6}, {"phi_deg", 33}, {"Gnc", 10},
                      {"Gsc", 100}, {"phi_r_deg", phi_r_deg}, {"law", "residual_friction"}};
  json doc = shear_box_case("direct_shear_constant_normal", 45, joint);
  if (body) doc["fracture"]["regions"] = {"lower", "upper"};
  const double area = dim == 2 ? 0.1 : 0.01;
  const json drive = dim == 2 ? json::array({0.1, 0.0}) : json::array({0.1, 0.0, 0.0});
  const json load = dim == 2 ? json::array({0.0, -sigma * area}) : json::array({0.0, 0.0, -sigma * area});
  doc["boundary"] = {
      {"fixed", {{{"set", "region.lower"}}}},
      {"velocity", {{{"set", "region.upper"}, {"velocity", drive}, {"components", "x"}, {"ramp_time", 4e-3}}}},
      {"point_loads", {{{"set", "top"}, {"force", load}, {"ramp_time", 1e-3}}}}};
  run_shear_box(doc, dim, end_time, dir);
  auto h = fdem::test::read_history(dir + "/out/history.csv");
  ShearRun r;
  const std::string nname = std::string("region.lower_reaction_") + (dim == 2 ? "y" : "z") + " [N]";
  for (const char* name : {"region.lower_reaction_x [N]", "E_interface [J]", "E_contact [J]", "energy_error [J]",
                           "W_external [J]"})
    EXPECT_FALSE(h[name].empty()) << name;
  EXPECT_FALSE(h[nname].empty()) << nname;
  for (size_t i = 0; i < h[nname].size(); ++i) {
    r.tau.push_back(std::abs(h["region.lower_reaction_x [N]"][i]) / area);
    r.sigma.push_back(std::abs(h[nname][i]) / area);
    r.e_interface.push_back(h["E_interface [J]"][i]);
    r.e_contact.push_back(h["E_contact [J]"][i]);
    r.error.push_back(h["energy_error [J]"][i]);
    r.work.push_back(h["W_external [J]"][i]);
  }
  return r;
}

// From the peak to the end, tau / sigma_n never falls below tan(phi_r) by more than `dip` over
// windows of 10 history rows (50 us, 5 um of slip), nor by more than twice that in any single row
// ("instantaneous"), and it is tan(phi_r) within `tol` just before the handover and at the end;
// the balance holds within 1 % of the work throughout. Measured: 2D and 3D, the lowest window and
// row tan(phi_r) to four digits (with each node taking half of the energy at the handover: 0.3 -
// 0.9 % in 2D, 1.7 - 3.3 % in 3D, single rows 10 %; docs/theory.md section 4); the 2D body of
// interfaces 3.0 %, single rows 3.8 %, from the bounce after its 5 % drop of the normal stress at
// the handover (the contacts' shear springs stick while the normal force rises).
void check_residual_friction(int dim, double sigma, double phi_r_deg, bool body, double tol, double dip,
                             double end, const std::string& name) {
  const std::string dir = fdem::test::scratch_dir("joints", name);
  const double c = 1.5e6, tanphi = std::tan(33 * M_PI / 180), tanr = std::tan(phi_r_deg * M_PI / 180);
  const ShearRun r = constant_normal_shear(dim, sigma, phi_r_deg, end, body, dir);
  ASSERT_GT(r.tau.size(), 100u);
  const size_t ip = std::max_element(r.tau.begin(), r.tau.end()) - r.tau.begin();
  // handed over: the joint's interfaces store nothing, the contacts hold its compression
  size_t ih = r.tau.size();
  for (size_t i = ip; i < r.tau.size() && ih == r.tau.size(); ++i)
    if (r.e_interface[i] == 0.0 && r.e_contact[i] > 0.0) ih = i;
  if (body)  // the blocks' own interfaces keep storing energy: the contacts' appears
    for (size_t i = ip; i < r.tau.size() && ih == r.tau.size(); ++i)
      if (r.e_contact[i] > 0.0) ih = i;
  const size_t w = 10;
  double lowest = 1e9, instant = 1e9, worst = 0;
  for (size_t i = ip; i + w <= r.tau.size(); ++i) {
    double t = 0, sn = 0;
    for (size_t j = i; j < i + w; ++j) {
      t += r.tau[j];
      sn += r.sigma[j];
    }
    lowest = std::min(lowest, t / sn);
    instant = std::min(instant, r.tau[i] / r.sigma[i]);
  }
  for (size_t i = 0; i < r.tau.size(); ++i) worst = std::max(worst, std::abs(r.error[i]));
  ASSERT_LT(ih, r.tau.size()) << "the joint was not handed over to contact";
  const double before = r.tau[ih - 1] / r.sigma[ih - 1], after = r.tau.back() / r.sigma.back();
  std::printf(
      "direct shear %dD%s, sigma_n %.3g MPa: peak tau %.4g MPa (c + sigma_n tan(phi) %.4g), tau / sigma_n after "
      "the peak: lowest %.4f (instantaneous %.4f), before the handover (row %zu) %.4f, at the end %.4f; "
      "tan(phi_r) %.4f; worst balance error %.3g %% of the work\n",
      dim, body ? " in a body of interfaces" : "", sigma / 1e6, r.tau[ip] / 1e6, (c + r.sigma[ip] * tanphi) / 1e6,
      lowest, instant, ih, before, after, tanr, 100 * worst / r.work.back());
  // the Mohr-Coulomb peak, within 3 %: sigma_n swings, and in 3D the points of the coarse joint do
  // not all reach their peak together (the displacement-controlled test above checks it to 0.02 %)
  EXPECT_NEAR(r.tau[ip], c + r.sigma[ip] * tanphi, 0.03 * r.tau[ip]);
  EXPECT_GT(ih, ip + 10);
  EXPECT_GT(lowest, tanr * (1 - dip));  // no window without friction at any slip
  EXPECT_GT(instant, tanr * (1 - 2 * dip));
  EXPECT_NEAR(before, tanr, tol * tanr);
  EXPECT_NEAR(after, tanr, tol * tanr);
  EXPECT_LT(worst, 0.01 * r.work.back());
  std::filesystem::remove_all(dir);
}

TEST(Joints, CohesiveJointSlidesAtItsResidualFrictionThroughTheHandover2D) {
  check_residual_friction(2, 1.5e6, 25, false, 0.005, 0.002, 0.02, "residual2_15");
  check_residual_friction(2, 4e6, 25, false, 0.005, 0.002, 0.02, "residual2_40");
}
TEST(Joints, CohesiveJointSlidesAtItsResidualFrictionThroughTheHandover3D) {
  check_residual_friction(3, 1.5e6, 25, false, 0.005, 0.002, 0.025, "residual3_15");
  check_residual_friction(3, 4e6, 25, false, 0.005, 0.002, 0.025, "residual3_40");
}
// Inside a body whose own interfaces have phi 45 degrees (the contact law's default friction):
// the joint keeps its own residual friction after the handover (within 1 %: the blocks, cut into
// elements joined by interfaces, are softer, and the swings of the normal stress larger).
TEST(Joints, JointInABodyOfOtherInterfacesKeepsItsOwnResidualFriction2D) {
  check_residual_friction(2, 3e6, 33, true, 0.01, 0.035, 0.02, "residual_body");
}

// A purely frictional joint (ft = c = 0, phi = 35 degrees): handed over to contact from the
// start, it slides at sigma_n tan(phi) with the joint's friction, not the contact default (tan 20
// degrees here), at normal stresses of 1, 2 and 4 MPa at the end.
void check_frictional_joint(int dim) {
  const std::string dir = fdem::test::scratch_dir("joints", "friction" + std::to_string(dim));
  // the slip rate is high enough for the shear spring (contact ks = 1e11 Pa/m) to reach the
  // friction limit at once: the joint slides from the start
  const double tanphi = std::tan(35 * M_PI / 180), kc = 1e11, vx = 0.1, end = 1e-3;
  const json joint = {{"kn", kc}, {"ks", kc}, {"ft", 0}, {"c", 0}, {"phi_deg", 35}};
  for (double s : {1e6, 2e6, 4e6}) {
    const auto rows = direct_shear(dim, joint, vx, s / (kc * end), end,
                                   dir + "/s" + std::to_string(static_cast<int>(s / 1e6)));
    ASSERT_GT(rows.size(), 10u);
    const Stresses e = rows.back();
    std::printf(
        "direct shear %dD, frictional joint: sigma_n %.6g Pa, tau %.6g Pa, sigma_n tan(phi) %.6g Pa (%+.3f "
        "%%)\n",
        dim, e.sigma, e.tau, e.sigma * tanphi, 100 * (e.tau / (e.sigma * tanphi) - 1));
    // about the contact kn (the default: rock_if's kn) times the closure; more in 3D, where a
    // node on the joint's edge counts its share of the block's side faces in its contact area
    // (+43 % on this 4 x 4 face mesh, +14 % at 8 x 8)
    EXPECT_GT(e.sigma, 0.95 * s);
    EXPECT_LT(e.sigma, (dim == 2 ? 1.05 : 1.5) * s);
    EXPECT_NEAR(e.tau, e.sigma * tanphi, 0.01 * e.tau);
    // sliding all along: the ratio holds over the second half of the run too
    for (size_t i = rows.size() / 2; i < rows.size(); i += rows.size() / 10)
      EXPECT_NEAR(rows[i].tau, rows[i].sigma * tanphi, 0.01 * rows[i].tau + 1.0) << "row " << i;
  }
  std::filesystem::remove_all(dir);
}

// A frictionless joint (ft = c = phi = 0) under load slides: the upper block of joint_square.geo,
// pressed down by 2e5 N and pushed sideways by 1.5e4 N on its top (the lower block fixed), slides
// about 5 mm. The nodes at the block's ends slide off the edge of the face they press on; their
// contacts' weights fade out while compressed, releasing sigma_n^2 / (2 K_n) per unit area that
// slides off (4.85 J here, 4.1 % of the energy scale, when it was not booked): D_friction books it,
// and the balance closes (measured 0.003 %).
TEST(Joints, FrictionlessJointSlidingOffItsEdgeKeepsTheBalance2D) {
  const std::string dir = fdem::test::scratch_dir("joints", "frictionless_slide");
  json doc = json::parse(R"({
    "name": "frictionless_slide", "dimension": 2, "analysis": {"plane": "strain", "thickness": 1.0},
    "materials": {"rock": {"density": 2500, "E": 30e9, "nu": 0.2}},
    "regions": {"lower": "rock", "upper": "rock"},
    "interface_materials": {"joint_if": {"kn": 1e10, "ks": 1e10, "ft": 0, "c": 0, "phi_deg": 0}},
    "fracture": {"regions": [], "interface_material": "joint_if", "surfaces": {"joint": "joint_if"}},
    "boundary": {"fixed": [{"set": "region.lower"}],
                 "point_loads": [{"set": "top", "force": [1.5e4, -2e5], "ramp_time": 2e-4}]},
    "damping": {"local": 0}, "time": {"end_time": 3e-3, "safety_factor": 0.5},
    "output": {"history_rows": 300, "snapshot_count": 0, "monitors": ["region.upper"]}
  })");
  doc["mesh"] = {{"file", data("joint_square.geo")}};
  std::filesystem::create_directories(dir);
  std::ofstream(dir + "/case.json") << doc.dump(2);
  const int st = fdem::test::system_status("env OMP_NUM_THREADS=1 OMP_PROC_BIND=false " +
                                           std::string(FDEM_BINARY) + " run " + dir + "/case.json --out " +
                                           dir + "/out --quiet > " + dir + "/run.log 2>&1");
  ASSERT_EQ(st, 0) << fdem::test::slurp(dir + "/run.log");
  auto h = fdem::test::read_history(dir + "/out/history.csv");
  for (const char* name : {"W_external [J]", "energy_error [J]", "D_friction [J]", "region.upper_ux [m]"})
    ASSERT_FALSE(h[name].empty()) << name;
  double scale = 0, worst = 0;
  for (double w : h["W_external [J]"]) scale = std::max(scale, std::abs(w));
  for (double e : h["energy_error [J]"]) worst = std::max(worst, std::abs(e));
  const double slid = h["region.upper_ux [m]"].back(), friction = h["D_friction [J]"].back();
  std::printf(
      "frictionless joint: slid %.3g m, D_friction %.4g J, worst balance error %.3g J (%.4f %% of %.4g J)\n",
      slid, friction, worst, 100 * worst / scale, scale);
  EXPECT_GT(slid, 5e-3);              // it slid past the ends' fade (0.1 mm) by far
  EXPECT_GT(friction, 0.02 * scale);  // what the ends released (4.85 J of 119 J)
  EXPECT_LT(worst, 1e-3 * scale);     // was 4.1 %
  std::filesystem::remove_all(dir);
}

TEST(Joints, DirectShearPeakIsCohesionPlusFriction2D) { check_cohesive_joint(2); }
TEST(Joints, DirectShearPeakIsCohesionPlusFriction3D) { check_cohesive_joint(3); }
TEST(Joints, FrictionalJointSlidesAtItsOwnFriction2D) { check_frictional_joint(2); }
TEST(Joints, FrictionalJointSlidesAtItsOwnFriction3D) { check_frictional_joint(3); }

}  // namespace
