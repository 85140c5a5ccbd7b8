// Structural check of Gmsh .msh files before Gmsh reads them (see msh_check.hpp). The rules
// follow how Gmsh 4.8's readers (Geo/GModelIO_MSH2.cpp, GModelIO_MSH4.cpp) consume the file, so
// that whatever passes here is read by Gmsh the way it was checked:
//   - numbers Gmsh reads with fscanf are whitespace-separated tokens; the counts on their own
//     line (fgets + sscanf) must be alone on that line;
//   - MSH 4 entity lines and element lines are read line by line (fgets + sscanf "%[0-9- ]"), so
//     an entity or element must be on one line, with plain integers;
//   - section markers are found by prefix ("$NO..." is a node section for the MSH 2 reader), so
//     any section name Gmsh knows but fdem does not check is refused, and an unknown section must
//     not hold lines that start with '$' (the MSH 2 reader would take them for markers);
//   - Gmsh looks up nodes by `int` tag and indexes arrays with tags and counts from the file, so
//     tags are 1 .. 2^31-1, counts must match the data, element nodes must be defined and
//     physical-name dimensions are 0..3.
// The tokenizer is in msh_tokens.cpp, the $Entities, $Nodes and $Elements readers in
// msh_sections.cpp (shared declarations: msh_scan.hpp).
#include "mesh/msh_check.hpp"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <iterator>
#include <set>
#include <string>
#include <utility>

#include "common/error.hpp"
#include "mesh/msh_scan.hpp"

namespace fdem::mesh_detail {
namespace msh {
namespace {

// Section names (prefixes) that Gmsh's MSH readers act on. fdem checks and passes on only
// MeshFormat, PhysicalNames, Entities (MSH 4), Nodes and Elements.
const char* const kGmshSections[] = {
    "MeshFormat", "PhysicalNames", "Entities", "PartitionedEntities", "Nodes", "NO",
    "ParametricNodes", "ELM", "Elements", "Periodic", "GhostElements", "Parametrizations",
    "NodeData", "ElementData", "ElementNodeData", "PTS", "PARA", "InterpolationScheme",
    "PostFormat", "View"};

}  // namespace

void MshScanner::run() {
  first_line();
  format();
  std::set<std::string> seen;
  std::size_t start = 0;
  std::string name;
  while (next_section(start, name)) {
    const bool handled = name == "PhysicalNames" || name == "Nodes" || name == "Elements" ||
                         (v4_ && name == "Entities");
    if (handled) {
      read_section(name, start, seen);
      continue;
    }
    refuse_gmsh_section(name, start);
    skip_unknown(name, start);
  }
}

void MshScanner::first_line() {
  std::string_view first = line();
  if (first != "$MeshFormat") {
    if (first.rfind("$NOD", 0) == 0 || first.rfind("$NOE", 0) == 0)
      fail_at(0, "MSH version 1 files are not supported (fdem reads Gmsh MSH 2.2 and 4.1; "
                 "convert with 'gmsh FILE -save -format msh41')");
    fail_at(0, "not a Gmsh MSH file: the first line must be $MeshFormat (fdem reads Gmsh MSH "
               "2.2 and 4.1, ASCII or binary, and .geo files)");
  }
}

// Finds the next section marker ("$Name" after blank lines). Returns false at the end of the file;
// otherwise sets `start` (the marker's offset), `name` and the current section.
bool MshScanner::next_section(std::size_t& start, std::string& name) {
  start = p_;
  std::string_view l;
  bool found = false;
  while (!at_end()) {
    start = p_;
    l = line();
    if (!blank(l)) {
      found = true;
      break;
    }
  }
  if (!found) return false;
  if (l[0] != '$') fail_at(start, "unexpected text between sections: '" + shown(l) + "'");
  name = std::string(l.substr(1));
  if (name.empty() || !std::all_of(name.begin(), name.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
      }))
    fail_at(start, "bad section marker '" + shown(l) + "'");
  section_ = name;
  return true;
}

// A section fdem checks: at most once, in order, complete up to its end marker.
void MshScanner::read_section(const std::string& name, std::size_t start, std::set<std::string>& seen) {
  if (!seen.insert(name).second) fail_at(start, "section $" + name + " appears twice");
  if (name == "PhysicalNames") {
    names();
  } else if (name == "Entities") {
    if (seen.count("Nodes")) fail_at(start, "$Entities must come before $Nodes");
    entities();
  } else if (name == "Nodes") {
    v4_ ? nodes4() : nodes2();
    std::sort(node_tags_.begin(), node_tags_.end());
    auto dup = std::adjacent_find(node_tags_.begin(), node_tags_.end());
    if (dup != node_tags_.end())
      fail_at(start, "$Nodes: node tag " + std::to_string(*dup) + " is defined twice");
  } else {
    if (!seen.count("Nodes")) fail_at(start, "$Elements must come after $Nodes");
    v4_ ? elements4() : elements2();
    std::sort(elem_tags_.begin(), elem_tags_.end());
    auto dup = std::adjacent_find(elem_tags_.begin(), elem_tags_.end());
    if (dup != elem_tags_.end())
      fail_at(start, "$Elements: element tag " + std::to_string(*dup) + " is used twice");
  }
  end_marker(name);
}

// Known Gmsh sections other than those fdem checks are refused (by prefix, as Gmsh finds them).
void MshScanner::refuse_gmsh_section(const std::string& name, std::size_t start) const {
  if (name == "MeshFormat") fail_at(start, "section $MeshFormat appears twice");
  if (name.rfind("End", 0) == 0) fail_at(start, "'$" + name + "' without its section start");
  for (const char* known : kGmshSections)
    if (name.rfind(known, 0) == 0)
      fail_at(start, "section $" + name + " is not supported (fdem reads $MeshFormat, " +
                         "$PhysicalNames, " + (v4_ ? "$Entities, " : "") +
                         "$Nodes and $Elements; other sections must be left out)");
}

void MshScanner::end_marker(const std::string& name) {
  skip_ws();
  const size_t s = p_;
  if (at_end()) fail_at(s, "$End" + name + " is missing (the file is truncated?)");
  const std::string_view l = line();
  if (l != "$End" + name)
    fail_at(s, "expected $End" + name + ", found '" + shown(l) +
                   "' (the section holds more data than its counts say)");
}

void MshScanner::skip_unknown(const std::string& name, size_t start) {
  while (true) {
    if (at_end()) fail_at(start, "section $" + name + " has no $End" + name);
    const size_t s = p_;
    const std::string_view l = line();
    if (l.size() > 200) fail_at(s, "line longer than 200 characters in section $" + name);
    if (!l.empty() && l[0] == '$') {
      if (l == "$End" + name) return;
      fail_at(s, "'" + shown(l) + "' inside section $" + name + " (expected $End" + name + ")");
    }
  }
}

void MshScanner::format() {
  section_ = "MeshFormat";
  const size_t s = p_;
  const auto t = split(line());
  if (t.size() != 3)
    fail_at(s, "$MeshFormat: expected 'version file-type data-size', e.g. '4.1 0 8'");
  if (t[0] == "4.1") {
    v4_ = true;
  } else if (t[0] == "2.2") {
    v4_ = false;
  } else {
    fail_at(s, "MSH format version '" + shown(t[0]) +
                   "' is not supported (fdem reads 2.2 and 4.1; convert with "
                   "'gmsh FILE -save -format msh41')");
  }
  if (t[1] != "0" && t[1] != "1")
    fail_at(s, "$MeshFormat: file type must be 0 (ASCII) or 1 (binary), found '" + shown(t[1]) +
                   "'");
  if (t[2] != "8")
    fail_at(s, "$MeshFormat: data size must be 8, found '" + shown(t[2]) + "'");
  if (t[1] == "1") {
    binary_ = true;
    const size_t at = p_;
    if (bin<std::int32_t>() != 1)
      fail_at(at, "$MeshFormat: binary file of the other byte order (only little-endian "
                  "binary files are read)");
  }
  end_marker("MeshFormat");
}

void MshScanner::names() {
  const std::int64_t n = count_line("number of physical names", 1000000);
  for (std::int64_t i = 0; i < n; ++i) {
    skip_ws();
    if (at_end()) truncated();
    const size_t s = p_;
    const std::string_view l = line();
    p_ = s;  // messages point at this line
    if (l.size() > 200) fail(in() + "line longer than 200 characters");
    const size_t q = l.find('"');
    const size_t q2 = q == std::string_view::npos ? q : l.find('"', q + 1);
    const auto head = split(l.substr(0, q == std::string_view::npos ? l.size() : q));
    if (q2 == std::string_view::npos || head.size() != 2 || !blank(l.substr(q2 + 1)))
      fail(in() + "expected 'dimension tag \"name\"', found '" + shown(l) + "'");
    integer(head[0], "physical group dimension", 0, 3);
    integer(head[1], "physical group tag", 1, static_cast<std::int64_t>(kTagMax));
    if (!valid_utf8_text(l.substr(q + 1, q2 - q - 1)))
      fail(in() + "physical name is not printable UTF-8 text");
    line();
  }
}

}  // namespace msh

void check_msh_structure(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": mesh file cannot be opened for reading");
  std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw InputError(path + ": error while reading the mesh file");
  if (data.empty()) throw InputError(path + ": the mesh file is empty");
  msh::MshScanner(path, std::move(data)).run();
}

}  // namespace fdem::mesh_detail
