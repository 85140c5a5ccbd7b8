#pragma once
// Structural check of a Gmsh .msh file before Gmsh (4.8) reads it. Gmsh's MSH readers trust the
// file: element node tags out of range, section counts that disagree with the data, bad physical
// dimensions or huge counts make it read out of bounds, allocate without limit or crash. This
// scanner reads the file once, without Gmsh, and accepts only what Gmsh reads safely:
//   - first line $MeshFormat; version 2.2 or 4.1; ASCII or binary (little-endian, data size 8);
//   - sections $PhysicalNames, $Entities (4.1), $Nodes, $Elements, each at most once and
//     complete (counts match the data, all numbers finite and in range, every element node
//     defined, no duplicate node or element tags, element types 1..31 of Gmsh's table);
//   - other Gmsh sections ($Periodic, $NodeData, partitions, ...) are refused; unknown sections
//     (e.g. $Comments) are skipped as Gmsh skips them.
// Throws InputError naming the file, the problem and the line (ASCII) or byte offset (binary).
#include <string>

namespace fdem::mesh_detail {

void check_msh_structure(const std::string& path);

}  // namespace fdem::mesh_detail
