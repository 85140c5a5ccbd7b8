// Case file reader: JSON -> overrides -> parameters -> validation -> Case. See docs/case-format.md.
// The parts: io/json_reader.hpp (JSON text with its limits, typed Reader), io/overrides.hpp
// (--set), io/expr.hpp (parameters and expressions), io/case_internal.hpp (the section readers in
// io/case_sections.cpp and io/case_conditions.cpp); this file runs them in order and checks a case
// against its mesh.
#include "io/case.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "common/error.hpp"
#include "io/case_internal.hpp"
#include "io/expr.hpp"
#include "io/json_reader.hpp"
#include "io/overrides.hpp"

namespace fdem {
namespace fs = std::filesystem;

namespace case_detail {
namespace {

std::string default_name(const std::string& source) {
  fs::path p(source);
  std::string stem = p.stem().string();
  if (stem == "case" && p.has_parent_path()) {
    std::string dir = p.parent_path().filename().string();
    if (valid_name(dir)) return dir;
  }
  return valid_name(stem) ? stem : std::string("case");
}

Case parse_impl(json doc, const std::string& source, const std::vector<std::string>& overrides,
                const fs::path& base_dir, bool check_files) {
  Reader R(source);
  if (!doc.is_object()) R.fail("", "a case file must hold one JSON object {...}, got " + describe(doc));
  check_depth(doc, source, "the case");
  for (const auto& ov : overrides) apply_override(doc, ov, R);
  strip_nulls(doc);

  // parameters and expressions
  const Params params = read_parameters(doc, R);
  substitute(doc, "", params, R);
  check_finite(doc, "", R);

  R.keys(doc, "", {"name", "description", "dimension", "parameters", "mesh", "analysis",
                   "materials", "regions", "interface_materials", "fracture", "boundary",
                   "platens", "contact", "damping", "time", "output", "parallel", "precision"});
  Case c;
  c.file = source;
  c.dim = static_cast<int>(R.integer(doc, "", "dimension", 2, 3));
  c.name = R.name(doc, "", "name", default_name(source));
  if (doc.contains("description")) R.string(doc, "", "description");
  const std::string precision = R.string(doc, "", "precision", std::string("double"));
  if (precision != "double" && precision != "mixed")
    R.fail("precision", "'" + precision + "' is not allowed (allowed: \"double\", \"mixed\")");
  c.mixed_precision = precision == "mixed";
  read_mesh(doc, c, R, base_dir, check_files);
  read_analysis(doc, c, R);
  read_materials(doc, c, R);
  read_interfaces(doc, c, R);
  read_boundary(doc, c, R);
  read_platens(doc, c, R);
  read_contact(doc, c, R);
  read_damping(doc, c, R);
  read_parallel(doc, c, R);
  read_time(doc, c, R);
  read_output(doc, c, R);
  c.resolved = std::move(doc);
  return c;
}

// InputError "<case file>: <path>: <msg>" of check_case_against_mesh.
[[noreturn]] void fail_at(const Case& c, const std::string& path, const std::string& msg) {
  const std::string src = c.file.empty() ? std::string("case") : c.file;
  throw InputError(src + ": " + path + ": " + msg);
}

// Mesh side of check_case_against_mesh: dimension and region names.
void check_mesh_regions(const Case& c, const HostMesh& mesh) {
  auto fail = [&](const std::string& path, const std::string& msg) { fail_at(c, path, msg); };
  if (mesh.dim != c.dim)
    fail("dimension", "the case has dimension " + std::to_string(c.dim) + " but the mesh is " +
                          std::to_string(mesh.dim) + "D");
  const std::vector<std::string>& regs = mesh.region_names;
  auto has_region = [&](const std::string& r) {
    return std::find(regs.begin(), regs.end(), r) != regs.end();
  };
  const std::string reg_list = "mesh regions: " + quoted_list(regs);
  for (const auto& kv : c.region_material)
    if (!has_region(kv.first))
      fail("regions." + kv.first, "the mesh has no region '" + kv.first + "'" +
                                      did_you_mean(kv.first, regs) + " (" + reg_list + ")");
  std::vector<std::string> mats;
  for (const auto& m : c.materials) mats.push_back(m.name);
  for (const auto& r : regs)
    if (!c.region_material.count(r))
      fail("regions", "mesh region '" + r + "' has no material; add \"" + r +
                          "\": \"<material>\" (" + reg_list + "; materials: " + quoted_list(mats) + ")");
  for (size_t i = 0; i < c.fracturable_regions.size(); ++i)
    if (!has_region(c.fracturable_regions[i]))
      fail(child("fracture.regions", i), "the mesh has no region '" + c.fracturable_regions[i] +
                                             "'" + did_you_mean(c.fracturable_regions[i], regs) +
                                             " (" + reg_list + ")");
  for (size_t i = 0; i < c.initial_velocities.size(); ++i) {
    const std::string& r = c.initial_velocities[i].region;
    if (r != "all" && !has_region(r))
      fail(child(child("boundary.initial_velocity", i), "region"),
           "the mesh has no region '" + r + "'" + did_you_mean(r, regs) + " (allowed: 'all'; " +
               reg_list + ")");
  }
}

// Node sets used by the boundary conditions, point loads and monitors; face sets of fracture.surfaces.
void check_mesh_sets(const Case& c, const HostMesh& mesh) {
  auto fail = [&](const std::string& path, const std::string& msg) { fail_at(c, path, msg); };
  std::vector<std::string> sets;
  for (const auto& kv : mesh.node_sets) sets.push_back(kv.first);
  const std::string prefix = kRegionSetPrefix;
  auto check_set = [&](const std::string& set, const std::string& path) {
    if (set.compare(0, prefix.size(), prefix) == 0) {  // "region.<name>": the nodes of a region
      const std::string r = set.substr(prefix.size());
      if (mesh.region_index(r) < 0)
        fail(path, "the mesh has no region '" + r + "'" + did_you_mean(r, mesh.region_names) + " (\"" +
                       prefix + "<region>\" names the nodes of a region; mesh regions: " +
                       quoted_list(mesh.region_names) + ")");
      return;
    }
    if (!mesh.node_sets.count(set))
      fail(path, "the mesh has no node set '" + set + "'" + did_you_mean(set, sets) +
                     " (node sets: " + quoted_list(sets) + ")");
  };
  size_t nfixed = 0;
  bool known_layout = false;
  if (c.resolved.is_object() && c.resolved.contains("boundary") &&
      c.resolved["boundary"].is_object() && c.resolved["boundary"].contains("fixed") &&
      c.resolved["boundary"]["fixed"].is_array()) {
    nfixed = c.resolved["boundary"]["fixed"].size();
    known_layout = nfixed <= c.velocity_bcs.size();
  }
  for (size_t i = 0; i < c.velocity_bcs.size(); ++i) {
    std::string path = !known_layout ? "boundary (velocity condition " + std::to_string(i) + ")"
                       : i < nfixed  ? child(child("boundary.fixed", i), "set")
                                     : child(child("boundary.velocity", i - nfixed), "set");
    check_set(c.velocity_bcs[i].set, path);
  }
  for (size_t i = 0; i < c.point_loads.size(); ++i)
    check_set(c.point_loads[i].set, child(child("boundary.point_loads", i), "set"));
  for (size_t i = 0; i < c.monitors.size(); ++i) check_set(c.monitors[i], child("output.monitors", i));
  std::vector<std::string> faces;
  for (const auto& kv : mesh.face_sets) faces.push_back(kv.first);
  for (const auto& kv : c.surface_iface_material)
    if (!mesh.face_sets.count(kv.first))
      fail(child("fracture.surfaces", kv.first),
           "the mesh has no named " + std::string(c.dim == 2 ? "curve" : "surface") + " '" + kv.first + "'" +
               did_you_mean(kv.first, faces) + " (physical groups of dimension " + std::to_string(c.dim - 1) +
               " of a Gmsh mesh: " + (faces.empty() ? std::string("none") : quoted_list(faces)) + ")");
}

}  // namespace
}  // namespace case_detail

Case load_case(const std::string& path, const std::vector<std::string>& overrides) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path + ": case file does not exist");
  if (fs::is_directory(path, ec))
    throw InputError(path + ": is a folder, not a case file (give the .json file)");
  // Not a device or pipe (/dev/zero would be read for ever); case files are small.
  if (!fs::is_regular_file(path, ec)) throw InputError(path + ": is not a regular file");
  const auto size = fs::file_size(path, ec);
  if (!ec && size > (64u << 20))
    throw InputError(path + ": case file is too large (" + std::to_string(size >> 20) +
                     " MiB; a case file is a few kB of JSON)");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open the case file for reading");
  std::stringstream ss;
  ss << in.rdbuf();
  case_detail::json doc = case_detail::parse_text(ss.str(), path);
  fs::path base = fs::path(path).parent_path();
  return case_detail::parse_impl(std::move(doc), path, overrides, base, true);
}

Case parse_case(nlohmann::json doc, const std::string& source,
                const std::vector<std::string>& overrides) {
  return case_detail::parse_impl(std::move(doc), source, overrides, fs::path(source).parent_path(),
                                 false);
}

void check_case_against_mesh(const Case& c, const HostMesh& mesh) {
  case_detail::check_mesh_regions(c, mesh);
  case_detail::check_mesh_sets(c, mesh);
}

}  // namespace fdem
