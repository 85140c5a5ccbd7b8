#pragma once
// JSON side of the case reader (src/io/case.cpp): the text parser with its limits (duplicate keys,
// nesting depth), and `Reader`, typed access to the document with allowed ranges and key paths in
// every message. Internal to the reader; not part of io/case.hpp.
#include <array>
#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/case_text.hpp"

namespace fdem::case_detail {

using json = nlohmann::json;
using Vec3 = std::array<double, 3>;  // the same type as fdem::Vec3 (io/case.hpp)

constexpr double kInf = std::numeric_limits<double>::infinity();

// "null", "a boolean (true)", "a string (\"...\")", "an object", "an array", "a number (1.5)".
std::string describe(const json& v);

// Allowed interval of a number, with its text for messages.
struct Range {
  double lo = -kInf, hi = kInf;
  bool lo_open = false, hi_open = false;
  bool contains(double x) const {
    if (lo_open ? !(x > lo) : !(x >= lo)) return false;
    if (hi_open ? !(x < hi) : !(x <= hi)) return false;
    return true;
  }
  std::string text() const {
    std::vector<std::string> parts;
    if (lo > -kInf) parts.push_back((lo_open ? "> " : ">= ") + fmt_num(lo));
    if (hi < kInf) parts.push_back((hi_open ? "< " : "<= ") + fmt_num(hi));
    return parts.empty() ? "any finite number" : join(parts, " and ");
  }
};
inline Range gt(double a) { return Range{a, kInf, true, false}; }
inline Range ge(double a) { return Range{a, kInf, false, false}; }
inline Range any() { return Range{}; }
inline Range between(double lo, bool lo_open, double hi, bool hi_open) {
  return Range{lo, hi, lo_open, hi_open};
}

// Reader: typed access to the document with key paths in every message; missing optional keys
// get their default written into the document (which becomes Case::resolved). Every failure throws
// InputError "<source>: <key path>: <message>".
class Reader {
 public:
  explicit Reader(std::string src) : src_(std::move(src)) {}
  const std::string& src() const { return src_; }

  [[noreturn]] void fail(const std::string& path, const std::string& msg) const;

  void require_object(const json& v, const std::string& path) const;

  // Every key of `obj` must be in `allowed`.
  void keys(const json& obj, const std::string& path, const std::vector<std::string>& allowed) const;

  double number_value(const json& v, const std::string& p, const Range& r) const;
  double number(json& obj, const std::string& path, const char* key, const Range& r,
                std::optional<double> def = std::nullopt) const;

  long integer_value(const json& v, const std::string& p, long lo, long hi) const;
  long integer(json& obj, const std::string& path, const char* key, long lo, long hi,
               std::optional<long> def = std::nullopt) const;

  std::string string_value(const json& v, const std::string& p) const;
  std::string string(json& obj, const std::string& path, const char* key,
                     std::optional<std::string> def = std::nullopt) const;

  // A name used as a reference (material, region, set, platen): non-empty, no blanks.
  std::string name(json& obj, const std::string& path, const char* key,
                   std::optional<std::string> def = std::nullopt) const;

  Vec3 vec_value(const json& v, const std::string& p, int dim, const Range& r = any()) const;
  Vec3 vec(json& obj, const std::string& path, const char* key, int dim,
           std::optional<Vec3> def = std::nullopt, const Range& r = any()) const;

  // Sub-object; a missing optional one is created empty (and then filled with defaults).
  json& object(json& obj, const std::string& path, const char* key, bool required) const;
  json& array(json& obj, const std::string& path, const char* key, bool required) const;

  // "components": letters from "xy" (2D) or "xyz" (3D), each at most once. Default: all.
  std::array<bool, 3> components(json& obj, const std::string& path, int dim) const;

 private:
  std::string src_;
};

// Nesting depth: the walks over the document are recursive, so a hostile file such as
// [[[[...]]]] nested 100000 deep would overflow the stack. Case files nest 4 or 5 levels.
constexpr size_t kMaxDepth = 64;

// Throws InputError "<src>: <what> nests objects/arrays more than 64 levels deep" if it does.
void check_depth(const json& j, const std::string& src, const std::string& what);

// JSON text -> document: syntax errors with line/column, duplicate keys rejected (InputError).
json parse_text(const std::string& text, const std::string& src);

// JSON text -> value, as parse_text reads it (each object's keys tracked) but without throwing:
// a discarded value when the text is not JSON (a number that overflows included), and in `dup`
// the key path (inside the text) of the first key that appears twice in one object, e.g. "kn" or
// "0.a" ("" when none does). For --set values, which are refused the same way as a case file's
// duplicate keys (io/overrides.cpp).
json parse_value_text(const std::string& text, std::string& dup);

// Every number of the document must be finite.
void check_finite(const json& j, const std::string& path, const Reader& R);

}  // namespace fdem::case_detail
