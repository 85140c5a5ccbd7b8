// Case file reader: the example cases parse to the right numbers; every kind of bad input gives an
// InputError naming the key path (and the nearest valid name for unknown keys); --set overrides.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <unistd.h>

#include "common/error.hpp"
#include "io/case.hpp"
#include "mesh/mesh.hpp"
#include "solver/run.hpp"

namespace {

using fdem::Case;
using fdem::InputError;
using json = nlohmann::json;
namespace fs = std::filesystem;

const std::string kDisc = std::string(FDEM_SOURCE_DIR) + "/cases/brazilian_disc/case.json";
const std::string kDiscPaper = std::string(FDEM_SOURCE_DIR) + "/cases/brazilian_disc/case_paper.json";
const std::string kBar = std::string(FDEM_TEST_DATA) + "/cases/bar.json";
constexpr double kPi = 3.14159265358979323846;

// A small valid case, edited by the tests.
json base_doc() {
  return json::parse(R"({
    "name": "t",
    "dimension": 2,
    "mesh": {"generator": "rectangle", "origin": [0, 0], "size": [0.1, 0.01], "cells": [10, 1]},
    "analysis": {"plane": "stress", "thickness": 0.01},
    "materials": {"concrete": {"density": 2500, "E": 30e9, "nu": 0.2}},
    "regions": {"body": "concrete"},
    "interface_materials": {"cif": {"kn": 6e13, "ks": 2.5e13, "ft": 3e6, "c": 9e6, "phi_deg": 30,
                                    "Gnc": 50, "Gsc": 1000}},
    "fracture": {"regions": ["body"], "interface_material": "cif"},
    "boundary": {"fixed": [{"set": "left"}],
                 "velocity": [{"set": "right", "velocity": [0.05, 0], "components": "x"}],
                 "point_loads": [{"set": "right", "force": [0, -10]}],
                 "initial_velocity": [{"region": "body", "velocity": [1, 0]}]},
    "platens": [{"name": "top", "point": [0, 0.02], "normal": [0, -2], "velocity": [0, -0.1],
                 "friction": 0.3}],
    "damping": {"local": 0.7},
    "time": {"end_time": 2e-3, "stop": {"platen": "top", "drop_fraction": 0.5}},
    "output": {"history_rows": 100}
  })");
}

// The message of the InputError thrown by parse_case, or "<no error>".
std::string error_of(const json& doc, const std::vector<std::string>& overrides = {}) {
  try {
    fdem::parse_case(doc, "test.json", overrides);
  } catch (const InputError& e) {
    return e.what();
  }
  return "<no error>";
}

std::string load_error(const std::string& path, const std::vector<std::string>& overrides = {}) {
  try {
    fdem::load_case(path, overrides);
  } catch (const InputError& e) {
    return e.what();
  }
  return "<no error>";
}

// A fresh folder under the temp dir, removed at the end of the test.
struct TempDir {
  fs::path path;
  TempDir() {
    static int counter = 0;
    path = fs::temp_directory_path() /
           ("fdem_test_case_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  std::string write(const std::string& name, const std::string& text) const {
    fs::path p = path / name;
    std::ofstream(p) << text;
    return p.string();
  }
};

#define EXPECT_HAS(msg, part) EXPECT_NE((msg).find(part), std::string::npos) << "message: " << (msg)

// ---------------------------------------------------------------------------------------------

// The paper's setting (flat rigid platens, a Delaunay mesh without the embedded diameter): the case
// variant case_paper.json (cases/brazilian_disc/README.md).
TEST(CaseExamples, BrazilianDiscHasThePapersParameters) {
  Case c = fdem::load_case(kDiscPaper);
  EXPECT_EQ(c.file, kDiscPaper);
  EXPECT_EQ(c.name, "brazilian_disc");
  EXPECT_EQ(c.dim, 2);
  EXPECT_EQ(c.mesh.kind, "disc");
  EXPECT_DOUBLE_EQ(c.mesh.radius, 0.05);
  EXPECT_DOUBLE_EQ(c.mesh.element_size, 0.003);
  EXPECT_DOUBLE_EQ(c.mesh.diameter[0], 0.0);  // no embedded diameter
  EXPECT_DOUBLE_EQ(c.mesh.diameter[1], 0.0);
  EXPECT_DOUBLE_EQ(c.mesh.origin[0], 0.0);
  EXPECT_DOUBLE_EQ(c.mesh.origin[1], 0.0);
  EXPECT_EQ(c.mesh.region, "body");
  EXPECT_TRUE(c.plane_stress);
  EXPECT_DOUBLE_EQ(c.thickness, 1e-3);

  ASSERT_EQ(c.materials.size(), 1u);
  EXPECT_EQ(c.materials[0].name, "rock");
  EXPECT_DOUBLE_EQ(c.materials[0].E, 33e9);
  EXPECT_DOUBLE_EQ(c.materials[0].nu, 0.25);
  EXPECT_DOUBLE_EQ(c.materials[0].density, 2700);
  ASSERT_EQ(c.region_material.count("body"), 1u);
  EXPECT_EQ(c.region_material.at("body"), 0);

  ASSERT_EQ(c.interface_materials.size(), 1u);
  const auto& im = c.interface_materials[0];
  EXPECT_DOUBLE_EQ(im.kn, 1.10e14);
  EXPECT_DOUBLE_EQ(im.ks, 4.40e13);
  EXPECT_DOUBLE_EQ(im.ft, 8e6);
  EXPECT_DOUBLE_EQ(im.c, 16.56e6);
  EXPECT_NEAR(im.phi, kPi / 4, 1e-15);  // 45 degrees, stored in radians
  EXPECT_DOUBLE_EQ(im.Gnc, 75);
  EXPECT_DOUBLE_EQ(im.Gsc, 1500);
  EXPECT_DOUBLE_EQ(im.eta, 2.0);
  EXPECT_EQ(c.fracturable_regions, std::vector<std::string>{"body"});
  EXPECT_EQ(c.fracture_material, 0);

  ASSERT_EQ(c.platens.size(), 2u);
  const auto& top = c.platens[0];
  const auto& bot = c.platens[1];
  EXPECT_EQ(top.name, "top");
  EXPECT_NEAR(top.point[1], 0.05005, 1e-15);  // 0.05 mm gap
  EXPECT_DOUBLE_EQ(top.normal[1], -1.0);
  EXPECT_DOUBLE_EQ(top.velocity[0], 0.0);
  EXPECT_DOUBLE_EQ(top.velocity[1], -0.05);
  EXPECT_DOUBLE_EQ(top.kn, 0.0);  // derived by the solver
  EXPECT_EQ(bot.name, "bottom");
  EXPECT_NEAR(bot.point[1], -0.05005, 1e-15);
  EXPECT_DOUBLE_EQ(bot.normal[1], 1.0);
  EXPECT_DOUBLE_EQ(bot.velocity[1], 0.05);

  EXPECT_DOUBLE_EQ(c.local_damping, 0.7);
  EXPECT_DOUBLE_EQ(c.mass_damping, 0.0);
  // Platens close by 0.8 mm at 2 x 0.05 m/s.
  EXPECT_NEAR(c.end_time, 8e-3, 1e-15);
  EXPECT_NEAR((top.velocity[1] - bot.velocity[1]) * c.end_time, -0.8e-3, 1e-15);
  EXPECT_EQ(c.stop_platen, "top");
  EXPECT_DOUBLE_EQ(c.stop_drop_fraction, 0.7);
  EXPECT_NEAR(c.history_interval, 8e-3 / 400, 1e-18);
  EXPECT_NEAR(c.snapshot_interval, 8e-3 / 8, 1e-18);
  EXPECT_DOUBLE_EQ(c.safety_factor, 0.5);
  EXPECT_TRUE(c.velocity_bcs.empty());

  // resolved: expressions evaluated, defaults filled in
  ASSERT_TRUE(c.resolved.is_object());
  EXPECT_TRUE(c.resolved["time"]["end_time"].is_number());
  EXPECT_NEAR(c.resolved["time"]["end_time"].get<double>(), 8e-3, 1e-15);
  EXPECT_EQ(c.resolved["time"]["max_steps"], 0);
  EXPECT_EQ(c.resolved["time"]["dt"], 0.0);
  EXPECT_EQ(c.resolved["boundary"]["gravity"], json::array({0.0, 0.0}));
}

// The case's default (issue 23): the paper's disc and parameters, its loaded diameter meshed as
// element edges, padded platens (normal stiffness 1e12 Pa/m per area), each platen at 0.1 m/s for
// its first 0.26 mm (about 60 % of the peak load) and at 0.0125 m/s after it, local damping 0.1,
// closure 1.6 mm, stop at a drop of 30 % from the peak.
TEST(CaseExamples, BrazilianDiscDefaultHasTheDiameterAndPaddedPlatens) {
  Case c = fdem::load_case(kDisc);
  EXPECT_EQ(c.name, "brazilian_disc");
  EXPECT_DOUBLE_EQ(c.mesh.element_size, 0.003);
  EXPECT_DOUBLE_EQ(c.mesh.diameter[0], 0.0);
  EXPECT_DOUBLE_EQ(c.mesh.diameter[1], 1.0);
  ASSERT_EQ(c.platens.size(), 2u);
  for (const auto& p : c.platens) EXPECT_DOUBLE_EQ(p.kn, 1e12);
  EXPECT_DOUBLE_EQ(c.platens[0].velocity[1], -0.1);
  EXPECT_DOUBLE_EQ(c.platens[1].velocity[1], 0.1);
  for (const auto& p : c.platens) {
    EXPECT_TRUE(p.has_change);
    EXPECT_NEAR(p.change_time, 2.6e-3, 1e-15);
    EXPECT_DOUBLE_EQ(std::fabs(p.change_velocity[1]), 0.0125);
    EXPECT_GT(p.change_velocity[1] * p.velocity[1], 0.0);  // same direction
  }
  EXPECT_DOUBLE_EQ(c.local_damping, 0.1);
  EXPECT_NEAR(c.end_time, 2.6e-3 + (0.8e-3 - 0.26e-3) / 0.0125, 1e-12);
  EXPECT_DOUBLE_EQ(c.stop_drop_fraction, 0.3);
  EXPECT_DOUBLE_EQ(c.interface_materials.at(0).ft, 8e6);
}

TEST(CaseExamples, BrazilianDiscRateIsOneOverride) {
  Case c = fdem::load_case(kDiscPaper, {"parameters.rate=0.001"});  // the paper's 1 mm/s
  EXPECT_DOUBLE_EQ(c.platens[0].velocity[1], -0.001);
  EXPECT_DOUBLE_EQ(c.platens[1].velocity[1], 0.001);
  EXPECT_NEAR(c.end_time, 0.4, 1e-12);
  EXPECT_NEAR(c.history_interval, 0.4 / 400, 1e-15);
}

TEST(CaseExamples, BarParses) {
  Case c = fdem::load_case(kBar);
  EXPECT_EQ(c.name, "bar");
  EXPECT_EQ(c.mesh.kind, "rectangle");
  EXPECT_EQ(c.mesh.cells[0], 10);
  EXPECT_EQ(c.mesh.cells[1], 1);
  EXPECT_DOUBLE_EQ(c.mesh.size[0], 0.1);
  EXPECT_DOUBLE_EQ(c.mesh.size[1], 0.01);
  ASSERT_EQ(c.velocity_bcs.size(), 2u);
  EXPECT_EQ(c.velocity_bcs[0].set, "left");
  EXPECT_TRUE(c.velocity_bcs[0].active[0] && c.velocity_bcs[0].active[1]);
  EXPECT_FALSE(c.velocity_bcs[0].active[2]);
  EXPECT_DOUBLE_EQ(c.velocity_bcs[0].velocity[0], 0.0);
  EXPECT_EQ(c.velocity_bcs[1].set, "right");
  EXPECT_TRUE(c.velocity_bcs[1].active[0]);
  EXPECT_FALSE(c.velocity_bcs[1].active[1]);
  EXPECT_DOUBLE_EQ(c.velocity_bcs[1].velocity[0], 0.05);
  EXPECT_DOUBLE_EQ(c.velocity_bcs[1].ramp_time, 1e-4);
  EXPECT_NEAR(c.history_interval, 2e-5, 1e-18);
  EXPECT_DOUBLE_EQ(c.snapshot_interval, 0.0);
  EXPECT_TRUE(c.platens.empty());
}

TEST(CaseExamples, ResolvedIsAValidCaseWithTheSameValues) {
  for (const auto& path : {kDisc, kBar}) {
    Case a = fdem::load_case(path);
    Case b = fdem::parse_case(a.resolved, path);
    EXPECT_EQ(b.resolved, a.resolved) << path;  // fixed point: all defaults already present
    EXPECT_DOUBLE_EQ(b.end_time, a.end_time);
    EXPECT_DOUBLE_EQ(b.history_interval, a.history_interval);
    EXPECT_EQ(b.platens.size(), a.platens.size());
    EXPECT_EQ(b.velocity_bcs.size(), a.velocity_bcs.size());
  }
}

TEST(CaseDefaults, FilledAndApplied) {
  json d = base_doc();
  d.erase("analysis");
  d.erase("damping");
  d.erase("output");
  d["interface_materials"]["cif"].erase("eta");
  d["boundary"]["fixed"][0].erase("components");
  Case c = fdem::parse_case(d, "test.json");
  EXPECT_FALSE(c.plane_stress);
  EXPECT_DOUBLE_EQ(c.thickness, 1.0);
  EXPECT_DOUBLE_EQ(c.local_damping, 0.0);
  EXPECT_DOUBLE_EQ(c.interface_materials[0].eta, 2.0);
  EXPECT_TRUE(c.velocity_bcs[0].active[0] && c.velocity_bcs[0].active[1]);
  EXPECT_NEAR(c.history_interval, 2e-3 / 200, 1e-18);
  EXPECT_DOUBLE_EQ(c.safety_factor, 0.5);
  EXPECT_EQ(c.check_interval, 100);
  EXPECT_EQ(c.max_steps, 0);
  // platen normal is normalised
  EXPECT_DOUBLE_EQ(c.platens[0].normal[1], -1.0);
  EXPECT_DOUBLE_EQ(c.platens[0].friction, 0.3);
  EXPECT_EQ(c.resolved["analysis"]["plane"], "strain");
  EXPECT_EQ(c.resolved["boundary"]["fixed"][0]["components"], "xy");
  EXPECT_EQ(c.resolved["damping"]["local"], 0.0);
  EXPECT_EQ(c.resolved["output"]["history_rows"], 200);
  EXPECT_EQ(c.resolved["output"]["snapshot_count"], 0);
  // name defaults to the file's stem (or its folder for case.json)
  d.erase("name");
  EXPECT_EQ(fdem::parse_case(d, "dir/beam.json").name, "beam");
  EXPECT_EQ(fdem::parse_case(d, "dir/beam/case.json").name, "beam");
  // no "fracture": no interfaces
  d.erase("fracture");
  Case nf = fdem::parse_case(d, "test.json");
  EXPECT_EQ(nf.fracture_material, -1);
  EXPECT_TRUE(nf.fracturable_regions.empty());
}

TEST(CaseDefaults, ThreeDimensionalBox) {
  json d = base_doc();
  d["dimension"] = 3;
  d.erase("analysis");
  d["mesh"] = {{"generator", "box"}, {"size", {1, 1, 1}}, {"element_size", 0.1}};
  d["boundary"] = json::parse(R"({"fixed": [{"set": "zmin", "components": "z"}], "gravity": [0, 0, -9.81]})");
  d["platens"][0]["point"] = {0, 0, 1};
  d["platens"][0]["normal"] = {0, 0, -1};
  d["platens"][0]["velocity"] = {0, 0, -0.1};
  Case c = fdem::parse_case(d, "test.json");
  EXPECT_EQ(c.dim, 3);
  EXPECT_EQ(c.mesh.kind, "box");
  EXPECT_DOUBLE_EQ(c.mesh.element_size, 0.1);
  EXPECT_EQ(c.mesh.cells[0], 0);
  EXPECT_DOUBLE_EQ(c.gravity[2], -9.81);
  EXPECT_FALSE(c.velocity_bcs[0].active[0]);
  EXPECT_TRUE(c.velocity_bcs[0].active[2]);
  EXPECT_EQ(c.resolved.count("analysis"), 0u);
  // 2D-only section in 3D
  d["analysis"] = {{"plane", "stress"}};
  EXPECT_HAS(error_of(d), "analysis");
}

// ---------------------------------------------------------------------------------------------

TEST(CaseErrors, UnknownKeyNamesPathAndNearestName) {
  struct Item {
    std::string pointer, key_path, suggestion;
  };
  const std::vector<Item> items = {
      {"/materials/concrete/Young", "materials.concrete.Young", "did you mean 'E'?"},
      {"/materials/concrete/densty", "materials.concrete.densty", "did you mean 'density'?"},
      {"/interface_materials/cif/phi", "interface_materials.cif.phi", "did you mean 'phi_deg'?"},
      {"/dimensoin", "dimensoin", "did you mean 'dimension'?"},
      {"/time/end_tme", "time.end_tme", "did you mean 'end_time'?"},
      {"/damping/Local", "damping.Local", "did you mean 'local'?"},
      {"/platens/0/frction", "platens.0.frction", "did you mean 'friction'?"},
      {"/boundary/fixed/0/componets", "boundary.fixed.0.componets", "did you mean 'components'?"},
      {"/mesh/centre", "mesh.centre", "allowed keys in 'mesh'"},
  };
  for (const auto& it : items) {
    json d = base_doc();
    d[json::json_pointer(it.pointer)] = 1;
    std::string msg = error_of(d);
    EXPECT_HAS(msg, "test.json: unknown key '" + it.key_path + "'");
    EXPECT_HAS(msg, it.suggestion);
  }
  // no nonsense suggestion for a far-off name, but the allowed keys are listed
  json d = base_doc();
  d["damping"]["qqqqqqqqq"] = 1;
  std::string msg = error_of(d);
  EXPECT_EQ(msg.find("did you mean"), std::string::npos) << msg;
  EXPECT_HAS(msg, "local, mass_proportional");
}

TEST(CaseErrors, MissingRequiredKeyNamesPath) {
  const std::vector<std::pair<std::string, std::string>> items = {
      {"/materials/concrete/E", "materials.concrete.E"},
      {"/materials/concrete/density", "materials.concrete.density"},
      {"/interface_materials/cif/Gsc", "interface_materials.cif.Gsc"},
      {"/time/end_time", "time.end_time"},
      {"/time", "time"},
      {"/dimension", "dimension"},
      {"/mesh", "mesh"},
      {"/mesh/size", "mesh.size"},
      {"/materials", "materials"},
      {"/regions", "regions"},
      {"/fracture/interface_material", "fracture.interface_material"},
      {"/boundary/velocity/0/velocity", "boundary.velocity.0.velocity"},
      {"/boundary/fixed/0/set", "boundary.fixed.0.set"},
      {"/platens/0/normal", "platens.0.normal"},
      {"/time/stop/drop_fraction", "time.stop.drop_fraction"},
  };
  for (const auto& [pointer, path] : items) {
    json d = base_doc();
    json::json_pointer ptr(pointer);
    d[ptr.parent_pointer()].erase(ptr.back());
    std::string msg = error_of(d);
    EXPECT_HAS(msg, "test.json: " + path + ": ");
    EXPECT_HAS(msg, "missing");
  }
}

TEST(CaseErrors, OutOfRangeNamesPathValueAndRange) {
  struct Item {
    std::string pointer;
    json value;
    std::string path, allowed;
  };
  const std::vector<Item> items = {
      {"/materials/concrete/E", -3e9, "materials.concrete.E", "allowed: > 0"},
      {"/materials/concrete/E", 0, "materials.concrete.E", "allowed: > 0"},
      {"/materials/concrete/density", 0, "materials.concrete.density", "> 0"},
      {"/materials/concrete/nu", 0.5, "materials.concrete.nu", "> -1 and < 0.5"},
      {"/materials/concrete/nu", -1, "materials.concrete.nu", "> -1 and < 0.5"},
      {"/interface_materials/cif/kn", 0, "interface_materials.cif.kn", "> 0"},
      {"/interface_materials/cif/ks", -1, "interface_materials.cif.ks", "> 0"},
      {"/interface_materials/cif/ft", -1, "interface_materials.cif.ft", ">= 0"},
      {"/interface_materials/cif/c", -1, "interface_materials.cif.c", ">= 0"},
      {"/interface_materials/cif/phi_deg", 90, "interface_materials.cif.phi_deg", ">= 0 and < 90"},
      {"/interface_materials/cif/phi_deg", -5, "interface_materials.cif.phi_deg", ">= 0 and < 90"},
      {"/interface_materials/cif/Gnc", 0, "interface_materials.cif.Gnc", "> 0"},
      {"/interface_materials/cif/Gsc", -2, "interface_materials.cif.Gsc", "> 0"},
      {"/interface_materials/cif/eta", 0, "interface_materials.cif.eta", "> 0"},
      {"/damping/local", 1.0, "damping.local", ">= 0 and < 1"},
      {"/damping/local", -0.1, "damping.local", ">= 0 and < 1"},
      {"/damping/mass_proportional", -1, "damping.mass_proportional", ">= 0"},
      {"/parallel/rebalance_above", 0, "parallel.rebalance_above", ">= 0.01 and <= 1000"},
      {"/parallel/rebalance_above", 1e4, "parallel.rebalance_above", ">= 0.01 and <= 1000"},
      {"/parallel/work_model/element_ns", 0, "parallel.work_model.element_ns", "> 0 and <= 100000"},
      {"/parallel/work_model/interface_ns", -3, "parallel.work_model.interface_ns", "> 0 and <= 100000"},
      {"/parallel/work_model/node_ns", 1e6, "parallel.work_model.node_ns", "> 0 and <= 100000"},
      {"/parallel/work_model/contact_unit_ns", 0, "parallel.work_model.contact_unit_ns", "> 0 and <= 100000"},
      {"/time/safety_factor", 0, "time.safety_factor", "> 0 and <= 2"},
      {"/time/safety_factor", 2.5, "time.safety_factor", "> 0 and <= 2"},
      {"/time/end_time", 0, "time.end_time", "> 0"},
      {"/time/dt", -1e-6, "time.dt", ">= 0"},
      {"/time/max_steps", -1, "time.max_steps", ">= 0"},
      {"/time/check_interval", 0, "time.check_interval", ">= 1"},
      {"/time/stop/drop_fraction", 1, "time.stop.drop_fraction", "> 0 and < 1"},
      {"/analysis/thickness", 0, "analysis.thickness", "> 0"},
      {"/mesh/size/1", -0.01, "mesh.size.1", "> 0"},
      {"/mesh/cells/0", 0, "mesh.cells.0", ">= 1"},
      {"/mesh/element_size", 0, "mesh.element_size", "> 0"},
      {"/platens/0/friction", -0.1, "platens.0.friction", ">= 0"},
      {"/platens/0/kn", -1, "platens.0.kn", ">= 0"},
      {"/platens/0/cohesion", -1, "platens.0.cohesion", ">= 0"},
      {"/boundary/velocity/0/ramp_time", -1, "boundary.velocity.0.ramp_time", ">= 0"},
      {"/boundary/point_loads/0/ramp_time", -1, "boundary.point_loads.0.ramp_time", ">= 0"},
      {"/output/history_rows", 0, "output.history_rows", ">= 1"},
      {"/dimension", 4, "dimension", "2 to 3"},
  };
  for (const auto& it : items) {
    json d = base_doc();
    d[json::json_pointer(it.pointer)] = it.value;
    std::string msg = error_of(d);
    EXPECT_HAS(msg, "test.json: " + it.path + ": ");
    EXPECT_HAS(msg, it.allowed);
    EXPECT_HAS(msg, "out of range");
  }
  // the value itself is in the message
  json d = base_doc();
  d["materials"]["concrete"]["E"] = -3e9;
  EXPECT_HAS(error_of(d), "value -3e+09");

  // disc generator: radius and element size
  d = base_doc();
  d["mesh"] = {{"generator", "disc"}, {"radius", 0}, {"element_size", 0.001}};
  EXPECT_HAS(error_of(d), "mesh.radius");
  d["mesh"] = {{"generator", "disc"}, {"radius", 0.05}, {"element_size", -1}};
  EXPECT_HAS(error_of(d), "mesh.element_size");
  d["mesh"] = {{"generator", "disc"}, {"radius", 0.05}, {"element_size", 0.1}};
  EXPECT_HAS(error_of(d), "mesh.element_size");
  // embedded diameter: a zero direction, a wrong length; the rectangle does not take the key
  d["mesh"] = {
      {"generator", "disc"}, {"radius", 0.05}, {"element_size", 0.01}, {"embedded_diameter", {0, 0}}};
  EXPECT_HAS(error_of(d), "mesh.embedded_diameter: the direction is zero");
  d["mesh"]["embedded_diameter"] = {1};
  EXPECT_HAS(error_of(d), "mesh.embedded_diameter");
  d["mesh"] = {
      {"generator", "rectangle"}, {"size", {1, 1}}, {"cells", {2, 2}}, {"embedded_diameter", {0, 1}}};
  EXPECT_HAS(error_of(d), "embedded_diameter");
  // symmetric: a boolean, and only with an embedded diameter
  d["mesh"] = {{"generator", "disc"}, {"radius", 0.05}, {"element_size", 0.01}, {"symmetric", true}};
  EXPECT_HAS(error_of(d), "mesh.symmetric: a mesh symmetric about a diameter needs mesh.embedded_diameter");
  d["mesh"]["embedded_diameter"] = {0, 1};
  d["mesh"]["symmetric"] = 1;
  EXPECT_HAS(error_of(d), "mesh.symmetric: must be true or false");
  // zero platen normal
  d = base_doc();
  d["platens"][0]["normal"] = {0, 0};
  EXPECT_HAS(error_of(d), "platens.0.normal");
}

TEST(CaseErrors, WrongTypes) {
  json d = base_doc();
  d["materials"]["concrete"]["E"] = "33e9";
  std::string msg = error_of(d);
  EXPECT_HAS(msg, "materials.concrete.E");
  EXPECT_HAS(msg, "expected a number, got a string");

  d = base_doc();
  d["damping"]["local"] = true;
  EXPECT_HAS(error_of(d), "damping.local: expected a number, got a boolean");

  d = base_doc();
  d["materials"] = json::array();
  EXPECT_HAS(error_of(d), "materials: expected an object, got an array");

  d = base_doc();
  d["boundary"]["fixed"][0]["components"] = 3;
  EXPECT_HAS(error_of(d), "boundary.fixed.0.components: expected a string");

  d = base_doc();
  d["time"]["max_steps"] = 2.5;
  EXPECT_HAS(error_of(d), "time.max_steps: expected an integer");

  d = base_doc();
  d["boundary"]["fixed"] = {{"set", "left"}};  // object instead of array
  EXPECT_HAS(error_of(d), "boundary.fixed: expected an array");

  d = base_doc();
  d["analysis"]["plane"] = "strainn";
  EXPECT_HAS(error_of(d), "analysis.plane");

  d = base_doc();
  d["precision"] = "single";
  msg = error_of(d);
  EXPECT_HAS(msg, "precision: 'single' is not allowed (allowed: \"double\", \"mixed\")");
  d = base_doc();
  d["precision"] = 32;
  EXPECT_HAS(error_of(d), "precision: expected a string");
  d = base_doc();
  EXPECT_FALSE(fdem::parse_case(d, "test.json", {}).mixed_precision);
  d["precision"] = "mixed";
  EXPECT_TRUE(fdem::parse_case(d, "test.json", {}).mixed_precision);

  d = base_doc();
  d["mesh"]["generator"] = "rectangel";
  msg = error_of(d);
  EXPECT_HAS(msg, "mesh.generator");
  EXPECT_HAS(msg, "did you mean 'rectangle'?");

  d = base_doc();
  d["mesh"]["generator"] = "box";  // 3D generator in 2D
  EXPECT_HAS(error_of(d), "mesh.generator");

  d = base_doc();
  d["mesh"]["file"] = "x.msh";  // both file and generator
  EXPECT_HAS(error_of(d), "mesh: give either 'file' or 'generator'");

  EXPECT_HAS(error_of(json::array()), "test.json");
}

TEST(CaseErrors, VectorsNeedDimensionComponents) {
  json d = base_doc();
  d["boundary"]["gravity"] = {0, -9.81, 0};
  std::string msg = error_of(d);
  EXPECT_HAS(msg, "boundary.gravity");
  EXPECT_HAS(msg, "expected 2 components");

  d = base_doc();
  d["platens"][0]["velocity"] = {0.1};
  EXPECT_HAS(error_of(d), "platens.0.velocity");

  d = base_doc();
  d["mesh"]["cells"] = {10, 1, 1};
  EXPECT_HAS(error_of(d), "mesh.cells");

  d = base_doc();
  d["boundary"]["velocity"][0]["velocity"] = {0.05, "fast"};
  EXPECT_HAS(error_of(d), "boundary.velocity.0.velocity.1: expected a number");
}

TEST(CaseErrors, Components) {
  for (const char* bad : {"xz", "xx", "", "q", "X"}) {
    json d = base_doc();
    d["boundary"]["fixed"][0]["components"] = bad;
    std::string msg = error_of(d);
    EXPECT_HAS(msg, "boundary.fixed.0.components");
    EXPECT_HAS(msg, "allowed: letters from 'xy'");
  }
  // a velocity on a component that is not prescribed is a mistake
  json d = base_doc();
  d["boundary"]["velocity"][0]["velocity"] = {0.05, 1.0};
  EXPECT_HAS(error_of(d), "boundary.velocity.0.velocity.1");
  // "xyz" is fine in 3D only
  d = base_doc();
  d["boundary"]["fixed"][0]["components"] = "yx";
  EXPECT_EQ(error_of(d), "<no error>");
}

TEST(CaseErrors, ReferencesToUndefinedNames) {
  json d = base_doc();
  d["regions"]["body"] = "concret";
  std::string msg = error_of(d);
  EXPECT_HAS(msg, "regions.body");
  EXPECT_HAS(msg, "did you mean 'concrete'?");

  d = base_doc();
  d["fracture"]["interface_material"] = "cf";
  EXPECT_HAS(error_of(d), "fracture.interface_material");

  d = base_doc();
  d["fracture"]["regions"] = {"bdy"};
  msg = error_of(d);
  EXPECT_HAS(msg, "fracture.regions.0");
  EXPECT_HAS(msg, "'body'");

  d = base_doc();
  d["time"]["stop"]["platen"] = "tpo";
  msg = error_of(d);
  EXPECT_HAS(msg, "time.stop.platen");
  EXPECT_HAS(msg, "did you mean 'top'?");

  d = base_doc();
  d["boundary"]["initial_velocity"][0]["region"] = "rock";
  EXPECT_HAS(error_of(d), "boundary.initial_velocity.0.region");

  d = base_doc();
  d["platens"].push_back(d["platens"][0]);
  EXPECT_HAS(error_of(d), "platens.1.name");
}

TEST(CaseErrors, NonFiniteNumbers) {
  json d = base_doc();
  d["time"]["end_time"] = std::numeric_limits<double>::infinity();
  std::string msg = error_of(d);
  EXPECT_HAS(msg, "time.end_time");
  EXPECT_HAS(msg, "finite");

  TempDir tmp;
  std::string text = base_doc().dump(2);
  text.replace(text.find("\"density\": 2500"), 15, "\"density\": 1e400");
  std::string path = tmp.write("huge.json", text);
  msg = load_error(path);
  EXPECT_HAS(msg, path);
  EXPECT_HAS(msg, "1e400");

  msg = error_of(base_doc(), {"time.end_time=1e400"});
  EXPECT_HAS(msg, "time.end_time");
  EXPECT_HAS(msg, "finite");
}

TEST(CaseErrors, FilesSyntaxAndDuplicates) {
  std::string msg = load_error("/nonexistent/folder/case.json");
  EXPECT_HAS(msg, "/nonexistent/folder/case.json");
  EXPECT_HAS(msg, "does not exist");

  TempDir tmp;
  std::string path = tmp.write("bad.json", "{\n  \"name\": \"x\",\n  \"dimension\": 2,,\n}\n");
  msg = load_error(path);
  EXPECT_HAS(msg, path);
  EXPECT_HAS(msg, "line 3");
  EXPECT_HAS(msg, "invalid JSON");

  path = tmp.write("dup.json", R"({"materials": {"a": {"E": 1, "E": 2}}})");
  msg = load_error(path);
  EXPECT_HAS(msg, "materials.a.E");
  EXPECT_HAS(msg, "duplicate key");

  // comments are allowed
  std::string text = base_doc().dump(2);
  text.insert(1, "\n  // a comment\n  /* another */\n");
  path = tmp.write("comments.json", text);
  EXPECT_EQ(load_error(path), "<no error>");
}

TEST(CaseErrors, MeshFileIsResolvedAgainstTheCaseFolder) {
  TempDir tmp;
  fs::create_directories(tmp.path / "sub");
  json d = base_doc();
  d.erase("name");
  d["mesh"] = {{"file", "beam.msh"}};
  std::string path = tmp.write("sub/case.json", d.dump());
  std::string msg = load_error(path);
  EXPECT_HAS(msg, "mesh.file");
  EXPECT_HAS(msg, "beam.msh");
  EXPECT_HAS(msg, "does not exist");

  tmp.write("sub/beam.msh", "$MeshFormat\n");
  Case c = fdem::load_case(path);
  EXPECT_EQ(c.mesh.kind, "file");
  EXPECT_TRUE(fs::equivalent(c.mesh.file, tmp.path / "sub" / "beam.msh"));
  EXPECT_TRUE(fs::path(c.resolved["mesh"]["file"].get<std::string>()).is_absolute());
  EXPECT_EQ(c.name, "sub");

  d["mesh"] = {{"file", "beam.msh"}, {"region", "x"}};  // generator-only key
  EXPECT_HAS(error_of(d), "unknown key 'mesh.region'");
}

// ---------------------------------------------------------------------------------------------

TEST(CaseOverrides, NestedArrayNumericAndString) {
  Case c = fdem::parse_case(base_doc(), "test.json",
                            {"materials.concrete.E=4e10", "platens.0.velocity.1=-0.2",
                             "boundary.velocity.0.velocity=[0.1, 0]", "analysis.plane=strain",
                             "name=renamed", "time.stop.drop_fraction=0.25"});
  EXPECT_DOUBLE_EQ(c.materials[0].E, 4e10);
  EXPECT_DOUBLE_EQ(c.platens[0].velocity[1], -0.2);
  EXPECT_DOUBLE_EQ(c.velocity_bcs[1].velocity[0], 0.1);
  EXPECT_FALSE(c.plane_stress);
  EXPECT_EQ(c.name, "renamed");
  EXPECT_DOUBLE_EQ(c.stop_drop_fraction, 0.25);
  EXPECT_EQ(c.resolved["materials"]["concrete"]["E"], 4e10);
}

// damping.change: the damping from a given time on (slope: settle at 0.7, then let it move), and
// fracture.strength_reduction: its keys, defaults and ranges.
TEST(CaseDamping, ChangeAtATimeAndStrengthReduction) {
  Case c = fdem::parse_case(base_doc(), "test.json", {R"(damping.change={"time": 0.5, "local": 0.05})"});
  EXPECT_DOUBLE_EQ(c.damping_change_time, 0.5);
  EXPECT_DOUBLE_EQ(c.damping_change_local, 0.05);
  EXPECT_DOUBLE_EQ(c.damping_change_mass, 0.0);
  EXPECT_EQ(c.resolved["damping"]["change"]["mass_proportional"], 0.0);
  c = fdem::parse_case(base_doc(), "test.json");
  EXPECT_LT(c.damping_change_time, 0);
  EXPECT_HAS(error_of(base_doc(), {R"(damping.change={"local": 0.1})"}), "damping.change.time");
  EXPECT_HAS(error_of(base_doc(), {R"(damping.change={"time": 1, "local": 1.0})"}), "damping.change.local");
  EXPECT_HAS(error_of(base_doc(), {R"(damping.change={"time": 1, "loc": 0.1})"}), "did you mean 'local'?");
  c = fdem::parse_case(base_doc(), "test.json",
                       {R"(fracture.strength_reduction={"initial": 0.5, "start_time": 0.2, "rate": 2})"});
  EXPECT_DOUBLE_EQ(c.srf_initial, 0.5);
  EXPECT_DOUBLE_EQ(c.srf_start, 0.2);
  EXPECT_DOUBLE_EQ(c.srf_rate, 2);
  EXPECT_HAS(error_of(base_doc(), {R"(fracture.strength_reduction={"initial": 0})"}),
             "fracture.strength_reduction.initial");
  EXPECT_HAS(error_of(base_doc(), {R"(fracture.strength_reduction={"rate": -1})"}),
             "fracture.strength_reduction.rate");
}

TEST(CaseOverrides, NewKeysAndRemovals) {
  // a new leaf under an existing object
  Case c = fdem::parse_case(base_doc(), "test.json", {"damping.mass_proportional=5", "time.dt=1e-8"});
  EXPECT_DOUBLE_EQ(c.mass_damping, 5);
  EXPECT_DOUBLE_EQ(c.dt, 1e-8);
  // a typo in a new leaf is caught by the unknown-key check, with the nearest name
  std::string msg = error_of(base_doc(), {"damping.locl=0.5"});
  EXPECT_HAS(msg, "damping.locl");
  EXPECT_HAS(msg, "did you mean 'local'?");
  // null removes an optional key
  c = fdem::parse_case(base_doc(), "test.json", {"fracture=null", "time.stop=null"});
  EXPECT_EQ(c.fracture_material, -1);
  EXPECT_TRUE(c.stop_platen.empty());
  // a whole object as a value
  c = fdem::parse_case(base_doc(), "test.json", {R"(boundary={"gravity": [0, -9.81]})"});
  EXPECT_DOUBLE_EQ(c.gravity[1], -9.81);
  EXPECT_TRUE(c.velocity_bcs.empty());
  // overridden value out of range: same message as in the file
  EXPECT_HAS(error_of(base_doc(), {"materials.concrete.nu=0.6"}), "materials.concrete.nu");
  // string where a number is expected
  EXPECT_HAS(error_of(base_doc(), {"time.end_time=soon"}), "expected a number, got a string");
}

TEST(CaseOverrides, BadPaths) {
  std::string msg = error_of(base_doc(), {"materials.granite.E=1"});
  EXPECT_HAS(msg, "--set 'materials.granite.E=1'");
  EXPECT_HAS(msg, "'materials.granite' does not exist");

  msg = error_of(base_doc(), {"platens.3.kn=1"});
  EXPECT_HAS(msg, "platens");
  EXPECT_HAS(msg, "index 3");

  msg = error_of(base_doc(), {"platens.top.kn=1"});
  EXPECT_HAS(msg, "not an index");

  msg = error_of(base_doc(), {"time.end_time.x=1"});
  EXPECT_HAS(msg, "time.end_time");

  msg = error_of(base_doc(), {"time.end_time"});
  EXPECT_HAS(msg, "--set 'time.end_time'");
  EXPECT_HAS(msg, "key.path=value");

  EXPECT_HAS(error_of(base_doc(), {"time..end_time=1"}), "empty key");
  EXPECT_HAS(error_of(base_doc(), {"=1"}), "empty key");

  msg = error_of(base_doc(), {"tme.end_time=1"});
  EXPECT_HAS(msg, "'tme' does not exist");
  EXPECT_HAS(msg, "did you mean 'time'?");
}

TEST(CaseParameters, Expressions) {
  json d = base_doc();
  d["parameters"] = {{"rate", 0.05}, {"len", 0.1}};
  d["boundary"]["velocity"][0]["velocity"] = {"=rate * 2", 0};
  d["time"]["end_time"] = "=0.5 * len / (2*rate) - -1e-3";
  d["platens"][0]["point"] = {0, "=-(len + 0.01)"};
  d["interface_materials"]["cif"]["phi_deg"] = "=180 / pi * 0.5";
  Case c = fdem::parse_case(d, "test.json");
  EXPECT_DOUBLE_EQ(c.velocity_bcs[1].velocity[0], 0.1);
  EXPECT_NEAR(c.end_time, 0.5 * 0.1 / 0.1 + 1e-3, 1e-15);
  EXPECT_NEAR(c.platens[0].point[1], -0.11, 1e-15);
  EXPECT_NEAR(c.interface_materials[0].phi, 0.5, 1e-15);
  EXPECT_EQ(c.resolved["parameters"]["rate"], 0.05);
  EXPECT_TRUE(c.resolved["time"]["end_time"].is_number());

  c = fdem::parse_case(d, "test.json", {"parameters.rate=0.5"});
  EXPECT_DOUBLE_EQ(c.velocity_bcs[1].velocity[0], 1.0);

  json e = d;
  e["time"]["end_time"] = "=len / rat";
  std::string msg = error_of(e);
  EXPECT_HAS(msg, "time.end_time");
  EXPECT_HAS(msg, "unknown parameter 'rat'; did you mean 'rate'?");

  e = d;
  e["time"]["end_time"] = "=len / 0";
  EXPECT_HAS(error_of(e), "not finite");

  e = d;
  e["time"]["end_time"] = "=len / (rate";
  EXPECT_HAS(error_of(e), "missing ')'");

  e = d;
  e["parameters"]["rate"] = "fast";
  EXPECT_HAS(error_of(e), "parameters.rate: expected a number");
}

TEST(CaseParameters, ExpressionFunctions) {
  json d = base_doc();
  d["parameters"] = {{"E", 30e9}, {"rho", 2500}, {"r", 0.05}};
  d["time"]["end_time"] = "=sqrt(E / rho) * 1e-6";
  d["platens"][0]["point"] = {"=r * cos(pi / 3)", "=max(r, 0.02) + pow(2, -3) * abs(-0.08)"};
  d["interface_materials"]["cif"]["phi_deg"] = "=atan2(1, 1) * 180 / pi + min(log(exp(2)), log10(1000))";
  Case c = fdem::parse_case(d, "test.json");
  EXPECT_NEAR(c.end_time, std::sqrt(30e9 / 2500) * 1e-6, 1e-15);
  EXPECT_NEAR(c.platens[0].point[0], 0.025, 1e-15);
  EXPECT_NEAR(c.platens[0].point[1], 0.05 + 0.01, 1e-15);
  EXPECT_NEAR(c.interface_materials[0].phi, (45.0 + 2.0) * kPi / 180, 1e-12);

  json e = d;
  e["time"]["end_time"] = "=sqrt(-E)";
  std::string msg = error_of(e);
  EXPECT_HAS(msg, "time.end_time");
  EXPECT_HAS(msg, "sqrt is not defined there");
  e["time"]["end_time"] = "=sqr(E)";
  EXPECT_HAS(error_of(e), "unknown function 'sqr'; did you mean 'sqrt'?");
  e["time"]["end_time"] = "=pow(E)";
  EXPECT_HAS(error_of(e), "pow takes two arguments (got 1)");
  e["time"]["end_time"] = "=sin(1, 2)";
  EXPECT_HAS(error_of(e), "sin takes one argument (got 2)");
  e["time"]["end_time"] = "=sqrt(E";
  EXPECT_HAS(error_of(e), "missing ')' after the arguments of sqrt");
}

// ---------------------------------------------------------------------------------------------

fdem::HostMesh tiny_mesh(std::vector<std::string> regions, std::vector<std::string> sets) {
  fdem::HostMesh m;
  m.dim = 2;
  m.X = {0, 0, 1, 0, 0, 1};
  m.elems = {0, 1, 2};
  m.elem_region = {0};
  m.region_names = std::move(regions);
  for (const auto& s : sets) m.node_sets[s] = {0};
  m.node_origin = {0, 1, 2};
  return m;
}

TEST(CaseMeshCheck, NamesMustExistInTheMesh) {
  Case c = fdem::parse_case(base_doc(), "test.json");
  EXPECT_NO_THROW(fdem::check_case_against_mesh(c, tiny_mesh({"body"}, {"left", "right", "all"})));

  auto msg_of = [&](const Case& cs, const fdem::HostMesh& m) -> std::string {
    try {
      fdem::check_case_against_mesh(cs, m);
    } catch (const InputError& e) {
      return e.what();
    }
    return "<no error>";
  };
  // region in the case, not in the mesh
  std::string msg = msg_of(c, tiny_mesh({"bodyy"}, {"left", "right"}));
  EXPECT_HAS(msg, "test.json: regions.body");
  EXPECT_HAS(msg, "'bodyy'");
  // mesh region without a material
  msg = msg_of(c, tiny_mesh({"body", "inclusion"}, {"left", "right"}));
  EXPECT_HAS(msg, "'inclusion' has no material");
  // node sets
  msg = msg_of(c, tiny_mesh({"body"}, {"left", "xmax"}));
  EXPECT_HAS(msg, "boundary.velocity.0.set");
  EXPECT_HAS(msg, "'right'");
  EXPECT_HAS(msg, "'left', 'xmax'");
  msg = msg_of(c, tiny_mesh({"body"}, {"xmin", "right"}));
  EXPECT_HAS(msg, "boundary.fixed.0.set");
  // dimension mismatch
  fdem::HostMesh m3 = tiny_mesh({"body"}, {"left", "right"});
  m3.dim = 3;
  EXPECT_HAS(msg_of(c, m3), "dimension");
  // initial velocity region "all" is always fine
  json d = base_doc();
  d["boundary"]["initial_velocity"][0]["region"] = "all";
  Case a = fdem::parse_case(d, "test.json");
  EXPECT_NO_THROW(fdem::check_case_against_mesh(a, tiny_mesh({"body"}, {"left", "right"})));
}

}  // namespace

namespace {

// The example cases' names (regions, node sets) match what their mesh generators make.
TEST(CaseMeshCheck, ExampleCasesMatchTheirGeneratedMeshes) {
  for (const auto& path : {kBar, kDisc}) {
    Case c = fdem::load_case(path);
    fdem::HostMesh m = fdem::build_mesh(c.mesh, c.dim);
    EXPECT_GT(m.num_elems(), 0) << path;
    EXPECT_NO_THROW(fdem::check_case_against_mesh(c, m)) << path;
  }
}

// A run writes its case.json with the values it derived (docs/case-format.md): the platen and
// contact stiffness a case leaves unset are the rule's (the fracture interface material's kn and
// ks; without one, 10 E / mean element size and ks = kn / (2 (1 + nu))), and the file read again
// gives the same case.
TEST(CaseDefaults, RunCaseJsonShowsDerivedStiffness) {
  const fs::path dir = fs::temp_directory_path() / ("fdem_case_defaults_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  json frac = base_doc();
  frac["time"] = {{"end_time", 2e-3}, {"max_steps", 2}};
  json plain = frac;
  plain.erase("interface_materials");
  plain.erase("fracture");
  plain["contact"] = {{"enabled", true}};
  for (const bool fractured : {true, false}) {
    const std::string name = fractured ? "frac" : "plain";
    const std::string path = (dir / (name + ".json")).string();
    std::ofstream(path) << (fractured ? frac : plain).dump();
    fdem::RunOptions opt;
    opt.out_dir = (dir / name).string();
    opt.progress = false;
    fdem::run_case(path, opt);
    std::ifstream in(opt.out_dir + "/case.json");
    const json r = json::parse(in);

    fdem::HostMesh mesh = fdem::build_mesh(fdem::load_case(path).mesh, 2);  // as the run builds it
    fdem::reorder_for_locality(mesh);
    const double h = fdem::mesh_quality(mesh).mean_size;
    const double kn = fractured ? 6e13 : 10 * 30e9 / h;
    const double ks = fractured ? 2.5e13 : kn / (2 * (1 + 0.2));
    for (const json& j : {r["platens"][0], r["contact"]}) {
      EXPECT_DOUBLE_EQ(j["kn"].get<double>(), kn) << name;
      EXPECT_DOUBLE_EQ(j["ks"].get<double>(), ks) << name;
    }
    EXPECT_DOUBLE_EQ(r["contact"]["friction"].get<double>(), fractured ? std::tan(30 * kPi / 180) : 0.0);
    EXPECT_NEAR(r["contact"]["skin"].get<double>(), 0.02 * h, 1e-12 * h) << name;

    const Case again = fdem::load_case(opt.out_dir + "/case.json");
    EXPECT_EQ(again.platens[0].kn, r["platens"][0]["kn"].get<double>()) << name;
    EXPECT_EQ(again.contact.ks, r["contact"]["ks"].get<double>()) << name;
  }
  std::error_code ec;
  fs::remove_all(dir, ec);
}

// ---------------------------------------------------------------------------------------------
// Cross-key checks of docs/robustness.md section 4 (issue "Robustness III").

// A frictional joint (ft = c = 0) starts failed and only contact carries it: with contact switched
// off its blocks would pass through each other. Refused, naming the case file, contact.enabled, the
// material and the rule that gives it to interfaces; cohesive interfaces without contact still run.
TEST(CaseErrors, FrictionalJointWithContactOffIsRefused) {
  json d = base_doc();
  d["interface_materials"]["joint"] = {{"kn", 6e13}, {"ks", 2.5e13}, {"ft", 0}, {"c", 0}, {"phi_deg", 30}};
  d["contact"] = {{"enabled", false}};
  EXPECT_EQ(error_of(d), "<no error>");  // cif is cohesive

  d["fracture"]["interface_material"] = "joint";
  EXPECT_THROW(fdem::parse_case(d, "test.json"), InputError);
  std::string msg = error_of(d);
  EXPECT_HAS(msg, "test.json: contact.enabled: is false");
  EXPECT_HAS(msg, "interface material 'joint' (fracture.interface_material)");
  EXPECT_HAS(msg, "frictional joint");
  EXPECT_HAS(msg, "switch contact on");
  EXPECT_HAS(msg, "interface_materials.joint a tensile strength ft > 0 or a cohesion c > 0");
  // the case file is named
  TempDir tmp;
  const std::string path = tmp.write("joint.json", d.dump());
  EXPECT_THROW(fdem::load_case(path), InputError);
  EXPECT_HAS(load_error(path), path + ": contact.enabled");
  // contact on (or automatic) carries the joint
  for (const json& on : {json(true), json("auto")}) {
    json e = d;
    e["contact"]["enabled"] = on;
    EXPECT_EQ(error_of(e), "<no error>");
  }
  json e = d;
  e["contact"].erase("enabled");
  EXPECT_EQ(error_of(e), "<no error>");

  // by region, and by named surface
  d["fracture"]["interface_material"] = "cif";
  d["fracture"]["region_materials"] = {{"body", "joint"}};
  msg = error_of(d);
  EXPECT_HAS(msg, "contact.enabled");
  EXPECT_HAS(msg, "'joint' (fracture.region_materials.body)");
  d["fracture"] = {
      {"regions", json::array()}, {"interface_material", "cif"}, {"surfaces", {{"top", "joint"}}}};
  msg = error_of(d);
  EXPECT_HAS(msg, "contact.enabled");
  EXPECT_HAS(msg, "'joint' (fracture.surfaces.top)");
  // a frictional default that no interface can take (the only region has its own material)
  d["fracture"] = {
      {"regions", {"body"}}, {"interface_material", "joint"}, {"region_materials", {{"body", "cif"}}}};
  EXPECT_EQ(error_of(d), "<no error>");
}

// A --set value's objects take each key once, as a case file's do (the last one won before).
TEST(CaseOverrides, DuplicateKeyInAValueIsRefused) {
  const std::string ov = R"(contact={"kn": 1e12, "kn": 2e12})";
  EXPECT_THROW(fdem::parse_case(base_doc(), "test.json", {ov}), InputError);
  std::string msg = error_of(base_doc(), {ov});
  EXPECT_HAS(msg, "test.json: --set '" + ov + "': contact.kn: duplicate key");
  // nested, inside an array
  msg = error_of(base_doc(), {R"(boundary.fixed=[{"set": "left", "components": "x", "set": "right"}])"});
  EXPECT_HAS(msg, "boundary.fixed.0.set: duplicate key");
  // the same key in two objects is no duplicate; neither is a string value
  EXPECT_EQ(error_of(base_doc(), {R"(damping={"local": 0.5, "change": {"time": 1, "local": 0.1}})"}),
            "<no error>");
  EXPECT_EQ(error_of(base_doc(), {"name=kn_kn"}), "<no error>");
}

// Weibull factors are not truncated: `lower` and `upper` belong to the normal distribution and are
// refused with Weibull as `cov` is (they were read and ignored before).
TEST(CaseErrors, WeibullScatterRefusesLowerAndUpper) {
  json d = base_doc();
  d["fracture"]["scatter"] = {{"distribution", "weibull"}, {"modulus", 5}};
  EXPECT_EQ(error_of(d), "<no error>");
  for (const char* key : {"lower", "upper"}) {
    json e = d;
    e["fracture"]["scatter"][key] = std::string(key) == "lower" ? 0.5 : 2.0;
    EXPECT_THROW(fdem::parse_case(e, "test.json"), InputError);
    const std::string msg = error_of(e);
    EXPECT_HAS(msg, "test.json: fracture.scatter." + std::string(key) + ": is for the normal distribution");
  }
  d["fracture"]["scatter"] = {{"distribution", "normal"}, {"cov", 0.2}, {"lower", 0.5}, {"upper", 2}};
  const Case c = fdem::parse_case(d, "test.json");
  EXPECT_DOUBLE_EQ(c.scatter.lower, 0.5);
  EXPECT_DOUBLE_EQ(c.scatter.upper, 2.0);
}

// The interface law and the residual friction (docs/case-format.md, interface_materials):
// defaults, the paper's law, and the refusals naming the key and what is allowed.
TEST(CaseErrors, InterfaceLawAndResidualFriction) {
  json d = base_doc();
  Case c = fdem::parse_case(d, "test.json");
  EXPECT_FALSE(c.interface_materials[0].residual_friction);  // the paper's law, the default for now
  EXPECT_DOUBLE_EQ(c.interface_materials[0].phi_r, c.interface_materials[0].phi);  // default phi
  d["interface_materials"]["cif"]["phi_r_deg"] = 20;
  d["interface_materials"]["cif"]["law"] = "residual_friction";
  c = fdem::parse_case(d, "test.json");
  EXPECT_TRUE(c.interface_materials[0].residual_friction);
  EXPECT_NEAR(c.interface_materials[0].phi_r, 20 * M_PI / 180, 1e-15);
  json e = d;
  e["interface_materials"]["cif"]["law"] = "alfano";
  EXPECT_HAS(error_of(e), "test.json: interface_materials.cif.law: 'alfano' is not a law (allowed: \"paper\", the default, or \"residual_friction\")");
  e = d;
  e["interface_materials"]["cif"]["phi_r_deg"] = 90;
  EXPECT_HAS(error_of(e), "test.json: interface_materials.cif.phi_r_deg");
  e = d;
  e["interface_materials"]["cif"]["ft"] = 0;
  e["interface_materials"]["cif"]["c"] = 0;
  EXPECT_HAS(error_of(e), "test.json: interface_materials.cif.phi_r_deg: is for materials that soften");
}

// The same monitor twice would give history.csv the same columns twice.
TEST(CaseErrors, MonitorListedTwiceIsRefused) {
  json d = base_doc();
  d["output"]["monitors"] = {"left", "right", "left"};
  EXPECT_THROW(fdem::parse_case(d, "test.json"), InputError);
  const std::string msg = error_of(d);
  EXPECT_HAS(msg, "test.json: output.monitors.2: monitor 'left' is listed twice (also output.monitors.0)");
  EXPECT_HAS(error_of(base_doc(), {R"(output.monitors=["right", "right"])"}), "output.monitors.1");
  d["output"]["monitors"] = {"left", "right", "region.body"};
  EXPECT_EQ(fdem::parse_case(d, "test.json").monitors.size(), 3u);
}

}  // namespace
