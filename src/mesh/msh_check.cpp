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
#include "mesh/msh_check.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <set>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "common/error.hpp"

namespace fdem::mesh_detail {
namespace {

constexpr std::uint64_t kTagMax = static_cast<std::uint64_t>(std::numeric_limits<int>::max());
constexpr std::uint64_t kMaxEntities = 100000;  // Gmsh allocates 128 bytes per entity and line

// Gmsh element types 1..31: nodes per element and dimension.
struct ElemType {
  int nodes;
  int dim;
};
const ElemType* elem_type(std::int64_t t) {
  static const ElemType table[32] = {
      {0, -1}, {2, 1},  {3, 2},  {4, 2},  {4, 3},  {8, 3},  {6, 3},  {5, 3},
      {3, 1},  {6, 2},  {9, 2},  {10, 3}, {27, 3}, {18, 3}, {14, 3}, {1, 0},
      {8, 2},  {20, 3}, {15, 3}, {13, 3}, {9, 2},  {10, 2}, {12, 2}, {15, 2},
      {15, 2}, {21, 2}, {4, 1},  {5, 1},  {6, 1},  {20, 3}, {35, 3}, {56, 3}};
  return t >= 1 && t <= 31 ? &table[t] : nullptr;
}

// Section names (prefixes) that Gmsh's MSH readers act on. fdem checks and passes on only
// MeshFormat, PhysicalNames, Entities (MSH 4), Nodes and Elements.
const char* const kGmshSections[] = {
    "MeshFormat", "PhysicalNames", "Entities", "PartitionedEntities", "Nodes", "NO",
    "ParametricNodes", "ELM", "Elements", "Periodic", "GhostElements", "Parametrizations",
    "NodeData", "ElementData", "ElementNodeData", "PTS", "PARA", "InterpolationScheme",
    "PostFormat", "View"};

bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
}

bool blank(std::string_view s) {
  return std::all_of(s.begin(), s.end(), [](char c) { return is_space(c); });
}

std::vector<std::string_view> split(std::string_view s) {
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && is_space(s[i])) ++i;
    size_t j = i;
    while (j < s.size() && !is_space(s[j])) ++j;
    if (j > i) out.push_back(s.substr(i, j - i));
    i = j;
  }
  return out;
}

std::string shown(std::string_view s) {
  std::string r;
  for (char c : s.substr(0, 40)) r += (c >= 32 && c < 127) ? c : '?';
  if (s.size() > 40) r += "...";
  return r;
}

// Printable UTF-8 (no control characters; strict: no overlong forms, surrogates or > U+10FFFF),
// so that names taken from the file can go into JSON reports.
bool valid_utf8_text(std::string_view s) {
  size_t i = 0;
  while (i < s.size()) {
    const auto c = static_cast<unsigned char>(s[i]);
    int extra = 0;
    unsigned lo = 0x80, hi = 0xbf;  // allowed range of the second byte
    if (c < 0x80) {
      if (c < 0x20 || c == 0x7f) return false;
    } else if (c >= 0xc2 && c <= 0xdf) {
      extra = 1;
    } else if (c >= 0xe0 && c <= 0xef) {
      extra = 2;
      if (c == 0xe0) lo = 0xa0;
      if (c == 0xed) hi = 0x9f;
    } else if (c >= 0xf0 && c <= 0xf4) {
      extra = 3;
      if (c == 0xf0) lo = 0x90;
      if (c == 0xf4) hi = 0x8f;
    } else {
      return false;
    }
    if (s.size() - i <= static_cast<size_t>(extra)) return false;
    for (int k = 1; k <= extra; ++k) {
      const auto b = static_cast<unsigned char>(s[i + k]);
      if (k == 1 ? (b < lo || b > hi) : (b < 0x80 || b > 0xbf)) return false;
    }
    i += 1 + extra;
  }
  return true;
}

class Scanner {
 public:
  Scanner(const std::string& path, std::string data) : path_(path), d_(std::move(data)) {}

  void run() {
    std::string_view first = line();
    if (first != "$MeshFormat") {
      if (first.rfind("$NOD", 0) == 0 || first.rfind("$NOE", 0) == 0)
        fail_at(0, "MSH version 1 files are not supported (fdem reads Gmsh MSH 2.2 and 4.1; "
                   "convert with 'gmsh FILE -save -format msh41')");
      fail_at(0, "not a Gmsh MSH file: the first line must be $MeshFormat (fdem reads Gmsh MSH "
                 "2.2 and 4.1, ASCII or binary, and .geo files)");
    }
    format();
    std::set<std::string> seen;
    while (true) {
      size_t start = p_;
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
      if (!found) break;
      if (l[0] != '$') fail_at(start, "unexpected text between sections: '" + shown(l) + "'");
      const std::string name(l.substr(1));
      if (name.empty() || !std::all_of(name.begin(), name.end(), [](char c) {
            return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
          }))
        fail_at(start, "bad section marker '" + shown(l) + "'");
      section_ = name;
      const bool handled = name == "PhysicalNames" || name == "Nodes" || name == "Elements" ||
                           (v4_ && name == "Entities");
      if (handled) {
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
        continue;
      }
      if (name == "MeshFormat") fail_at(start, "section $MeshFormat appears twice");
      if (name.rfind("End", 0) == 0) fail_at(start, "'$" + name + "' without its section start");
      for (const char* known : kGmshSections)
        if (name.rfind(known, 0) == 0)
          fail_at(start, "section $" + name + " is not supported (fdem reads $MeshFormat, " +
                             "$PhysicalNames, " + (v4_ ? "$Entities, " : "") +
                             "$Nodes and $Elements; other sections must be left out)");
      skip_unknown(name, start);
    }
  }

 private:
  // ------------------------------------------------------------------------------ messages
  [[noreturn]] void fail_at(size_t at, const std::string& msg) const {
    std::string where;
    if (binary_) {
      where = "byte " + std::to_string(at);
    } else {
      const size_t upto = std::min(at, d_.size());
      where = "line " + std::to_string(1 + std::count(d_.begin(), d_.begin() + upto, '\n'));
    }
    throw InputError(path_ + ": " + where + ": " + msg);
  }
  [[noreturn]] void fail(const std::string& msg) const { fail_at(p_, msg); }
  std::string in() const { return "$" + section_ + ": "; }
  [[noreturn]] void truncated() const {
    fail(in() + "unexpected end of file (the file is truncated or a count is too large)");
  }

  // ------------------------------------------------------------------------------ text
  bool at_end() const { return p_ >= d_.size(); }

  // The rest of the current line without its "\n" (and a trailing "\r"); moves past the "\n".
  std::string_view line() {
    const size_t nl = d_.find('\n', p_);
    const size_t end = nl == std::string::npos ? d_.size() : nl;
    std::string_view l(d_.data() + p_, end - p_);
    p_ = nl == std::string::npos ? d_.size() : nl + 1;
    if (!l.empty() && l.back() == '\r') l.remove_suffix(1);
    return l;
  }

  void skip_ws() {
    while (p_ < d_.size() && is_space(d_[p_])) ++p_;
  }

  std::string_view token() {
    skip_ws();
    if (at_end()) truncated();
    const size_t b = p_;
    while (p_ < d_.size() && !is_space(d_[p_])) ++p_;
    return std::string_view(d_.data() + b, p_ - b);
  }

  // Integer token: [-]?[0-9]+ (unsigned: [0-9]+) within [lo, hi].
  std::int64_t integer(std::string_view t, const std::string& what, std::int64_t lo,
                       std::int64_t hi) const {
    bool neg = !t.empty() && t[0] == '-';
    std::string_view digits = neg ? t.substr(1) : t;
    bool ok = !digits.empty() && digits.size() <= 18 &&
              std::all_of(digits.begin(), digits.end(),
                          [](char c) { return c >= '0' && c <= '9'; });
    if (!ok) fail(in() + what + ": expected an integer, found '" + shown(t) + "'");
    std::int64_t v = 0;
    for (char c : digits) v = v * 10 + (c - '0');
    if (neg) v = -v;
    if (v < lo || v > hi)
      fail(in() + what + " " + std::string(t) + " is out of range (allowed: " +
           std::to_string(lo) + " to " + std::to_string(hi) + ")");
    return v;
  }
  std::int64_t integer(const std::string& what, std::int64_t lo, std::int64_t hi) {
    return integer(token(), what, lo, hi);
  }

  double real(std::string_view t, const std::string& what) const {
    const std::string s(t);
    char* end = nullptr;
    const double v = std::strtod(s.c_str(), &end);
    if (s.empty() || end != s.c_str() + s.size())
      fail(in() + what + ": expected a number, found '" + shown(t) + "'");
    if (!std::isfinite(v)) fail(in() + what + " '" + shown(t) + "' is not a finite number");
    return v;
  }
  double real(const std::string& what) { return real(token(), what); }

  // A count alone on its line (Gmsh reads it with fgets + sscanf).
  std::int64_t count_line(const std::string& what, std::int64_t hi) {
    const size_t s = p_;
    const auto t = split(line());
    if (t.size() != 1) fail_at(s, in() + "expected the " + what + " alone on its line");
    p_ = s;
    skip_ws();
    const std::int64_t v = integer(t[0], what, 0, hi);
    line();
    return v;
  }

  // ------------------------------------------------------------------------------ binary
  template <class T>
  T bin() {
    if (d_.size() - p_ < sizeof(T)) truncated();
    T v;
    std::memcpy(&v, d_.data() + p_, sizeof v);
    p_ += sizeof v;
    return v;
  }
  std::int64_t bin_int(const std::string& what, std::int64_t lo, std::int64_t hi) {
    const size_t at = p_;
    const std::int64_t v = bin<std::int32_t>();
    if (v < lo || v > hi)
      fail_at(at, in() + what + " " + std::to_string(v) + " is out of range (allowed: " +
                      std::to_string(lo) + " to " + std::to_string(hi) + ")");
    return v;
  }
  std::uint64_t bin_size(const std::string& what, std::uint64_t hi) {
    const size_t at = p_;
    const std::uint64_t v = bin<std::uint64_t>();
    if (v > hi)
      fail_at(at, in() + what + " " + std::to_string(v) + " is out of range (allowed: 0 to " +
                      std::to_string(hi) + ")");
    return v;
  }
  double bin_real(const std::string& what) {
    const size_t at = p_;
    const double v = bin<double>();
    if (!std::isfinite(v)) fail_at(at, in() + what + " is not a finite number");
    return v;
  }
  // Fails early if `n` records of `each` bytes cannot fit in the rest of the file.
  void need(std::uint64_t n, std::uint64_t each) const {
    if (each > 0 && n > (d_.size() - p_) / each) truncated();
  }

  // ------------------------------------------------------------------------------ sections
  void end_marker(const std::string& name) {
    skip_ws();
    const size_t s = p_;
    if (at_end()) fail_at(s, "$End" + name + " is missing (the file is truncated?)");
    const std::string_view l = line();
    if (l != "$End" + name)
      fail_at(s, "expected $End" + name + ", found '" + shown(l) +
                     "' (the section holds more data than its counts say)");
  }

  void skip_unknown(const std::string& name, size_t start) {
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

  void format() {
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

  void names() {
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

  // MSH 4.1 $Entities: points, curves, surfaces, volumes with physical tags and bounding entities.
  void entities() {
    std::uint64_t cnt[4];
    std::uint64_t total = 0;
    for (auto& c : cnt) {
      c = binary_ ? bin_size("number of entities", kMaxEntities)
                  : static_cast<std::uint64_t>(
                        integer("number of entities", 0, static_cast<std::int64_t>(kMaxEntities)));
      total += c;
    }
    if (total > kMaxEntities)
      fail(in() + "more than " + std::to_string(kMaxEntities) + " entities");
    for (int dim = 0; dim < 4; ++dim)
      for (std::uint64_t i = 0; i < cnt[dim]; ++i) {
        const int nbox = dim == 0 ? 3 : 6;
        std::int64_t tag;
        if (binary_) {
          tag = bin_int("entity tag", 1, static_cast<std::int64_t>(kTagMax));
          for (int k = 0; k < nbox; ++k) bin_real("entity bounding box");
          const std::uint64_t nphys = bin_size("number of physical tags", 100000);
          need(nphys, 4);
          p_ += nphys * 4;
          if (dim > 0) {
            const std::uint64_t nb = bin_size("number of bounding entities", 1000000);
            need(nb, 4);
            p_ += nb * 4;
          }
        } else {
          skip_ws();
          if (at_end()) truncated();
          const size_t s = p_;
          const std::string_view l = line();
          p_ = s;
          if (l.size() > 4000) fail(in() + "entity line longer than 4000 characters");
          if (!std::all_of(l.begin(), l.end(), [](char c) {
                return (c >= '0' && c <= '9') || c == ' ' || c == '-' || c == '+' || c == '.' ||
                       c == 'e' || c == 'E';
              }))
            fail(in() + "unexpected character in entity line '" + shown(l) + "'");
          const auto t = split(l);
          size_t k = 0;
          auto next = [&]() -> std::string_view {
            if (k >= t.size()) fail(in() + "entity line is too short: '" + shown(l) + "'");
            return t[k++];
          };
          tag = integer(next(), "entity tag", 1, static_cast<std::int64_t>(kTagMax));
          for (int b = 0; b < nbox; ++b) real(next(), "entity bounding box");
          const std::int64_t nphys = integer(next(), "number of physical tags", 0, 100000);
          for (std::int64_t j = 0; j < nphys; ++j)
            integer(next(), "physical tag", std::numeric_limits<int>::min(),
                    std::numeric_limits<int>::max());
          if (dim > 0) {
            const std::int64_t nb = integer(next(), "number of bounding entities", 0, 1000000);
            for (std::int64_t j = 0; j < nb; ++j)
              integer(next(), "bounding entity tag", -static_cast<std::int64_t>(kTagMax),
                      static_cast<std::int64_t>(kTagMax));
          }
          if (k != t.size()) fail(in() + "entity line has extra numbers: '" + shown(l) + "'");
          line();
        }
        entities_.insert({dim, tag});
      }
  }

  void nodes4() {
    std::uint64_t nblocks, total;
    if (binary_) {
      nblocks = bin_size("number of node blocks", kTagMax);
      total = bin_size("number of nodes", kTagMax);
      bin<std::uint64_t>();  // min and max tag: Gmsh only warns if they are wrong
      bin<std::uint64_t>();
      need(total, 32);
    } else {
      nblocks = integer("number of node blocks", 0, kTagMax);
      total = integer("number of nodes", 0, kTagMax);
      integer("minimum node tag", 0, std::numeric_limits<std::int64_t>::max());
      integer("maximum node tag", 0, std::numeric_limits<std::int64_t>::max());
    }
    std::uint64_t read = 0;
    for (std::uint64_t b = 0; b < nblocks; ++b) {
      std::int64_t edim, etag, param;
      std::uint64_t n;
      if (binary_) {
        edim = bin_int("entity dimension", 0, 3);
        etag = bin_int("entity tag", 1, static_cast<std::int64_t>(kTagMax));
        param = bin_int("parametric flag", 0, 1);
        n = bin_size("number of nodes in block", total - read);
      } else {
        edim = integer("entity dimension", 0, 3);
        etag = integer("entity tag", 1, static_cast<std::int64_t>(kTagMax));
        param = integer("parametric flag", 0, 1);
        n = integer("number of nodes in block", 0, static_cast<std::int64_t>(total - read));
      }
      entities_.insert({static_cast<int>(edim), etag});
      const std::int64_t ncoord = 3 + (param ? edim : 0);
      if (binary_) need(n, 8 + 8 * ncoord);
      for (std::uint64_t j = 0; j < n; ++j)
        node_tags_.push_back(static_cast<std::uint32_t>(
            binary_ ? bin_size("node tag", kTagMax)
                    : integer("node tag", 1, static_cast<std::int64_t>(kTagMax))));
      if (binary_)
        for (std::uint64_t j = node_tags_.size() - n; j < node_tags_.size(); ++j)
          if (node_tags_[j] == 0) fail(in() + "node tag 0 (tags start at 1)");
      for (std::uint64_t j = 0; j < n * ncoord; ++j)
        binary_ ? bin_real("node coordinate") : real("node coordinate");
      read += n;
    }
    if (read != total)
      fail(in() + "the header announces " + std::to_string(total) + " nodes but the blocks hold " +
           std::to_string(read));
  }

  void check_element_nodes(std::uint64_t elem, const std::vector<std::uint64_t>& nodes,
                           size_t at) const {
    for (std::uint64_t v : nodes)
      if (!std::binary_search(node_tags_.begin(), node_tags_.end(), v))
        fail_at(at, in() + "element " + std::to_string(elem) + " uses node " + std::to_string(v) +
                        ", which is not defined in $Nodes");
  }

  void elements4() {
    std::uint64_t nblocks, total;
    if (binary_) {
      nblocks = bin_size("number of element blocks", kTagMax);
      total = bin_size("number of elements", kTagMax);
      bin<std::uint64_t>();
      bin<std::uint64_t>();
      need(total, 16);
    } else {
      nblocks = integer("number of element blocks", 0, kTagMax);
      total = integer("number of elements", 0, kTagMax);
      integer("minimum element tag", 0, std::numeric_limits<std::int64_t>::max());
      integer("maximum element tag", 0, std::numeric_limits<std::int64_t>::max());
    }
    std::uint64_t read = 0;
    std::vector<std::uint64_t> nodes;
    for (std::uint64_t b = 0; b < nblocks; ++b) {
      const size_t bs = p_;
      std::int64_t edim, etag, type;
      std::uint64_t n;
      if (binary_) {
        edim = bin_int("entity dimension", 0, 3);
        etag = bin_int("entity tag", 1, static_cast<std::int64_t>(kTagMax));
        type = bin_int("element type", std::numeric_limits<int>::min(),
                       std::numeric_limits<int>::max());
        n = bin_size("number of elements in block", total - read);
      } else {
        edim = integer("entity dimension", 0, 3);
        etag = integer("entity tag", 1, static_cast<std::int64_t>(kTagMax));
        type = integer("element type", std::numeric_limits<int>::min(),
                       std::numeric_limits<int>::max());
        n = integer("number of elements in block", 0, static_cast<std::int64_t>(total - read));
      }
      const ElemType* et = elem_type(type);
      if (!et)
        fail_at(bs, in() + "element type " + std::to_string(type) +
                        " is not supported (Gmsh types 1 to 31)");
      if (et->dim != edim)
        fail_at(bs, in() + "elements of type " + std::to_string(type) + " (dimension " +
                        std::to_string(et->dim) + ") in an entity of dimension " +
                        std::to_string(edim));
      if (!entities_.count({static_cast<int>(edim), etag}))
        fail_at(bs, in() + "element block of entity " + std::to_string(etag) + " (dimension " +
                        std::to_string(edim) + "), which is in neither $Entities nor $Nodes");
      const int nv = et->nodes;
      nodes.resize(nv);
      if (binary_) need(n, 8 * (1 + nv));
      for (std::uint64_t j = 0; j < n; ++j) {
        std::uint64_t tag;
        size_t at;
        if (binary_) {
          at = p_;
          tag = bin_size("element tag", kTagMax);
          if (tag == 0) fail_at(at, in() + "element tag 0 (tags start at 1)");
          for (int k = 0; k < nv; ++k) nodes[k] = bin_size("element node tag", kTagMax);
        } else {
          skip_ws();
          if (at_end()) truncated();
          at = p_;
          const std::string_view l = line();
          p_ = at;
          if (l.size() > 9000) fail(in() + "element line longer than 9000 characters");
          if (!std::all_of(l.begin(), l.end(), [](char c) { return (c >= '0' && c <= '9') || c == ' '; }))
            fail(in() + "unexpected character in element line '" + shown(l) + "'");
          const auto t = split(l);
          if (t.size() != static_cast<size_t>(1 + nv))
            fail(in() + "expected an element tag and " + std::to_string(nv) +
                 " node tags on one line, found '" + shown(l) + "'");
          tag = integer(t[0], "element tag", 1, static_cast<std::int64_t>(kTagMax));
          for (int k = 0; k < nv; ++k)
            nodes[k] = integer(t[1 + k], "node tag", 1, static_cast<std::int64_t>(kTagMax));
          line();
        }
        check_element_nodes(tag, nodes, at);
        elem_tags_.push_back(static_cast<std::uint32_t>(tag));
      }
      read += n;
    }
    if (read != total)
      fail(in() + "the header announces " + std::to_string(total) +
           " elements but the blocks hold " + std::to_string(read));
  }

  void nodes2() {
    const std::int64_t n = count_line("number of nodes", static_cast<std::int64_t>(kTagMax));
    if (binary_) need(n, 28);
    node_tags_.reserve(n);
    for (std::int64_t i = 0; i < n; ++i) {
      if (binary_) {
        node_tags_.push_back(
            static_cast<std::uint32_t>(bin_int("node tag", 1, static_cast<std::int64_t>(kTagMax))));
        for (int k = 0; k < 3; ++k) bin_real("node coordinate");
      } else {
        node_tags_.push_back(
            static_cast<std::uint32_t>(integer("node tag", 1, static_cast<std::int64_t>(kTagMax))));
        for (int k = 0; k < 3; ++k) real("node coordinate");
      }
    }
  }

  void elements2() {
    const std::int64_t n = count_line("number of elements", static_cast<std::int64_t>(kTagMax));
    std::vector<std::uint64_t> nodes;
    const std::int64_t imin = std::numeric_limits<int>::min(), imax = std::numeric_limits<int>::max();
    if (!binary_) {
      for (std::int64_t i = 0; i < n; ++i) {
        skip_ws();
        const size_t at = p_;
        const std::int64_t tag = integer("element tag", 1, imax);
        const std::int64_t type = integer("element type", imin, imax);
        const ElemType* et = elem_type(type);
        if (!et)
          fail_at(at, in() + "element " + std::to_string(tag) + ": type " + std::to_string(type) +
                          " is not supported (Gmsh types 1 to 31)");
        const std::int64_t ntags = integer("number of element tags", 0, 3);
        for (std::int64_t k = 0; k < ntags; ++k) integer("element tag value", imin, imax);
        nodes.resize(et->nodes);
        for (auto& v : nodes) v = integer("element node tag", 1, imax);
        check_element_nodes(tag, nodes, at);
        elem_tags_.push_back(static_cast<std::uint32_t>(tag));
      }
      return;
    }
    std::int64_t read = 0;
    while (read < n) {
      const size_t bs = p_;
      const std::int64_t type = bin_int("element type", imin, imax);
      const ElemType* et = elem_type(type);
      if (!et)
        fail_at(bs, in() + "element type " + std::to_string(type) +
                        " is not supported (Gmsh types 1 to 31)");
      const std::int64_t ne = bin_int("number of elements in block", 1, n - read);
      const std::int64_t ntags = bin_int("number of element tags", 0, 2);
      need(ne, 4 * (1 + ntags + et->nodes));
      nodes.resize(et->nodes);
      for (std::int64_t j = 0; j < ne; ++j) {
        const size_t at = p_;
        const std::int64_t tag = bin_int("element tag", 1, imax);
        p_ += 4 * ntags;
        for (auto& v : nodes) v = bin_int("element node tag", 1, imax);
        check_element_nodes(tag, nodes, at);
        elem_tags_.push_back(static_cast<std::uint32_t>(tag));
      }
      read += ne;
    }
  }

  const std::string& path_;
  const std::string d_;
  size_t p_ = 0;
  bool v4_ = false;
  bool binary_ = false;
  std::string section_ = "MeshFormat";
  std::set<std::pair<int, std::int64_t>> entities_;  // (dim, tag) known to the MSH 4 reader
  std::vector<std::uint32_t> node_tags_;             // sorted after $Nodes
  std::vector<std::uint32_t> elem_tags_;
};

}  // namespace

void check_msh_structure(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": mesh file cannot be opened for reading");
  std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw InputError(path + ": error while reading the mesh file");
  if (data.empty()) throw InputError(path + ": the mesh file is empty");
  Scanner(path, std::move(data)).run();
}

}  // namespace fdem::mesh_detail
