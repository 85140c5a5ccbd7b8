#pragma once
// Internals of the structural .msh check (msh_check.hpp), shared by its three files:
//   msh_tokens.cpp    text helpers, Gmsh's element type table and MshCursor (the tokenizer over the
//                     file's bytes: lines, tokens, integers, reals, binary values, messages);
//   msh_check.cpp     MshScanner's section loop, $MeshFormat, $PhysicalNames, section markers;
//   msh_sections.cpp  MshScanner's $Entities, $Nodes and $Elements (MSH 2.2 and 4.1).
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <set>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace fdem::mesh_detail::msh {

constexpr std::uint64_t kTagMax = static_cast<std::uint64_t>(std::numeric_limits<int>::max());
constexpr std::uint64_t kMaxEntities = 100000;  // Gmsh allocates 128 bytes per entity and line

// Gmsh element types 1..31: nodes per element and dimension.
struct ElemType {
  int nodes;
  int dim;
};
const ElemType* elem_type(std::int64_t t);  // nullptr outside 1..31

inline bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
}
bool blank(std::string_view s);
std::vector<std::string_view> split(std::string_view s);  // whitespace-separated tokens
std::string shown(std::string_view s);  // first 40 characters, non-printable ones as '?'
// Printable UTF-8 (no control characters; strict: no overlong forms, surrogates or > U+10FFFF),
// so that names taken from the file can go into JSON reports.
bool valid_utf8_text(std::string_view s);

// Reading position in the file's bytes, with the primitives the section readers use. Every
// failure throws InputError naming the file, the line (ASCII) or byte offset (binary) and, for
// data inside a section, the section.
class MshCursor {
 public:
  MshCursor(const std::string& path, std::string data) : path_(path), d_(std::move(data)) {}

 protected:
  // messages
  [[noreturn]] void fail_at(std::size_t at, const std::string& msg) const;
  [[noreturn]] void fail(const std::string& msg) const { fail_at(p_, msg); }
  std::string in() const { return "$" + section_ + ": "; }
  [[noreturn]] void truncated() const;

  // text
  bool at_end() const { return p_ >= d_.size(); }
  // The rest of the current line without its "\n" (and a trailing "\r"); moves past the "\n".
  std::string_view line() {
    const std::size_t nl = d_.find('\n', p_);
    const std::size_t end = nl == std::string::npos ? d_.size() : nl;
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
    const std::size_t b = p_;
    while (p_ < d_.size() && !is_space(d_[p_])) ++p_;
    return std::string_view(d_.data() + b, p_ - b);
  }
  // Integer token: [-]?[0-9]+ (unsigned: [0-9]+) within [lo, hi].
  std::int64_t integer(std::string_view t, const std::string& what, std::int64_t lo,
                       std::int64_t hi) const;
  std::int64_t integer(const std::string& what, std::int64_t lo, std::int64_t hi) {
    return integer(token(), what, lo, hi);
  }
  double real(std::string_view t, const std::string& what) const;
  double real(const std::string& what) { return real(token(), what); }
  // A count alone on its line (Gmsh reads it with fgets + sscanf).
  std::int64_t count_line(const std::string& what, std::int64_t hi);
  // The next line, from the next non-blank character, for a reader that parses it token by
  // token; the position stays at its start (messages point at this line). Fails at the end.
  std::string_view peek_line();

  // binary
  template <class T>
  T bin() {
    if (d_.size() - p_ < sizeof(T)) truncated();
    T v;
    std::memcpy(&v, d_.data() + p_, sizeof v);
    p_ += sizeof v;
    return v;
  }
  std::int64_t bin_int(const std::string& what, std::int64_t lo, std::int64_t hi);
  std::uint64_t bin_size(const std::string& what, std::uint64_t hi);
  double bin_real(const std::string& what);
  // Fails early if `n` records of `each` bytes cannot fit in the rest of the file.
  void need(std::uint64_t n, std::uint64_t each) const {
    if (each > 0 && n > (d_.size() - p_) / each) truncated();
  }

  const std::string& path_;
  const std::string d_;
  std::size_t p_ = 0;
  bool binary_ = false;
  std::string section_ = "MeshFormat";
};

// The whole-file scan: sections in order, each checked by its reader.
class MshScanner : public MshCursor {
 public:
  using MshCursor::MshCursor;
  void run();

 private:
  // msh_check.cpp: section loop, markers, $MeshFormat, $PhysicalNames
  void first_line();
  bool next_section(std::size_t& start, std::string& name);
  void read_section(const std::string& name, std::size_t start, std::set<std::string>& seen);
  void refuse_gmsh_section(const std::string& name, std::size_t start) const;
  void end_marker(const std::string& name);
  void skip_unknown(const std::string& name, std::size_t start);
  void format();
  void names();

  // msh_sections.cpp: $Entities, $Nodes, $Elements
  struct Block {  // header of an MSH 4.1 node or element block
    std::int64_t edim, etag, kind;  // kind: parametric flag (nodes) or element type (elements)
    std::uint64_t n;
  };
  void entities();
  std::int64_t entity_binary(int dim);
  std::int64_t entity_text(int dim);
  std::uint64_t section_counts4(const std::string& noun, std::uint64_t each, std::uint64_t& total);
  Block block_header4(const std::string& kind, std::int64_t lo, std::int64_t hi,
                      const std::string& count, std::uint64_t left);
  const ElemType& element_block_type(const Block& b, std::size_t at) const;
  std::uint64_t element4_binary(std::vector<std::uint64_t>& nodes, std::size_t& at);
  std::uint64_t element4_text(std::vector<std::uint64_t>& nodes, std::size_t& at);
  void nodes4();
  void elements4();
  void nodes2();
  void elements2();
  void elements2_binary(std::int64_t n);
  void check_element_nodes(std::uint64_t elem, const std::vector<std::uint64_t>& nodes,
                           std::size_t at) const;

  bool v4_ = false;
  std::set<std::pair<int, std::int64_t>> entities_;  // (dim, tag) known to the MSH 4 reader
  std::vector<std::uint32_t> node_tags_;             // sorted after $Nodes
  std::vector<std::uint32_t> elem_tags_;
};

}  // namespace fdem::mesh_detail::msh
