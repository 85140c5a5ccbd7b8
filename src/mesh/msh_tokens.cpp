// Tokenizer of the structural .msh check (msh_scan.hpp): text helpers, Gmsh's element type table
// and the MshCursor primitives that read integers, reals and binary values with range checks.
#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "common/error.hpp"
#include "mesh/msh_scan.hpp"

namespace fdem::mesh_detail::msh {

const ElemType* elem_type(std::int64_t t) {
  // clang-format off
  static const ElemType table[32] = {
      {0, -1}, {2, 1},  {3, 2},  {4, 2},  {4, 3},  {8, 3},  {6, 3},  {5, 3},
      {3, 1},  {6, 2},  {9, 2},  {10, 3}, {27, 3}, {18, 3}, {14, 3}, {1, 0},
      {8, 2},  {20, 3}, {15, 3}, {13, 3}, {9, 2},  {10, 2}, {12, 2}, {15, 2},
      {15, 2}, {21, 2}, {4, 1},  {5, 1},  {6, 1},  {20, 3}, {35, 3}, {56, 3}};
  // clang-format on
  return t >= 1 && t <= 31 ? &table[t] : nullptr;
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

// ------------------------------------------------------------------------------ messages

void MshCursor::fail_at(std::size_t at, const std::string& msg) const {
  std::string where;
  if (binary_) {
    where = "byte " + std::to_string(at);
  } else {
    const std::size_t upto = std::min(at, d_.size());
    where = "line " + std::to_string(1 + std::count(d_.begin(), d_.begin() + upto, '\n'));
  }
  throw InputError(path_ + ": " + where + ": " + msg);
}

void MshCursor::truncated() const {
  fail(in() + "unexpected end of file (the file is truncated or a count is too large)");
}

// ------------------------------------------------------------------------------ text

std::int64_t MshCursor::integer(std::string_view t, const std::string& what, std::int64_t lo,
                                std::int64_t hi) const {
  bool neg = !t.empty() && t[0] == '-';
  std::string_view digits = neg ? t.substr(1) : t;
  bool ok = !digits.empty() && digits.size() <= 18 &&
            std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; });
  if (!ok) fail(in() + what + ": expected an integer, found '" + shown(t) + "'");
  std::int64_t v = 0;
  for (char c : digits) v = v * 10 + (c - '0');
  if (neg) v = -v;
  if (v < lo || v > hi)
    fail(in() + what + " " + std::string(t) + " is out of range (allowed: " + std::to_string(lo) + " to " +
         std::to_string(hi) + ")");
  return v;
}

double MshCursor::real(std::string_view t, const std::string& what) const {
  const std::string s(t);
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (s.empty() || end != s.c_str() + s.size())
    fail(in() + what + ": expected a number, found '" + shown(t) + "'");
  if (!std::isfinite(v)) fail(in() + what + " '" + shown(t) + "' is not a finite number");
  return v;
}

std::int64_t MshCursor::count_line(const std::string& what, std::int64_t hi) {
  const std::size_t s = p_;
  const auto t = split(line());
  if (t.size() != 1) fail_at(s, in() + "expected the " + what + " alone on its line");
  p_ = s;
  skip_ws();
  const std::int64_t v = integer(t[0], what, 0, hi);
  line();
  return v;
}

std::string_view MshCursor::peek_line() {
  skip_ws();
  if (at_end()) truncated();
  const std::size_t s = p_;
  const std::string_view l = line();
  p_ = s;
  return l;
}

// ------------------------------------------------------------------------------ binary

std::int64_t MshCursor::bin_int(const std::string& what, std::int64_t lo, std::int64_t hi) {
  const std::size_t at = p_;
  const std::int64_t v = bin<std::int32_t>();
  if (v < lo || v > hi)
    fail_at(at, in() + what + " " + std::to_string(v) + " is out of range (allowed: " + std::to_string(lo) +
                    " to " + std::to_string(hi) + ")");
  return v;
}

std::uint64_t MshCursor::bin_size(const std::string& what, std::uint64_t hi) {
  const std::size_t at = p_;
  const std::uint64_t v = bin<std::uint64_t>();
  if (v > hi)
    fail_at(at, in() + what + " " + std::to_string(v) + " is out of range (allowed: 0 to " +
                    std::to_string(hi) + ")");
  return v;
}

double MshCursor::bin_real(const std::string& what) {
  const std::size_t at = p_;
  const double v = bin<double>();
  if (!std::isfinite(v)) fail_at(at, in() + what + " is not a finite number");
  return v;
}

}  // namespace fdem::mesh_detail::msh
