#pragma once
// The section readers of the case schema (docs/case-format.md), shared by src/io/case.cpp (which
// calls them in order) and the files that define them: src/io/case_sections.cpp (mesh, analysis,
// materials, interfaces and fracture) and src/io/case_conditions.cpp (boundary, platens, contact,
// damping, time, output). Each reads its section of `doc` into `c`, writes the defaults it applies
// back into `doc` and throws InputError naming the key path. Internal; not part of io/case.hpp.
#include <filesystem>

#include "io/case.hpp"
#include "io/json_reader.hpp"

namespace fdem::case_detail {

// `base_dir`: folder relative mesh file names are taken from; `check_files`: the mesh file must
// exist (load_case) or not (parse_case).
void read_mesh(json& doc, Case& c, const Reader& R, const std::filesystem::path& base_dir,
               bool check_files);
// "mesh": {"generator": "particles"} (src/io/case_particles.cpp), called by read_mesh.
void read_particles_generator(json& m, MeshSpec& s, const Reader& R);
void read_analysis(json& doc, Case& c, const Reader& R);
void read_materials(json& doc, Case& c, const Reader& R);    // materials and regions
void read_interfaces(json& doc, Case& c, const Reader& R);   // interface_materials and fracture
void read_boundary(json& doc, Case& c, const Reader& R);
void read_platens(json& doc, Case& c, const Reader& R);
void read_contact(json& doc, Case& c, const Reader& R);      // after read_interfaces
void read_damping(json& doc, Case& c, const Reader& R);
void read_parallel(json& doc, Case& c, const Reader& R);
void read_time(json& doc, Case& c, const Reader& R);         // after read_platens
void read_output(json& doc, Case& c, const Reader& R);       // after read_time

}  // namespace fdem::case_detail
