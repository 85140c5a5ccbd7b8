// Structural .msh check (msh_scan.hpp): the $Entities, $Nodes and $Elements sections of MSH 2.2
// and 4.1, ASCII and binary. Gmsh looks up nodes by `int` tag and indexes arrays with tags and
// counts from the file, so tags are 1 .. 2^31-1, counts must match the data and element nodes must
// be defined. MSH 4 entity lines and element lines are read line by line (fgets + sscanf
// "%[0-9- ]"), so an entity or element must be on one line, with plain integers.
#include <algorithm>
#include <limits>

#include "mesh/msh_scan.hpp"

namespace fdem::mesh_detail::msh {

// ------------------------------------------------------------------------------ $Entities (4.1)

// Points, curves, surfaces, volumes with physical tags and bounding entities.
void MshScanner::entities() {
  std::uint64_t cnt[4];
  std::uint64_t total = 0;
  for (auto& c : cnt) {
    c = binary_ ? bin_size("number of entities", kMaxEntities)
                : static_cast<std::uint64_t>(
                      integer("number of entities", 0, static_cast<std::int64_t>(kMaxEntities)));
    total += c;
  }
  if (total > kMaxEntities) fail(in() + "more than " + std::to_string(kMaxEntities) + " entities");
  for (int dim = 0; dim < 4; ++dim)
    for (std::uint64_t i = 0; i < cnt[dim]; ++i) {
      const std::int64_t tag = binary_ ? entity_binary(dim) : entity_text(dim);
      entities_.insert({dim, tag});
    }
}

// One binary entity record; returns its tag.
std::int64_t MshScanner::entity_binary(int dim) {
  const int nbox = dim == 0 ? 3 : 6;
  const std::int64_t tag = bin_int("entity tag", 1, static_cast<std::int64_t>(kTagMax));
  for (int k = 0; k < nbox; ++k) bin_real("entity bounding box");
  const std::uint64_t nphys = bin_size("number of physical tags", 100000);
  need(nphys, 4);
  p_ += nphys * 4;
  if (dim > 0) {
    const std::uint64_t nb = bin_size("number of bounding entities", 1000000);
    need(nb, 4);
    p_ += nb * 4;
  }
  return tag;
}

// One ASCII entity line; returns its tag.
std::int64_t MshScanner::entity_text(int dim) {
  const int nbox = dim == 0 ? 3 : 6;
  const std::string_view l = peek_line();
  if (l.size() > 4000) fail(in() + "entity line longer than 4000 characters");
  if (!std::all_of(l.begin(), l.end(), [](char c) {
        return (c >= '0' && c <= '9') || c == ' ' || c == '-' || c == '+' || c == '.' || c == 'e' || c == 'E';
      }))
    fail(in() + "unexpected character in entity line '" + shown(l) + "'");
  const auto t = split(l);
  size_t k = 0;
  auto next = [&]() -> std::string_view {
    if (k >= t.size()) fail(in() + "entity line is too short: '" + shown(l) + "'");
    return t[k++];
  };
  const std::int64_t tag = integer(next(), "entity tag", 1, static_cast<std::int64_t>(kTagMax));
  for (int b = 0; b < nbox; ++b) real(next(), "entity bounding box");
  const std::int64_t nphys = integer(next(), "number of physical tags", 0, 100000);
  for (std::int64_t j = 0; j < nphys; ++j)
    integer(next(), "physical tag", std::numeric_limits<int>::min(), std::numeric_limits<int>::max());
  if (dim > 0) {
    const std::int64_t nb = integer(next(), "number of bounding entities", 0, 1000000);
    for (std::int64_t j = 0; j < nb; ++j)
      integer(next(), "bounding entity tag", -static_cast<std::int64_t>(kTagMax),
              static_cast<std::int64_t>(kTagMax));
  }
  if (k != t.size()) fail(in() + "entity line has extra numbers: '" + shown(l) + "'");
  line();
  return tag;
}

// ------------------------------------------------------------------------------ MSH 4.1 blocks

// Section header of $Nodes or $Elements ("node" or "element"): returns the number of blocks and
// sets `total`. Binary files must have room for `each` bytes per item.
std::uint64_t MshScanner::section_counts4(const std::string& noun, std::uint64_t each, std::uint64_t& total) {
  std::uint64_t nblocks;
  if (binary_) {
    nblocks = bin_size("number of " + noun + " blocks", kTagMax);
    total = bin_size("number of " + noun + "s", kTagMax);
    bin<std::uint64_t>();  // min and max tag: Gmsh only warns if they are wrong
    bin<std::uint64_t>();
    need(total, each);
  } else {
    nblocks = integer("number of " + noun + " blocks", 0, kTagMax);
    total = integer("number of " + noun + "s", 0, kTagMax);
    integer("minimum " + noun + " tag", 0, std::numeric_limits<std::int64_t>::max());
    integer("maximum " + noun + " tag", 0, std::numeric_limits<std::int64_t>::max());
  }
  return nblocks;
}

// Block header: entity dimension, entity tag, `kind` in [lo, hi], and `count` items (at most
// `left`, what the section header leaves).
MshScanner::Block MshScanner::block_header4(const std::string& kind, std::int64_t lo, std::int64_t hi,
                                            const std::string& count, std::uint64_t left) {
  Block b;
  if (binary_) {
    b.edim = bin_int("entity dimension", 0, 3);
    b.etag = bin_int("entity tag", 1, static_cast<std::int64_t>(kTagMax));
    b.kind = bin_int(kind, lo, hi);
    b.n = bin_size(count, left);
  } else {
    b.edim = integer("entity dimension", 0, 3);
    b.etag = integer("entity tag", 1, static_cast<std::int64_t>(kTagMax));
    b.kind = integer(kind, lo, hi);
    b.n = integer(count, 0, static_cast<std::int64_t>(left));
  }
  return b;
}

void MshScanner::nodes4() {
  std::uint64_t total = 0;
  const std::uint64_t nblocks = section_counts4("node", 32, total);
  std::uint64_t read = 0;
  for (std::uint64_t b = 0; b < nblocks; ++b) {
    const Block blk = block_header4("parametric flag", 0, 1, "number of nodes in block", total - read);
    const std::uint64_t n = blk.n;
    entities_.insert({static_cast<int>(blk.edim), blk.etag});
    const std::int64_t ncoord = 3 + (blk.kind ? blk.edim : 0);
    if (binary_) need(n, 8 + 8 * ncoord);
    for (std::uint64_t j = 0; j < n; ++j)
      node_tags_.push_back(
          static_cast<std::uint32_t>(binary_ ? bin_size("node tag", kTagMax)
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

// The element type of an element block, checked against Gmsh's table, the block's entity
// dimension and the entities known so far. `at`: the block's start, for messages.
const ElemType& MshScanner::element_block_type(const Block& b, std::size_t at) const {
  const std::int64_t type = b.kind, edim = b.edim, etag = b.etag;
  const ElemType* et = elem_type(type);
  if (!et)
    fail_at(at, in() + "element type " + std::to_string(type) + " is not supported (Gmsh types 1 to 31)");
  if (et->dim != edim)
    fail_at(at, in() + "elements of type " + std::to_string(type) + " (dimension " + std::to_string(et->dim) +
                    ") in an entity of dimension " + std::to_string(edim));
  if (!entities_.count({static_cast<int>(edim), etag}))
    fail_at(at, in() + "element block of entity " + std::to_string(etag) + " (dimension " +
                    std::to_string(edim) + "), which is in neither $Entities nor $Nodes");
  return *et;
}

// One binary element record (tag and nodes.size() node tags); returns the tag, sets `at` to the
// record's start.
std::uint64_t MshScanner::element4_binary(std::vector<std::uint64_t>& nodes, std::size_t& at) {
  at = p_;
  const std::uint64_t tag = bin_size("element tag", kTagMax);
  if (tag == 0) fail_at(at, in() + "element tag 0 (tags start at 1)");
  for (auto& v : nodes) v = bin_size("element node tag", kTagMax);
  return tag;
}

// One ASCII element line (tag and nodes.size() node tags); returns the tag, sets `at` to the
// line's start.
std::uint64_t MshScanner::element4_text(std::vector<std::uint64_t>& nodes, std::size_t& at) {
  const int nv = static_cast<int>(nodes.size());
  const std::string_view l = peek_line();
  at = p_;
  if (l.size() > 9000) fail(in() + "element line longer than 9000 characters");
  if (!std::all_of(l.begin(), l.end(), [](char c) { return (c >= '0' && c <= '9') || c == ' '; }))
    fail(in() + "unexpected character in element line '" + shown(l) + "'");
  const auto t = split(l);
  if (t.size() != static_cast<size_t>(1 + nv))
    fail(in() + "expected an element tag and " + std::to_string(nv) + " node tags on one line, found '" +
         shown(l) + "'");
  const std::uint64_t tag = integer(t[0], "element tag", 1, static_cast<std::int64_t>(kTagMax));
  for (int k = 0; k < nv; ++k)
    nodes[k] = integer(t[1 + k], "node tag", 1, static_cast<std::int64_t>(kTagMax));
  line();
  return tag;
}

void MshScanner::elements4() {
  std::uint64_t total = 0;
  const std::uint64_t nblocks = section_counts4("element", 16, total);
  std::uint64_t read = 0;
  std::vector<std::uint64_t> nodes;
  for (std::uint64_t b = 0; b < nblocks; ++b) {
    const size_t bs = p_;
    const Block blk =
        block_header4("element type", std::numeric_limits<int>::min(), std::numeric_limits<int>::max(),
                      "number of elements in block", total - read);
    const int nv = element_block_type(blk, bs).nodes;
    nodes.resize(nv);
    if (binary_) need(blk.n, 8 * (1 + nv));
    for (std::uint64_t j = 0; j < blk.n; ++j) {
      size_t at;
      const std::uint64_t tag = binary_ ? element4_binary(nodes, at) : element4_text(nodes, at);
      check_element_nodes(tag, nodes, at);
      elem_tags_.push_back(static_cast<std::uint32_t>(tag));
    }
    read += blk.n;
  }
  if (read != total)
    fail(in() + "the header announces " + std::to_string(total) + " elements but the blocks hold " +
         std::to_string(read));
}

void MshScanner::check_element_nodes(std::uint64_t elem, const std::vector<std::uint64_t>& nodes,
                                     size_t at) const {
  for (std::uint64_t v : nodes)
    if (!std::binary_search(node_tags_.begin(), node_tags_.end(), v))
      fail_at(at, in() + "element " + std::to_string(elem) + " uses node " + std::to_string(v) +
                      ", which is not defined in $Nodes");
}

// ------------------------------------------------------------------------------ MSH 2.2

void MshScanner::nodes2() {
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

void MshScanner::elements2() {
  const std::int64_t n = count_line("number of elements", static_cast<std::int64_t>(kTagMax));
  if (binary_) return elements2_binary(n);
  std::vector<std::uint64_t> nodes;
  const std::int64_t imin = std::numeric_limits<int>::min(), imax = std::numeric_limits<int>::max();
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
}

// Binary MSH 2.2 elements: blocks of elements of one type with the same number of tags.
void MshScanner::elements2_binary(std::int64_t n) {
  std::vector<std::uint64_t> nodes;
  const std::int64_t imin = std::numeric_limits<int>::min(), imax = std::numeric_limits<int>::max();
  std::int64_t read = 0;
  while (read < n) {
    const size_t bs = p_;
    const std::int64_t type = bin_int("element type", imin, imax);
    const ElemType* et = elem_type(type);
    if (!et)
      fail_at(bs, in() + "element type " + std::to_string(type) + " is not supported (Gmsh types 1 to 31)");
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

}  // namespace fdem::mesh_detail::msh
