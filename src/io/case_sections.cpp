// Case schema, first part: mesh, analysis, materials and regions, interface materials and fracture.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <optional>
#include <string>
#include <system_error>
#include <vector>

#include "io/case_internal.hpp"
#include "io/case_text.hpp"

namespace fdem::case_detail {
namespace {

namespace fs = std::filesystem;

// "mesh": {"file": ..., "element_size": ...}: a Gmsh mesh or geometry file.
void read_mesh_file(json& m, MeshSpec& s, const Reader& R, const fs::path& base_dir,
                    bool check_files) {
  const std::string P = "mesh";
  R.keys(m, P, {"file", "element_size"});
  std::string f = R.string(m, P, "file");
  if (f.empty()) R.fail(child(P, "file"), "empty file name");
  if (m.contains("element_size")) {
    std::string ext = fs::path(f).extension().string();
    for (auto& ch : ext) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    if (ext != ".geo")
      R.fail(child(P, "element_size"), "applies to Gmsh geometry files (.geo) only, which are "
                                       "meshed on reading; '" + f + "' is a mesh already");
    s.element_size = R.number(m, P, "element_size", gt(0));
  }
  fs::path p(f);
  if (p.is_relative()) p = base_dir / p;
  p = p.lexically_normal();
  s.kind = "file";
  s.file = p.string();
  if (check_files) {
    std::error_code ec;
    if (!fs::exists(p, ec))
      R.fail(child(P, "file"), "mesh file '" + f + "' does not exist (looked for '" + s.file +
                                   "'; a relative path is taken from the case file's folder)");
    if (!fs::is_regular_file(p, ec))
      R.fail(child(P, "file"), "'" + s.file + "' is not a regular file");
  }
  std::error_code ec;
  fs::path abs = fs::absolute(p, ec);
  m["file"] = ec ? s.file : abs.lexically_normal().string();
}

// Rectangle (2D) or box (3D): origin, size, and cells per direction and/or element_size.
void read_block_generator(json& m, MeshSpec& s, int d, const std::string& g, const Reader& R) {
  const std::string P = "mesh";
  R.keys(m, P, {"generator", "origin", "size", "cells", "element_size", "region"});
  Vec3 o = R.vec(m, P, "origin", d, Vec3{0, 0, 0});
  Vec3 sz = R.vec(m, P, "size", d, std::nullopt, gt(0));
  s.origin = o;
  s.size = sz;
  const bool has_cells = m.contains("cells"), has_h = m.contains("element_size");
  if (!has_cells && !has_h)
    R.fail(P, "give 'cells' (cells per direction) or 'element_size' for generator '" + g + "'");
  if (has_cells) {
    const json& cj = m["cells"];
    const std::string cp = child(P, "cells");
    if (!cj.is_array() || static_cast<int>(cj.size()) != d)
      R.fail(cp, "expected an array of " + std::to_string(d) + " integers, got " +
                     (cj.is_array() ? std::to_string(cj.size()) + " elements" : describe(cj)));
    for (int i = 0; i < d; ++i)
      s.cells[i] = static_cast<int>(R.integer_value(cj[i], child(cp, i), 1, 100000000));
  }
  if (has_h) s.element_size = R.number(m, P, "element_size", gt(0));
}

// "mesh": {"generator": "grains", ...}: a Voronoi grain specimen (disc or rectangle; box in 3D).
void read_grains_generator(json& m, MeshSpec& s, int d, const Reader& R) {
  const std::string P = "mesh";
  R.keys(m, P,
         {"generator", "shape", "center", "radius", "origin", "size", "grain_size", "element_size", "seed",
          "minerals", "region", "mesher"});
  s.shape = R.string(m, P, "shape");
  if (d == 3 && s.shape != "box") R.fail(child(P, "shape"), "unknown 3D shape '" + s.shape + "' (allowed: box)");
  if (d == 2 && s.shape == "box") R.fail(child(P, "shape"), "'box' is a 3D shape (allowed in 2D: disc, rectangle)");
  if (s.shape == "disc") {
    for (const char* k : {"origin", "size"})
      if (m.contains(k))
        R.fail(child(P, k), "applies to shape 'rectangle' only (a disc takes center, radius)");
    s.origin = R.vec(m, P, "center", 2, Vec3{0, 0, 0});
    s.radius = R.number(m, P, "radius", gt(0));
  } else if (s.shape == "rectangle" || s.shape == "box") {
    for (const char* k : {"center", "radius"})
      if (m.contains(k)) R.fail(child(P, k), "applies to shape 'disc' only (a " + s.shape + " takes origin, size)");
    s.origin = R.vec(m, P, "origin", d, Vec3{0, 0, 0});
    s.size = R.vec(m, P, "size", d, std::nullopt, gt(0));
  } else {
    R.fail(child(P, "shape"), "unknown shape '" + s.shape + "' (allowed: disc, rectangle)");
  }
  s.element_size = R.number(m, P, "element_size", gt(0));
  if (!std::isfinite(2 * s.element_size))  // no grain_size is twice it ("allowed: >= inf")
    R.fail(child(P, "element_size"), "value " + fmt_num(s.element_size) +
                                         " leaves no grain_size (a grain needs grain_size >= 2 element_size): "
                                         "give an element_size of at most half the grain_size");
  s.grain_size = R.number(m, P, "grain_size", ge(2 * s.element_size));
  s.seed = static_cast<unsigned long>(R.integer(m, P, "seed", 0, 4294967295L, 1));
  if (m.contains("mesher")) {  // 3D only, not written when absent
    if (d != 3) R.fail(child(P, "mesher"), "applies to 3D grains only (2D grains are meshed by Gmsh's Delaunay)");
    s.mesher = R.string(m, P, "mesher");
    if (s.mesher != "delaunay" && s.mesher != "hxt")
      R.fail(child(P, "mesher"), "unknown mesher '" + s.mesher + "' (allowed: delaunay, hxt)");
  }
  if (m.contains("minerals")) {
    json& mj = R.object(m, P, "minerals", true);
    const std::string mp = child(P, "minerals");
    if (mj.empty()) R.fail(mp, "give at least one mineral: {\"<region>\": <area fraction>, ...}");
    double sum = 0;
    for (auto& [name, v] : mj.items()) {
      if (!valid_name(name))
        R.fail(mp, "'" + name + "' is not a valid region name (allowed: letters, digits, '_', '-', '.')");
      const double f = R.number_value(v, child(mp, name), between(0, true, 1, false));
      s.minerals.push_back({name, f});
      sum += f;
    }
    if (std::abs(sum - 1) > 1e-6)
      R.fail(mp, "the area fractions add up to " + std::to_string(sum) + " (allowed: 1 within 1e-6)");
  }
}

// "mesh": {"generator": ...}: rectangle, disc (2D), box, sphere, particles (3D), grains (both).
void read_mesh_generator(json& m, Case& c, const Reader& R) {
  const std::string P = "mesh";
  MeshSpec& s = c.mesh;
  const std::vector<std::string> gens = {"rectangle", "disc", "grains", "box", "sphere", "particles"};
  std::string g = R.string(m, P, "generator");
  if (std::find(gens.begin(), gens.end(), g) == gens.end())
    R.fail(child(P, "generator"), "unknown generator '" + g + "'" + did_you_mean(g, gens) +
                                      " (allowed: rectangle, disc (2D); box, sphere, particles (3D); grains)");
  const bool is2 = g == "rectangle" || g == "disc";
  if (g != "grains" && (is2 ? 2 : 3) != c.dim)
    R.fail(child(P, "generator"), "generator '" + g + "' makes a " + (is2 ? "2D" : "3D") +
                                      " mesh but dimension is " + std::to_string(c.dim) + " (allowed: " +
                                      (c.dim == 2 ? "rectangle, disc, grains" : "box, sphere, grains, particles") + ")");
  s.kind = g;
  if (g == "particles") {  // many particles, each its own body (src/io/case_particles.cpp)
    read_particles_generator(m, s, R);
    return;
  }
  const int d = c.dim;
  if (g == "rectangle" || g == "box") {
    read_block_generator(m, s, d, g, R);
  } else if (g == "grains") {
    read_grains_generator(m, s, d, R);
  } else {
    if (g == "sphere")
      R.keys(m, P, {"generator", "center", "radius", "element_size", "region", "mesher"});
    else if (g == "disc")
      R.keys(m, P,
             {"generator", "center", "radius", "element_size", "region", "embedded_diameter", "symmetric"});
    else
      R.keys(m, P, {"generator", "center", "radius", "element_size", "region"});
    s.origin = R.vec(m, P, "center", d, Vec3{0, 0, 0});
    s.radius = R.number(m, P, "radius", gt(0));
    s.element_size = R.number(m, P, "element_size", between(0, true, s.radius, false));
    if (g == "sphere" && m.contains("mesher")) {  // not written when absent: same case hash as before
      s.mesher = R.string(m, P, "mesher");
      if (s.mesher != "delaunay" && s.mesher != "hxt")
        R.fail(child(P, "mesher"), "unknown mesher '" + s.mesher + "' (allowed: delaunay, hxt)");
    }
    if (g == "disc" && m.contains("embedded_diameter")) {  // optional, no default written (none)
      const Vec3 u = R.vec(m, P, "embedded_diameter", d, std::nullopt);
      const double len = std::sqrt(u[0] * u[0] + u[1] * u[1]);
      if (!(len > 0))
        R.fail(child(P, "embedded_diameter"),
               "the direction is zero (allowed: any non-zero [dx, dy]; it is normalised)");
      s.diameter = {u[0] / len, u[1] / len, 0};
    }
    if (g == "disc" && m.contains("symmetric")) {  // optional, not written when absent (same case hash)
      if (!m["symmetric"].is_boolean()) R.fail(child(P, "symmetric"), "must be true or false");
      s.symmetric = m["symmetric"].get<bool>();
      if (s.symmetric && !m.contains("embedded_diameter"))
        R.fail(child(P, "symmetric"),
               "a mesh symmetric about a diameter needs mesh.embedded_diameter (its direction)");
    }
  }
  s.region = R.name(m, P, "region", std::string("body"));
}

// The interface material named at `p` (an index into interface_materials).
int interface_material_ref(const json& v, const std::string& p, const Reader& R,
                           const std::vector<std::string>& names) {
  const std::string im = R.string_value(v, p);
  const auto it = std::find(names.begin(), names.end(), im);
  if (it == names.end())
    R.fail(p, "unknown interface material '" + im + "'" + did_you_mean(im, names) +
                  " (interface_materials: " + quoted_list(names) + ")");
  return static_cast<int>(it - names.begin());
}

// A region named at `p` that has a bulk material.
std::string region_ref(const std::string& r, const std::string& p, const Case& c, const Reader& R) {
  if (c.region_material.count(r)) return r;
  std::vector<std::string> known;
  for (const auto& kv : c.region_material) known.push_back(kv.first);
  R.fail(p, "region '" + r + "' has no material in 'regions'" + did_you_mean(r, known) +
                " (regions: " + quoted_list(known) + ")");
}

// "fracture.region_materials": {region: interface material}; "fracture.pair_materials":
// [{"regions": [r1, r2], "material": m}, ...].
void read_materials_by_place(json& f, Case& c, const Reader& R, const std::vector<std::string>& names) {
  json& rm = R.object(f, "fracture", "region_materials", false);
  for (auto it = rm.begin(); it != rm.end(); ++it) {
    const std::string p = child("fracture.region_materials", it.key());
    c.region_iface_material[region_ref(it.key(), p, c, R)] = interface_material_ref(*it, p, R, names);
  }
  json& pm = R.array(f, "fracture", "pair_materials", false);
  for (size_t i = 0; i < pm.size(); ++i) {
    const std::string p = child("fracture.pair_materials", i);
    R.require_object(pm[i], p);
    R.keys(pm[i], p, {"regions", "material"});
    json& rs = R.array(pm[i], p, "regions", true);
    if (rs.size() != 2) R.fail(p + ".regions", "two region names are needed (got " + std::to_string(rs.size()) + ")");
    std::string a = region_ref(R.string_value(rs[0], child(p + ".regions", 0)), child(p + ".regions", 0), c, R);
    std::string b = region_ref(R.string_value(rs[1], child(p + ".regions", 1)), child(p + ".regions", 1), c, R);
    if (a == b) R.fail(p + ".regions", "the two regions are the same ('" + a + "'): use fracture.region_materials");
    if (b < a) std::swap(a, b);
    if (!pm[i].contains("material")) R.fail(p + ".material", "missing (an interface material name)");
    const auto key = std::make_pair(a, b);
    if (c.pair_iface_material.count(key)) R.fail(p, "the pair ('" + a + "', '" + b + "') is listed twice");
    c.pair_iface_material[key] = interface_material_ref(pm[i]["material"], p + ".material", R, names);
  }
  if (!f.contains("surfaces")) return;  // (not added to the case as read: its hash stays that of earlier versions)
  json& sm = R.object(f, "fracture", "surfaces", false);
  for (auto it = sm.begin(); it != sm.end(); ++it) {
    const std::string p = child("fracture.surfaces", it.key());
    if (it.key().empty()) R.fail(p, "a surface name must not be empty");
    c.surface_iface_material[it.key()] = interface_material_ref(*it, p, R, names);
  }
}

// "fracture.scatter": random strength per interface.
void read_scatter(json& f, Case& c, const Reader& R) {
  json& s = R.object(f, "fracture", "scatter", false);
  const std::string p = "fracture.scatter";
  R.keys(s, p, {"distribution", "modulus", "cov", "lower", "upper", "seed", "energy", "correlation_length"});
  StrengthScatter& sc = c.scatter;
  sc.distribution = R.string(s, p, "distribution");
  if (sc.distribution == "weibull") {
    sc.modulus = R.number(s, p, "modulus", between(0.5, false, 1000, false));
    if (s.contains("cov")) R.fail(p + ".cov", "is for the normal distribution (weibull takes 'modulus')");
    for (const char* key : {"lower", "upper"})  // a Weibull factor is not truncated
      if (s.contains(key))
        R.fail(child(p, key),
               "is for the normal distribution (weibull takes 'modulus' only; its factor is not truncated)");
  } else if (sc.distribution == "normal") {
    sc.cov = R.number(s, p, "cov", between(0, true, 1, false));
    sc.lower = R.number(s, p, "lower", between(0, true, 1, true), 0.1);
    sc.upper = R.number(s, p, "upper", gt(1), 10.0);
    if (s.contains("modulus")) R.fail(p + ".modulus", "is for the weibull distribution (normal takes 'cov')");
  } else {
    R.fail(p + ".distribution", "must be \"weibull\" or \"normal\" (got \"" + sc.distribution + "\")");
  }
  sc.seed = static_cast<unsigned long long>(R.integer(s, p, "seed", 0, 4294967295L, 1));
  if (s.contains("correlation_length")) sc.correlation_length = R.number(s, p, "correlation_length", gt(0));
  if (s.contains("energy")) {
    if (!s["energy"].is_boolean()) R.fail(p + ".energy", "must be true or false");
    sc.energy = s["energy"].get<bool>();
  }
}

// "fracture": the fracturable regions, their interface material and the strength reduction.
void read_fracture(json& doc, Case& c, const Reader& R) {
  json& f = R.object(doc, "", "fracture", false);
  R.keys(f, "fracture",
         {"regions", "interface_material", "strength_reduction", "region_materials", "pair_materials",
          "surfaces", "scatter"});
  if (f.contains("strength_reduction")) {
    json& sr = R.object(f, "fracture", "strength_reduction", false);
    const std::string sp = "fracture.strength_reduction";
    R.keys(sr, sp, {"initial", "start_time", "rate"});
    c.srf_initial = R.number(sr, sp, "initial", gt(0), 1.0);
    c.srf_start = R.number(sr, sp, "start_time", ge(0), 0.0);
    c.srf_rate = R.number(sr, sp, "rate", ge(0), 0.0);
  }
  // with named surfaces, the regions may be none (interfaces on those surfaces only)
  const bool surfaces = f.contains("surfaces") && f["surfaces"].is_object() && !f["surfaces"].empty();
  json& regs = R.array(f, "fracture", "regions", !surfaces);
  if (regs.empty() && !surfaces)
    R.fail("fracture.regions",
           "at least one region (or one of fracture.surfaces) is needed (omit 'fracture' for no fracture)");
  std::vector<std::string> known;
  for (const auto& kv : c.region_material) known.push_back(kv.first);
  for (size_t i = 0; i < regs.size(); ++i) {
    const std::string p = child("fracture.regions", i);
    std::string r = R.string_value(regs[i], p);
    if (!c.region_material.count(r))
      R.fail(p, "region '" + r + "' has no material in 'regions'" + did_you_mean(r, known) +
                    " (regions: " + quoted_list(known) + ")");
    if (std::find(c.fracturable_regions.begin(), c.fracturable_regions.end(), r) !=
        c.fracturable_regions.end())
      R.fail(p, "region '" + r + "' is listed twice");
    c.fracturable_regions.push_back(r);
  }
  std::vector<std::string> names;
  for (const auto& m : c.interface_materials) names.push_back(m.name);
  std::string im = R.string(f, "fracture", "interface_material");
  auto it = std::find(names.begin(), names.end(), im);
  if (it == names.end())
    R.fail("fracture.interface_material",
           "unknown interface material '" + im + "'" + did_you_mean(im, names) +
               " (interface_materials: " + quoted_list(names) + ")");
  c.fracture_material = static_cast<int>(it - names.begin());
  read_materials_by_place(f, c, R, names);
  if (f.contains("scatter")) read_scatter(f, c, R);
}

// "mesh.rotation": {"angle_deg", "axis" (3D), "center"}, "mesh.jitter": {"amplitude", "seed"} and
// "mesh.refine" (levels):
// what any mesh (file or generator) may take (src/mesh/mesh_transforms.cpp). Nothing is written
// for a key that is absent (the same case hash as before).
void read_mesh_transforms(json& m, MeshSpec& s, int d, const Reader& R) {
  const std::string P = "mesh";
  if (m.contains("rotation")) {
    const std::string p = child(P, "rotation");
    json& r = R.object(m, P, "rotation", true);
    R.keys(r, p, d == 3 ? std::vector<std::string>{"angle_deg", "axis", "center"}
                        : std::vector<std::string>{"angle_deg", "center"});
    s.rotation_deg = R.number(r, p, "angle_deg", between(-360, true, 360, true));
    if (d == 3) {
      s.rotation_axis = R.vec(r, p, "axis", 3, std::nullopt);
      const Vec3& u = s.rotation_axis;
      if (!(u[0] * u[0] + u[1] * u[1] + u[2] * u[2] > 0))
        R.fail(child(p, "axis"), "the axis is zero (allowed: any non-zero [x, y, z]; it is normalised)");
    }
    if (r.contains("center")) {  // else the centre of the mesh's bounding box
      s.rotation_center = R.vec(r, p, "center", d, std::nullopt);
      s.has_rotation_center = true;
    }
  }
  if (m.contains("jitter")) {
    const std::string p = child(P, "jitter");
    json& j = R.object(m, P, "jitter", true);
    R.keys(j, p, {"amplitude", "seed"});
    s.jitter = R.number(j, p, "amplitude", between(0, true, 0.5, false));
    s.jitter_seed = static_cast<unsigned long>(R.integer(j, p, "seed", 0, 4294967295L, 1));
  }
  if (m.contains("refine"))  // each triangle into 4, each tetrahedron into 8, k times (mesh/refine.hpp)
    s.refine = static_cast<int>(R.integer(m, P, "refine", 0, 10, 0));
}

}  // namespace

void read_mesh(json& doc, Case& c, const Reader& R, const fs::path& base_dir, bool check_files) {
  json& whole = R.object(doc, "", "mesh", true);
  const std::string P = "mesh";
  // The transforms apply to every kind: read here, and out of the way while the kind's reader
  // checks its own keys.
  read_mesh_transforms(whole, c.mesh, c.dim, R);
  json transforms = json::object();
  for (const char* k : {"rotation", "jitter", "refine"})
    if (whole.contains(k)) {
      transforms[k] = whole[k];
      whole.erase(k);
    }
  struct PutBack {  // (also when a reader throws: the document stays whole)
    json& m;
    json& t;
    ~PutBack() {
      for (auto& [k, v] : t.items()) m[k] = v;
    }
  } put_back{whole, transforms};
  json& m = whole;
  const bool has_file = m.contains("file"), has_gen = m.contains("generator");
  if (has_file && has_gen) R.fail(P, "give either 'file' or 'generator', not both");
  if (!has_file && !has_gen) {
    if (!m.empty()) R.keys(m, P, {"file", "generator"});
    R.fail(P, "give either 'file' (a Gmsh .msh or .geo file) or 'generator' (rectangle, disc, box, sphere)");
  }
  if (has_file) {
    read_mesh_file(m, c.mesh, R, base_dir, check_files);
    return;
  }
  read_mesh_generator(m, c, R);
}

void read_analysis(json& doc, Case& c, const Reader& R) {
  if (c.dim != 2) {
    if (doc.contains("analysis"))
      R.fail("analysis", "applies to dimension 2 only (plane stress/strain and thickness)");
    return;
  }
  json& a = R.object(doc, "", "analysis", false);
  R.keys(a, "analysis", {"plane", "thickness"});
  std::string plane = R.string(a, "analysis", "plane", std::string("strain"));
  if (plane != "stress" && plane != "strain")
    R.fail("analysis.plane", "'" + plane + "' is not allowed (allowed: \"stress\", \"strain\")");
  c.plane_stress = plane == "stress";
  c.thickness = R.number(a, "analysis", "thickness", gt(0), 1.0);
}

void read_materials(json& doc, Case& c, const Reader& R) {
  json& mats = R.object(doc, "", "materials", true);
  if (mats.empty()) R.fail("materials", "at least one material is needed");
  for (auto it = mats.begin(); it != mats.end(); ++it) {
    const std::string p = child("materials", it.key());
    if (!valid_name(it.key())) R.fail(p, "'" + it.key() + "' is not a valid material name");
    R.keys(*it, p, {"density", "E", "nu"});
    BulkMaterial m;
    m.name = it.key();
    m.density = R.number(*it, p, "density", gt(0));
    m.E = R.number(*it, p, "E", gt(0));
    m.nu = R.number(*it, p, "nu", between(-1, true, 0.5, true));
    c.materials.push_back(m);
  }
  json& regs = R.object(doc, "", "regions", true);
  if (regs.empty()) R.fail("regions", "at least one region -> material entry is needed");
  std::vector<std::string> names;
  for (const auto& m : c.materials) names.push_back(m.name);
  for (auto it = regs.begin(); it != regs.end(); ++it) {
    const std::string p = child("regions", it.key());
    std::string mat = R.string_value(*it, p);
    auto f = std::find(names.begin(), names.end(), mat);
    if (f == names.end())
      R.fail(p, "unknown material '" + mat + "'" + did_you_mean(mat, names) +
                    " (materials: " + quoted_list(names) + ")");
    c.region_material[it.key()] = static_cast<int>(f - names.begin());
  }
}

void read_interfaces(json& doc, Case& c, const Reader& R) {
  json& ims = R.object(doc, "", "interface_materials", false);
  for (auto it = ims.begin(); it != ims.end(); ++it) {
    const std::string p = child("interface_materials", it.key());
    if (!valid_name(it.key())) R.fail(p, "'" + it.key() + "' is not a valid material name");
    R.keys(*it, p, {"kn", "ks", "ft", "c", "phi_deg", "phi_r_deg", "law", "Gnc", "Gsc", "eta"});
    InterfaceMaterial m;
    m.name = it.key();
    m.kn = R.number(*it, p, "kn", gt(0));
    m.ks = R.number(*it, p, "ks", gt(0));
    m.ft = R.number(*it, p, "ft", ge(0));
    m.c = R.number(*it, p, "c", ge(0));
    m.phi = R.number(*it, p, "phi_deg", between(0, false, 90, true)) * kPi / 180.0;
    // a frictional joint (ft = c = 0) never softens: its fracture energies are not needed
    const std::optional<double> unused = m.frictional() ? std::optional<double>(1.0) : std::nullopt;
    m.Gnc = R.number(*it, p, "Gnc", gt(0), unused);
    m.Gsc = R.number(*it, p, "Gsc", gt(0), unused);
    m.eta = R.number(*it, p, "eta", gt(0), 2.0);
    if (m.frictional() && it->contains("phi_r_deg"))
      R.fail(child(p, "phi_r_deg"), "is for materials that soften: a frictional joint (ft = c = 0) slides at phi_deg");
    m.phi_r = R.number(*it, p, "phi_r_deg", between(0, false, 90, true), m.phi * 180.0 / kPi) * kPi / 180.0;
    const std::string law = R.string(*it, p, "law", std::string("paper"));
    if (law != "residual_friction" && law != "paper")
      R.fail(child(p, "law"), "'" + law + "' is not a law (allowed: \"paper\", the default, or \"residual_friction\")");
    m.residual_friction = law == "residual_friction";
    c.interface_materials.push_back(m);
  }
  if (doc.contains("fracture")) read_fracture(doc, c, R);
}

}  // namespace fdem::case_detail
