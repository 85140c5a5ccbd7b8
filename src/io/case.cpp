// Case file reader: JSON -> overrides -> parameters -> validation -> Case. See docs/case-format.md.
#include "io/case.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <utility>

#include "common/error.hpp"

namespace fdem {
namespace {

using json = nlohmann::json;
namespace fs = std::filesystem;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPi = 3.14159265358979323846;

// ---------------------------------------------------------------------------------------------
// Small text helpers

std::string fmt_num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

std::string join(const std::vector<std::string>& v, const char* sep = ", ") {
  std::string s;
  for (size_t i = 0; i < v.size(); ++i) {
    if (i) s += sep;
    s += v[i];
  }
  return s;
}

std::string quoted_list(std::vector<std::string> v, bool sort = true) {
  if (sort) std::sort(v.begin(), v.end());
  if (v.empty()) return "none";
  for (auto& s : v) s = "'" + s + "'";
  return join(v);
}

std::string child(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}
std::string child(const std::string& path, size_t i) { return child(path, std::to_string(i)); }

// Lower case, without '_', '-' and blanks: "Young_Modulus" -> "youngmodulus".
std::string normalise(const std::string& s) {
  std::string r;
  for (char ch : s)
    if (ch != '_' && ch != '-' && ch != ' ')
      r += static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  return r;
}

size_t edit_distance(const std::string& a, const std::string& b) {
  // Optimal string alignment distance: insertions, deletions, substitutions, adjacent swaps.
  const size_t n = a.size(), m = b.size();
  std::vector<std::vector<size_t>> d(n + 1, std::vector<size_t>(m + 1, 0));
  for (size_t i = 0; i <= n; ++i) d[i][0] = i;
  for (size_t j = 0; j <= m; ++j) d[0][j] = j;
  for (size_t i = 1; i <= n; ++i)
    for (size_t j = 1; j <= m; ++j) {
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1,
                          d[i - 1][j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[n][m];
}

// Common names people use for the keys of a case file (normalised) -> the key.
const std::map<std::string, std::string>& aliases() {
  static const std::map<std::string, std::string> m = {
      {"young", "E"}, {"youngs", "E"}, {"youngmodulus", "E"}, {"youngsmodulus", "E"},
      {"modulus", "E"}, {"elasticmodulus", "E"}, {"emodulus", "E"}, {"ym", "E"},
      {"poisson", "nu"}, {"poissons", "nu"}, {"poissonratio", "nu"}, {"poissonsratio", "nu"},
      {"v", "nu"}, {"rho", "density"}, {"massdensity", "density"},
      {"phi", "phi_deg"}, {"frictionangle", "phi_deg"}, {"angle", "phi_deg"},
      {"cohesion", "c"}, {"tensilestrength", "ft"}, {"tension", "ft"}, {"sigmat", "ft"},
      {"normalstiffness", "kn"}, {"shearstiffness", "ks"},
      {"gic", "Gnc"}, {"g1c", "Gnc"}, {"gi", "Gnc"}, {"gf", "Gnc"}, {"gn", "Gnc"},
      {"giic", "Gsc"}, {"g2c", "Gsc"}, {"gii", "Gsc"}, {"gs", "Gsc"},
      {"bk", "eta"}, {"bkexponent", "eta"}, {"exponent", "eta"},
      {"centre", "center"}, {"h", "element_size"}, {"meshsize", "element_size"},
      {"elementsize", "element_size"}, {"size", "element_size"}, {"dim", "dimension"},
      {"mu", "friction"}, {"frictioncoefficient", "friction"}, {"speed", "velocity"},
      {"ramp", "ramp_time"}, {"alpha", "local"}, {"localdamping", "local"},
      {"cfl", "safety_factor"}, {"courant", "safety_factor"}, {"safety", "safety_factor"},
      {"tend", "end_time"}, {"duration", "end_time"}, {"tmax", "end_time"},
      {"timestep", "dt"}, {"steps", "max_steps"}, {"nsteps", "max_steps"},
      {"fixedcomponents", "components"}, {"dofs", "components"}, {"dof", "components"},
      {"nodeset", "set"}, {"nodes", "set"}, {"group", "set"},
      {"mesh", "file"}, {"path", "file"}, {"filename", "file"}, {"type", "generator"},
      {"kind", "generator"}, {"nelem", "cells"}, {"divisions", "cells"}, {"n", "cells"},
      {"material", "interface_material"}, {"interfacematerial", "interface_material"},
      {"r", "radius"}, {"planestress", "plane"}, {"planestrain", "plane"}, {"t", "thickness"},
      {"history", "history_rows"}, {"rows", "history_rows"}, {"snapshots", "snapshot_count"},
      {"bc", "boundary"}, {"bcs", "boundary"}, {"platen", "platens"}, {"g", "gravity"},
      {"fixed_nodes", "fixed"}, {"loads", "point_loads"}, {"forces", "point_loads"},
      {"bulkmaterials", "materials"}, {"interfaces", "interface_materials"},
  };
  return m;
}

// The nearest of `candidates` to `key`, or "" if none is close.
std::string suggest(const std::string& key, const std::vector<std::string>& candidates) {
  const std::string nk = normalise(key);
  auto al = aliases().find(nk);
  if (al != aliases().end() &&
      std::find(candidates.begin(), candidates.end(), al->second) != candidates.end())
    return al->second;
  std::string best;
  size_t best_d = std::numeric_limits<size_t>::max();
  for (const auto& c : candidates) {
    size_t d = edit_distance(nk, normalise(c));
    if (d < best_d) best_d = d, best = c;
  }
  // prefix match ("elem" -> "element_size")
  if (best_d > 0 && nk.size() >= 3)
    for (const auto& c : candidates)
      if (normalise(c).rfind(nk, 0) == 0) return c;
  const size_t limit = std::max<size_t>(2, nk.size() / 3);
  return best_d <= limit ? best : std::string();
}

std::string did_you_mean(const std::string& key, const std::vector<std::string>& candidates) {
  std::string s = suggest(key, candidates);
  return s.empty() ? std::string() : "; did you mean '" + s + "'?";
}

std::string describe(const json& v) {
  switch (v.type()) {
    case json::value_t::null: return "null";
    case json::value_t::boolean: return std::string("a boolean (") + (v.get<bool>() ? "true" : "false") + ")";
    case json::value_t::string: {
      std::string s = v.get<std::string>();
      if (s.size() > 40) s = s.substr(0, 37) + "...";
      return "a string (\"" + s + "\")";
    }
    case json::value_t::object: return "an object";
    case json::value_t::array: return "an array";
    default: return "a number (" + v.dump() + ")";
  }
}

bool valid_name(const std::string& s) {
  if (s.empty()) return false;
  for (char ch : s)
    if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '-' || ch == '.'))
      return false;
  return true;
}

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
Range gt(double a) { return Range{a, kInf, true, false}; }
Range ge(double a) { return Range{a, kInf, false, false}; }
Range any() { return Range{}; }
Range between(double lo, bool lo_open, double hi, bool hi_open) { return Range{lo, hi, lo_open, hi_open}; }

// ---------------------------------------------------------------------------------------------
// Reader: typed access to the document with key paths in every message; missing optional keys
// get their default written into the document (which becomes Case::resolved).

class Reader {
 public:
  explicit Reader(std::string src) : src_(std::move(src)) {}
  const std::string& src() const { return src_; }

  [[noreturn]] void fail(const std::string& path, const std::string& msg) const {
    throw InputError(src_ + ": " + (path.empty() ? std::string() : path + ": ") + msg);
  }

  void require_object(const json& v, const std::string& path) const {
    if (!v.is_object()) fail(path, "expected an object, got " + describe(v));
  }

  // Every key of `obj` must be in `allowed`.
  void keys(const json& obj, const std::string& path, const std::vector<std::string>& allowed) const {
    require_object(obj, path);
    for (auto it = obj.begin(); it != obj.end(); ++it) {
      if (std::find(allowed.begin(), allowed.end(), it.key()) != allowed.end()) continue;
      throw InputError(src_ + ": unknown key '" + child(path, it.key()) + "'" +
                       did_you_mean(it.key(), allowed) + " (allowed keys" +
                       (path.empty() ? std::string() : " in '" + path + "'") + ": " +
                       join(allowed) + ")");
    }
  }

  double number_value(const json& v, const std::string& p, const Range& r) const {
    if (!v.is_number()) fail(p, "expected a number, got " + describe(v));
    double x = v.get<double>();
    if (!std::isfinite(x)) fail(p, "value is not a finite number");
    if (!r.contains(x))
      fail(p, "value " + fmt_num(x) + " is out of range (allowed: " + r.text() + ")");
    return x;
  }

  double number(json& obj, const std::string& path, const char* key, const Range& r,
                std::optional<double> def = std::nullopt) const {
    const std::string p = child(path, key);
    auto it = obj.find(key);
    if (it == obj.end()) {
      if (!def) fail(p, "required key is missing");
      obj[key] = *def;
      return *def;
    }
    return number_value(*it, p, r);
  }

  long integer_value(const json& v, const std::string& p, long lo, long hi) const {
    if (!v.is_number()) fail(p, "expected an integer, got " + describe(v));
    double x = v.get<double>();
    if (!std::isfinite(x) || x != std::floor(x)) fail(p, "expected an integer, got " + v.dump());
    std::string allowed =
        hi - lo <= 10 ? std::to_string(lo) + " to " + std::to_string(hi)
                      : ">= " + std::to_string(lo) +
                            (hi == std::numeric_limits<long>::max() ? std::string()
                                                                    : " and <= " + std::to_string(hi));
    // static_cast<double>(LONG_MAX) rounds up to 2^63, which does not fit in a long.
    if (x < static_cast<double>(lo) || x > static_cast<double>(hi) || x >= 0x1p63)
      fail(p, "value " + fmt_num(x) + " is out of range (allowed: integer " + allowed + ")");
    return static_cast<long>(x);
  }

  long integer(json& obj, const std::string& path, const char* key, long lo, long hi,
               std::optional<long> def = std::nullopt) const {
    const std::string p = child(path, key);
    auto it = obj.find(key);
    if (it == obj.end()) {
      if (!def) fail(p, "required key is missing");
      obj[key] = *def;
      return *def;
    }
    return integer_value(*it, p, lo, hi);
  }

  std::string string_value(const json& v, const std::string& p) const {
    if (!v.is_string()) fail(p, "expected a string, got " + describe(v));
    return v.get<std::string>();
  }

  std::string string(json& obj, const std::string& path, const char* key,
                     std::optional<std::string> def = std::nullopt) const {
    const std::string p = child(path, key);
    auto it = obj.find(key);
    if (it == obj.end()) {
      if (!def) fail(p, "required key is missing");
      obj[key] = *def;
      return *def;
    }
    return string_value(*it, p);
  }

  // A name used as a reference (material, region, set, platen): non-empty, no blanks.
  std::string name(json& obj, const std::string& path, const char* key,
                   std::optional<std::string> def = std::nullopt) const {
    std::string s = string(obj, path, key, def);
    if (!valid_name(s))
      fail(child(path, key), "'" + s + "' is not a valid name (allowed: letters, digits, '_', '-', '.')");
    return s;
  }

  Vec3 vec_value(const json& v, const std::string& p, int dim, const Range& r = any()) const {
    const char* form = dim == 2 ? "[x, y]" : "[x, y, z]";
    if (!v.is_array())
      fail(p, "expected an array of " + std::to_string(dim) + " numbers " + form + ", got " + describe(v));
    if (static_cast<int>(v.size()) != dim)
      fail(p, "expected " + std::to_string(dim) + " components " + form + " for dimension " +
                  std::to_string(dim) + ", got " + std::to_string(v.size()));
    Vec3 out{0, 0, 0};
    for (int i = 0; i < dim; ++i) out[i] = number_value(v[i], child(p, i), r);
    return out;
  }

  Vec3 vec(json& obj, const std::string& path, const char* key, int dim,
           std::optional<Vec3> def = std::nullopt, const Range& r = any()) const {
    const std::string p = child(path, key);
    auto it = obj.find(key);
    if (it == obj.end()) {
      if (!def) fail(p, "required key is missing");
      json a = json::array();
      for (int i = 0; i < dim; ++i) a.push_back((*def)[i]);
      obj[key] = a;
      return *def;
    }
    return vec_value(*it, p, dim, r);
  }

  // Sub-object; a missing optional one is created empty (and then filled with defaults).
  json& object(json& obj, const std::string& path, const char* key, bool required) const {
    auto it = obj.find(key);
    if (it == obj.end()) {
      if (required) fail(child(path, key), "required key is missing");
      obj[key] = json::object();
      return obj[key];
    }
    require_object(*it, child(path, key));
    return *it;
  }

  json& array(json& obj, const std::string& path, const char* key, bool required) const {
    auto it = obj.find(key);
    if (it == obj.end()) {
      if (required) fail(child(path, key), "required key is missing");
      obj[key] = json::array();
      return obj[key];
    }
    if (!it->is_array()) fail(child(path, key), "expected an array, got " + describe(*it));
    return *it;
  }

  // "components": letters from "xy" (2D) or "xyz" (3D), each at most once. Default: all.
  std::array<bool, 3> components(json& obj, const std::string& path, int dim) const {
    const std::string all = dim == 2 ? "xy" : "xyz";
    std::string s = string(obj, path, "components", all);
    std::array<bool, 3> on{false, false, false};
    auto bad = [&](const std::string& why) {
      fail(child(path, "components"), "'" + s + "' " + why + " (allowed: letters from '" + all +
                                          "', each at most once, e.g. '" + all + "')");
    };
    if (s.empty()) bad("is empty");
    for (char ch : s) {
      size_t k = all.find(ch);
      if (k == std::string::npos)
        bad(std::string("has '") + ch + "', not a component for dimension " + std::to_string(dim));
      if (on[k]) bad(std::string("repeats '") + ch + "'");
      on[k] = true;
    }
    return on;
  }

 private:
  std::string src_;
};

// ---------------------------------------------------------------------------------------------
// Nesting depth: the walks over the document below are recursive, so a hostile file such as
// [[[[...]]]] nested 100000 deep would overflow the stack. Case files nest 4 or 5 levels.

constexpr size_t kMaxDepth = 64;

// Iterative (no recursion): the depth of `j`, counting containers; stops above kMaxDepth.
size_t json_depth(const json& j) {
  std::vector<std::pair<const json*, size_t>> stack{{&j, 1}};
  size_t depth = 0;
  while (!stack.empty()) {
    auto [v, d] = stack.back();
    stack.pop_back();
    if (!v->is_structured()) continue;
    depth = std::max(depth, d);
    if (depth > kMaxDepth) break;
    for (const auto& e : *v) stack.push_back({&e, d + 1});
  }
  return depth;
}

void check_depth(const json& j, const std::string& src, const std::string& what) {
  if (json_depth(j) > kMaxDepth)
    throw InputError(src + ": " + what + " nests objects/arrays more than " +
                     std::to_string(kMaxDepth) + " levels deep");
}

// ---------------------------------------------------------------------------------------------
// JSON text -> document (syntax errors with line/column, duplicate keys rejected)

struct DuplicateKey {
  std::string path;
};

json parse_text(const std::string& text, const std::string& src) {
  struct Frame {
    bool array = false;
    size_t index = 0;
    std::string key;
    std::set<std::string> keys;
  };
  std::vector<Frame> frames;
  std::vector<std::string> names;  // path of the current container
  auto member_name = [&]() -> std::string {
    if (frames.empty()) return {};
    const Frame& f = frames.back();
    return f.array ? std::to_string(f.index) : f.key;
  };
  auto element_done = [&]() {
    if (!frames.empty() && frames.back().array) ++frames.back().index;
  };
  json::parser_callback_t cb = [&](int, json::parse_event_t ev, json& parsed) -> bool {
    switch (ev) {
      case json::parse_event_t::object_start:
      case json::parse_event_t::array_start: {
        names.push_back(member_name());
        Frame f;
        f.array = ev == json::parse_event_t::array_start;
        frames.push_back(std::move(f));
        break;
      }
      case json::parse_event_t::key: {
        std::string k = parsed.get<std::string>();
        if (!frames.back().keys.insert(k).second) {
          std::string p;
          for (size_t i = 1; i < names.size(); ++i) p = child(p, names[i]);
          throw DuplicateKey{child(p, k)};
        }
        frames.back().key = k;
        break;
      }
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        frames.pop_back();
        names.pop_back();
        element_done();
        break;
      case json::parse_event_t::value:
        element_done();
        break;
    }
    return true;
  };
  try {
    return json::parse(text, cb, /*allow_exceptions=*/true, /*ignore_comments=*/true);
  } catch (const DuplicateKey& d) {
    throw InputError(src + ": " + d.path + ": duplicate key (each key may appear once per object)");
  } catch (const json::parse_error& e) {
    // Line and column of the offending byte.
    size_t byte = e.byte > 0 ? e.byte - 1 : 0;
    size_t line = 1, col = 1;
    for (size_t i = 0; i < byte && i < text.size(); ++i) {
      if (text[i] == '\n') ++line, col = 1;
      else ++col;
    }
    std::string what = e.what();
    size_t colon = what.find(": ");
    if (what.rfind("[json.exception", 0) == 0 && colon != std::string::npos) {
      // "[json.exception.parse_error.101] parse error at line 3, column 5: syntax error ..."
      std::string rest = what.substr(colon + 2);
      what = rest.empty() ? what : rest;
    }
    throw InputError(src + ": invalid JSON at line " + std::to_string(line) + ", column " +
                     std::to_string(col) + " (byte " + std::to_string(e.byte) + "): " + what);
  } catch (const json::exception& e) {
    // e.g. "number overflow parsing '1e400'"
    std::string what = e.what();
    size_t close = what.find("] ");
    if (close != std::string::npos) what = what.substr(close + 2);
    throw InputError(src + ": invalid JSON: " + what + " (numbers must be finite)");
  }
}

// ---------------------------------------------------------------------------------------------
// --set overrides

void apply_override(json& doc, const std::string& ov, const Reader& R) {
  // The resolved case is written out as JSON, which must be UTF-8 (a case file is, as parsed).
  try {
    (void)json(ov).dump();
  } catch (const json::exception&) {
    throw InputError(R.src() + ": --set: the override is not valid UTF-8 text");
  }
  const std::string where = "--set '" + ov + "'";
  const size_t eq = ov.find('=');
  if (eq == std::string::npos)
    throw InputError(R.src() + ": " + where + ": expected key.path=value (e.g. time.end_time=0.01)");
  const std::string key = ov.substr(0, eq);
  const std::string text = ov.substr(eq + 1);
  std::vector<std::string> segs;
  {
    size_t start = 0;
    while (true) {
      size_t dot = key.find('.', start);
      segs.push_back(key.substr(start, dot == std::string::npos ? std::string::npos : dot - start));
      if (dot == std::string::npos) break;
      start = dot + 1;
    }
  }
  for (const auto& s : segs)
    if (s.empty())
      throw InputError(R.src() + ": " + where + ": empty key in '" + key +
                       "' (expected key.path=value, e.g. platens.0.velocity.1=-0.1)");

  json value = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (value.is_discarded()) {
    // A number that overflows is an error, anything else that is not JSON is a string.
    char* end = nullptr;
    double x = std::strtod(text.c_str(), &end);
    if (!text.empty() && end && *end == '\0' && !std::isfinite(x) &&
        (std::isdigit(static_cast<unsigned char>(text[0])) || text[0] == '-' || text[0] == '+' ||
         text[0] == '.'))
      throw InputError(R.src() + ": " + where + ": value '" + text + "' is not a finite number");
    value = text;
  }

  check_depth(value, R.src(), where + ": the value");

  json* cur = &doc;
  std::string path;
  for (size_t i = 0; i < segs.size(); ++i) {
    const std::string& seg = segs[i];
    const bool last = i + 1 == segs.size();
    const std::string here = child(path, seg);
    if (cur->is_object()) {
      if (last) {
        (*cur)[seg] = std::move(value);
        return;
      }
      auto it = cur->find(seg);
      if (it == cur->end()) {
        std::vector<std::string> existing;
        for (auto jt = cur->begin(); jt != cur->end(); ++jt) existing.push_back(jt.key());
        throw InputError(R.src() + ": " + where + ": '" + here + "' does not exist" +
                         did_you_mean(seg, existing) + " (existing keys" +
                         (path.empty() ? std::string() : " in '" + path + "'") + ": " +
                         join(existing) + "; to add a missing object set it whole, e.g. --set '" +
                         here + "={...}')");
      }
      cur = &*it;
    } else if (cur->is_array()) {
      bool digits = !seg.empty() && std::all_of(seg.begin(), seg.end(), [](char ch) {
        return std::isdigit(static_cast<unsigned char>(ch));
      });
      if (!digits)
        throw InputError(R.src() + ": " + where + ": '" + path + "' is an array; '" + seg +
                         "' is not an index (use 0, 1, ...)");
      size_t idx = seg.size() > 9 ? std::numeric_limits<size_t>::max() : std::stoul(seg);
      if (idx >= cur->size())
        throw InputError(R.src() + ": " + where + ": '" + path + "' has " +
                         std::to_string(cur->size()) + " elements; index " + seg +
                         " does not exist (allowed: 0 to " +
                         std::to_string(cur->empty() ? 0 : cur->size() - 1) + ")");
      if (last) {
        (*cur)[idx] = std::move(value);
        return;
      }
      cur = &(*cur)[idx];
    } else {
      throw InputError(R.src() + ": " + where + ": '" + path + "' is " + describe(*cur) +
                       ", not an object or array, so '" + here + "' cannot be set");
    }
    path = here;
  }
}

// ---------------------------------------------------------------------------------------------
// Parameters: "parameters": {"rate": 0.05}; a string value "=expr" anywhere else is replaced by
// the value of expr (numbers, parameter names, pi, + - * /, parentheses).

class Expr {
 public:
  Expr(const std::string& s, const std::map<std::string, double>& params, const Reader& R,
       const std::string& path)
      : s_(s), params_(params), R_(R), path_(path) {}

  double eval() {
    pos_ = 1;  // skip '='
    double v = sum();
    skip();
    if (pos_ != s_.size()) error("unexpected '" + s_.substr(pos_, 1) + "'");
    if (!std::isfinite(v)) error("the result is not finite (division by zero?)");
    return v;
  }

 private:
  [[noreturn]] void error(const std::string& why) const {
    std::vector<std::string> names;
    for (const auto& kv : params_) names.push_back(kv.first);
    const std::string shown = s_.size() > 80 ? s_.substr(0, 77) + "..." : s_;
    R_.fail(path_, "expression '" + shown + "': " + why + " (expressions use numbers, parameters (" +
                       (names.empty() ? std::string("none defined") : join(names)) +
                       "), pi, + - * / and parentheses)");
  }
  void skip() {
    while (pos_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[pos_]))) ++pos_;
  }
  double sum() {
    double v = product();
    while (true) {
      skip();
      if (pos_ < s_.size() && (s_[pos_] == '+' || s_[pos_] == '-')) {
        char op = s_[pos_++];
        double w = product();
        v = op == '+' ? v + w : v - w;
      } else {
        return v;
      }
    }
  }
  double product() {
    double v = unary();
    while (true) {
      skip();
      if (pos_ < s_.size() && (s_[pos_] == '*' || s_[pos_] == '/')) {
        char op = s_[pos_++];
        double w = unary();
        v = op == '*' ? v * w : v / w;
      } else {
        return v;
      }
    }
  }
  double unary() {
    skip();
    if (pos_ < s_.size() && (s_[pos_] == '-' || s_[pos_] == '+')) {
      char op = s_[pos_++];
      Nest nest(*this);
      double v = unary();
      return op == '-' ? -v : v;
    }
    return primary();
  }
  // Recursion guard: "=((((...1...))))" or "=------1" nested without limit would overflow the stack.
  struct Nest {
    explicit Nest(Expr& e) : e_(e) {
      if (++e_.depth_ > 100) e_.error("nested more than 100 levels deep");
    }
    ~Nest() { --e_.depth_; }
    Expr& e_;
  };
  double primary() {
    skip();
    if (pos_ >= s_.size()) error("unexpected end");
    char ch = s_[pos_];
    if (ch == '(') {
      ++pos_;
      Nest nest(*this);
      double v = sum();
      skip();
      if (pos_ >= s_.size() || s_[pos_] != ')') error("missing ')'");
      ++pos_;
      return v;
    }
    if (std::isdigit(static_cast<unsigned char>(ch)) || ch == '.') {
      const char* begin = s_.c_str() + pos_;
      char* end = nullptr;
      double v = std::strtod(begin, &end);
      if (end == begin) error("bad number");
      pos_ += static_cast<size_t>(end - begin);
      return v;
    }
    if (std::isalpha(static_cast<unsigned char>(ch)) || ch == '_') {
      size_t start = pos_;
      while (pos_ < s_.size() &&
             (std::isalnum(static_cast<unsigned char>(s_[pos_])) || s_[pos_] == '_'))
        ++pos_;
      std::string name = s_.substr(start, pos_ - start);
      auto it = params_.find(name);
      if (it != params_.end()) return it->second;
      if (name == "pi") return kPi;
      std::vector<std::string> names;
      for (const auto& kv : params_) names.push_back(kv.first);
      error("unknown parameter '" + name + "'" + did_you_mean(name, names));
    }
    error("unexpected '" + std::string(1, ch) + "'");
  }

  const std::string& s_;
  const std::map<std::string, double>& params_;
  const Reader& R_;
  std::string path_;
  size_t pos_ = 0;
  int depth_ = 0;
};

void substitute(json& j, const std::string& path, const std::map<std::string, double>& params,
                const Reader& R) {
  if (j.is_string()) {
    const std::string& s = j.get_ref<const std::string&>();
    if (!s.empty() && s[0] == '=') {
      std::string copy = s;
      j = Expr(copy, params, R, path).eval();
    }
  } else if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it) {
      if (path.empty() && it.key() == "parameters") continue;
      substitute(it.value(), child(path, it.key()), params, R);
    }
  } else if (j.is_array()) {
    for (size_t i = 0; i < j.size(); ++i) substitute(j[i], child(path, i), params, R);
  }
}

// Null members of objects are the same as absent ones (so --set key=null removes an option).
void strip_nulls(json& j) {
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end();) {
      if (it->is_null()) {
        it = j.erase(it);
      } else {
        strip_nulls(*it);
        ++it;
      }
    }
  } else if (j.is_array()) {
    for (auto& e : j) strip_nulls(e);
  }
}

void check_finite(const json& j, const std::string& path, const Reader& R) {
  if (j.is_number_float() && !std::isfinite(j.get<double>()))
    R.fail(path, "value is not a finite number");
  if (j.is_object())
    for (auto it = j.begin(); it != j.end(); ++it) check_finite(*it, child(path, it.key()), R);
  if (j.is_array())
    for (size_t i = 0; i < j.size(); ++i) check_finite(j[i], child(path, i), R);
}

std::string default_name(const std::string& source) {
  fs::path p(source);
  std::string stem = p.stem().string();
  if (stem == "case" && p.has_parent_path()) {
    std::string dir = p.parent_path().filename().string();
    if (valid_name(dir)) return dir;
  }
  return valid_name(stem) ? stem : std::string("case");
}

// ---------------------------------------------------------------------------------------------
// Sections

void read_mesh(json& doc, Case& c, const Reader& R, const fs::path& base_dir, bool check_files) {
  json& m = R.object(doc, "", "mesh", true);
  const std::string P = "mesh";
  MeshSpec& s = c.mesh;
  const bool has_file = m.contains("file"), has_gen = m.contains("generator");
  if (has_file && has_gen) R.fail(P, "give either 'file' or 'generator', not both");
  if (!has_file && !has_gen) {
    if (!m.empty()) R.keys(m, P, {"file", "generator"});
    R.fail(P, "give either 'file' (a Gmsh .msh or .geo file) or 'generator' (rectangle, disc, box, sphere)");
  }
  if (has_file) {
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
    return;
  }
  const std::vector<std::string> gens = {"rectangle", "disc", "box", "sphere"};
  std::string g = R.string(m, P, "generator");
  if (std::find(gens.begin(), gens.end(), g) == gens.end())
    R.fail(child(P, "generator"), "unknown generator '" + g + "'" + did_you_mean(g, gens) +
                                      " (allowed: rectangle, disc (2D); box, sphere (3D))");
  const bool is2 = g == "rectangle" || g == "disc";
  if ((is2 ? 2 : 3) != c.dim)
    R.fail(child(P, "generator"), "generator '" + g + "' makes a " + (is2 ? "2D" : "3D") +
                                      " mesh but dimension is " + std::to_string(c.dim) +
                                      " (allowed: " + (c.dim == 2 ? "rectangle, disc" : "box, sphere") + ")");
  s.kind = g;
  const int d = c.dim;
  if (g == "rectangle" || g == "box") {
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
  } else {
    R.keys(m, P, {"generator", "center", "radius", "element_size", "region"});
    s.origin = R.vec(m, P, "center", d, Vec3{0, 0, 0});
    s.radius = R.number(m, P, "radius", gt(0));
    s.element_size = R.number(m, P, "element_size", between(0, true, s.radius, false));
  }
  s.region = R.name(m, P, "region", std::string("body"));
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
    R.keys(*it, p, {"kn", "ks", "ft", "c", "phi_deg", "Gnc", "Gsc", "eta"});
    InterfaceMaterial m;
    m.name = it.key();
    m.kn = R.number(*it, p, "kn", gt(0));
    m.ks = R.number(*it, p, "ks", gt(0));
    m.ft = R.number(*it, p, "ft", ge(0));
    m.c = R.number(*it, p, "c", ge(0));
    m.phi = R.number(*it, p, "phi_deg", between(0, false, 90, true)) * kPi / 180.0;
    m.Gnc = R.number(*it, p, "Gnc", gt(0));
    m.Gsc = R.number(*it, p, "Gsc", gt(0));
    m.eta = R.number(*it, p, "eta", gt(0), 2.0);
    c.interface_materials.push_back(m);
  }
  if (!doc.contains("fracture")) return;
  json& f = R.object(doc, "", "fracture", false);
  R.keys(f, "fracture", {"regions", "interface_material", "strength_reduction"});
  if (f.contains("strength_reduction")) {
    json& sr = R.object(f, "fracture", "strength_reduction", false);
    const std::string sp = "fracture.strength_reduction";
    R.keys(sr, sp, {"initial", "start_time", "rate"});
    c.srf_initial = R.number(sr, sp, "initial", gt(0), 1.0);
    c.srf_start = R.number(sr, sp, "start_time", ge(0), 0.0);
    c.srf_rate = R.number(sr, sp, "rate", ge(0), 0.0);
  }
  json& regs = R.array(f, "fracture", "regions", true);
  if (regs.empty()) R.fail("fracture.regions", "at least one region is needed (omit 'fracture' for no fracture)");
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
}

void read_boundary(json& doc, Case& c, const Reader& R) {
  const int d = c.dim;
  json& b = R.object(doc, "", "boundary", false);
  const std::string P = "boundary";
  R.keys(b, P, {"fixed", "velocity", "point_loads", "gravity", "initial_velocity"});

  json& fixed = R.array(b, P, "fixed", false);
  for (size_t i = 0; i < fixed.size(); ++i) {
    const std::string p = child(child(P, "fixed"), i);
    R.keys(fixed[i], p, {"set", "components"});
    VelocityBC bc;
    bc.set = R.name(fixed[i], p, "set");
    bc.active = R.components(fixed[i], p, d);
    c.velocity_bcs.push_back(bc);
  }
  json& vel = R.array(b, P, "velocity", false);
  for (size_t i = 0; i < vel.size(); ++i) {
    const std::string p = child(child(P, "velocity"), i);
    R.keys(vel[i], p, {"set", "velocity", "components", "ramp_time"});
    VelocityBC bc;
    bc.set = R.name(vel[i], p, "set");
    bc.velocity = R.vec(vel[i], p, "velocity", d);
    bc.active = R.components(vel[i], p, d);
    for (int k = 0; k < d; ++k)
      if (!bc.active[k] && bc.velocity[k] != 0.0)
        R.fail(child(child(p, "velocity"), static_cast<size_t>(k)),
               "component " + std::string(1, "xyz"[k]) + " is " + fmt_num(bc.velocity[k]) +
                   " but is not in components '" + vel[i]["components"].get<std::string>() +
                   "' (allowed: 0, or add it to components)");
    bc.ramp_time = R.number(vel[i], p, "ramp_time", ge(0), 0.0);
    c.velocity_bcs.push_back(bc);
  }
  json& loads = R.array(b, P, "point_loads", false);
  for (size_t i = 0; i < loads.size(); ++i) {
    const std::string p = child(child(P, "point_loads"), i);
    R.keys(loads[i], p, {"set", "force"});
    PointLoad pl;
    pl.set = R.name(loads[i], p, "set");
    pl.force = R.vec(loads[i], p, "force", d);
    c.point_loads.push_back(pl);
  }
  c.gravity = R.vec(b, P, "gravity", d, Vec3{0, 0, 0});
  json& iv = R.array(b, P, "initial_velocity", false);
  std::vector<std::string> known;
  for (const auto& kv : c.region_material) known.push_back(kv.first);
  for (size_t i = 0; i < iv.size(); ++i) {
    const std::string p = child(child(P, "initial_velocity"), i);
    R.keys(iv[i], p, {"region", "velocity"});
    InitialVelocity v;
    v.region = R.name(iv[i], p, "region", std::string("all"));
    if (v.region != "all" && !c.region_material.count(v.region))
      R.fail(child(p, "region"), "region '" + v.region + "' has no material in 'regions'" +
                                     did_you_mean(v.region, known) + " (allowed: 'all', " +
                                     quoted_list(known) + ")");
    v.velocity = R.vec(iv[i], p, "velocity", d);
    c.initial_velocities.push_back(v);
  }
}

void read_platens(json& doc, Case& c, const Reader& R) {
  const int d = c.dim;
  json& pl = R.array(doc, "", "platens", false);
  for (size_t i = 0; i < pl.size(); ++i) {
    const std::string p = child("platens", i);
    R.keys(pl[i], p, {"name", "point", "normal", "velocity", "kn", "ks", "friction", "cohesion"});
    PlatenSpec s;
    s.name = R.name(pl[i], p, "name");
    for (const auto& o : c.platens)
      if (o.name == s.name) R.fail(child(p, "name"), "platen name '" + s.name + "' is used twice");
    s.point = R.vec(pl[i], p, "point", d);
    Vec3 n = R.vec(pl[i], p, "normal", d);
    double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 0)) R.fail(child(p, "normal"), "the normal is zero (allowed: any non-zero vector; it is normalised)");
    for (auto& x : n) x /= len;
    s.normal = n;
    s.velocity = R.vec(pl[i], p, "velocity", d, Vec3{0, 0, 0});
    s.kn = R.number(pl[i], p, "kn", ge(0), 0.0);
    s.ks = R.number(pl[i], p, "ks", ge(0), 0.0);
    s.friction = R.number(pl[i], p, "friction", ge(0), 0.0);
    s.cohesion = R.number(pl[i], p, "cohesion", ge(0), 0.0);
    c.platens.push_back(s);
  }
}

void read_contact(json& doc, Case& c, const Reader& R) {
  json& ct = R.object(doc, "", "contact", false);
  const std::string P = "contact";
  R.keys(ct, P, {"enabled", "kn", "ks", "friction", "cohesion", "skin"});
  auto it = ct.find("enabled");
  if (it == ct.end()) {
    ct["enabled"] = "auto";
    c.contact.enabled = -1;
  } else if (it->is_boolean()) {
    c.contact.enabled = it->get<bool>() ? 1 : 0;
  } else if (it->is_string() && it->get<std::string>() == "auto") {
    c.contact.enabled = -1;
  } else {
    R.fail(child(P, "enabled"), "expected true, false or \"auto\", got " + describe(*it));
  }
  c.contact.kn = R.number(ct, P, "kn", ge(0), 0.0);
  c.contact.ks = R.number(ct, P, "ks", ge(0), 0.0);
  const double mu0 =
      c.fracture_material >= 0 ? std::tan(c.interface_materials[c.fracture_material].phi) : 0.0;
  c.contact.friction = R.number(ct, P, "friction", ge(0), mu0);
  c.contact.cohesion = R.number(ct, P, "cohesion", ge(0), 0.0);
  c.contact.skin = R.number(ct, P, "skin", ge(0), 0.0);
}

void read_damping(json& doc, Case& c, const Reader& R) {
  json& dmp = R.object(doc, "", "damping", false);
  R.keys(dmp, "damping", {"local", "mass_proportional", "change"});
  c.local_damping = R.number(dmp, "damping", "local", between(0, false, 1, true), 0.0);
  c.mass_damping = R.number(dmp, "damping", "mass_proportional", ge(0), 0.0);
  if (dmp.contains("change")) {
    json& ch = R.object(dmp, "damping", "change", false);
    const std::string cp = "damping.change";
    R.keys(ch, cp, {"time", "local", "mass_proportional"});
    c.damping_change_time = R.number(ch, cp, "time", ge(0));
    c.damping_change_local = R.number(ch, cp, "local", between(0, false, 1, true), 0.0);
    c.damping_change_mass = R.number(ch, cp, "mass_proportional", ge(0), 0.0);
  }
}

void read_time(json& doc, Case& c, const Reader& R) {
  json& t = R.object(doc, "", "time", true);
  const std::string P = "time";
  R.keys(t, P, {"safety_factor", "dt", "end_time", "max_steps", "stop", "check_interval"});
  c.safety_factor = R.number(t, P, "safety_factor", between(0, true, 2, false), 0.5);
  c.dt = R.number(t, P, "dt", ge(0), 0.0);
  c.end_time = R.number(t, P, "end_time", gt(0));
  c.max_steps = R.integer(t, P, "max_steps", 0, std::numeric_limits<long>::max(), 0L);
  c.check_interval =
      static_cast<int>(R.integer(t, P, "check_interval", 1, std::numeric_limits<int>::max(), 100L));
  if (t.contains("stop")) {
    json& s = R.object(t, P, "stop", false);
    const std::string sp = "time.stop";
    R.keys(s, sp, {"platen", "drop_fraction"});
    std::string name = R.string(s, sp, "platen");
    std::vector<std::string> names;
    for (const auto& p : c.platens) names.push_back(p.name);
    if (std::find(names.begin(), names.end(), name) == names.end())
      R.fail(child(sp, "platen"), "no platen named '" + name + "'" + did_you_mean(name, names) +
                                      " (platens: " + quoted_list(names, false) + ")");
    c.stop_platen = name;
    c.stop_drop_fraction = R.number(s, sp, "drop_fraction", between(0, true, 1, true));
  }
}

void read_output(json& doc, Case& c, const Reader& R) {
  json& o = R.object(doc, "", "output", false);
  const std::string P = "output";
  R.keys(o, P, {"history_interval", "history_rows", "snapshot_interval", "snapshot_count", "monitors",
                "fragments", "checkpoint_every"});
  if (o.contains("monitors")) {
    json& arr = R.array(o, P, "monitors", false);
    for (size_t i = 0; i < arr.size(); ++i) c.monitors.push_back(R.string_value(arr[i], child(child(P, "monitors"), i)));
  }
  if (o.contains("history_interval") && o.contains("history_rows"))
    R.fail(P, "give either 'history_interval' or 'history_rows', not both");
  if (o.contains("snapshot_interval") && o.contains("snapshot_count"))
    R.fail(P, "give either 'snapshot_interval' or 'snapshot_count', not both");
  if (o.contains("history_interval")) {
    c.history_interval = R.number(o, P, "history_interval", gt(0));
  } else {
    long rows = R.integer(o, P, "history_rows", 1, 100000000L, 200L);
    c.history_interval = c.end_time / static_cast<double>(rows);
  }
  if (o.contains("snapshot_interval")) {
    c.snapshot_interval = R.number(o, P, "snapshot_interval", ge(0));
  } else {
    long n = R.integer(o, P, "snapshot_count", 0, 1000000L, 0L);
    c.snapshot_interval = n > 0 ? c.end_time / static_cast<double>(n) : 0.0;
  }
  if (o.contains("fragments")) {
    if (!o["fragments"].is_boolean())
      R.fail(child(P, "fragments"), "expected true or false, got " + describe(o["fragments"]));
    c.output_fragments = o["fragments"].get<bool>();
  } else {
    o["fragments"] = true;
  }
  if (o.contains("checkpoint_every")) c.checkpoint_every = R.number(o, P, "checkpoint_every", ge(0));
}

Case parse_impl(json doc, const std::string& source, const std::vector<std::string>& overrides,
                const fs::path& base_dir, bool check_files) {
  Reader R(source);
  if (!doc.is_object()) R.fail("", "a case file must hold one JSON object {...}, got " + describe(doc));
  check_depth(doc, source, "the case");
  for (const auto& ov : overrides) apply_override(doc, ov, R);
  strip_nulls(doc);

  // parameters and expressions
  std::map<std::string, double> params;
  if (doc.contains("parameters")) {
    json& pj = doc["parameters"];
    R.require_object(pj, "parameters");
    for (auto it = pj.begin(); it != pj.end(); ++it) {
      const std::string p = child("parameters", it.key());
      const std::string& k = it.key();
      bool ident = !k.empty() && (std::isalpha(static_cast<unsigned char>(k[0])) || k[0] == '_') &&
                   std::all_of(k.begin(), k.end(), [](char ch) {
                     return std::isalnum(static_cast<unsigned char>(ch)) || ch == '_';
                   });
      if (!ident) R.fail(p, "'" + k + "' is not a valid parameter name (allowed: letters, digits, '_', not starting with a digit)");
      params[k] = R.number_value(*it, p, any());
    }
  }
  substitute(doc, "", params, R);
  check_finite(doc, "", R);

  R.keys(doc, "", {"name", "description", "dimension", "parameters", "mesh", "analysis",
                   "materials", "regions", "interface_materials", "fracture", "boundary",
                   "platens", "contact", "damping", "time", "output"});
  Case c;
  c.file = source;
  c.dim = static_cast<int>(R.integer(doc, "", "dimension", 2, 3));
  c.name = R.name(doc, "", "name", default_name(source));
  if (doc.contains("description")) R.string(doc, "", "description");
  read_mesh(doc, c, R, base_dir, check_files);
  read_analysis(doc, c, R);
  read_materials(doc, c, R);
  read_interfaces(doc, c, R);
  read_boundary(doc, c, R);
  read_platens(doc, c, R);
  read_contact(doc, c, R);
  read_damping(doc, c, R);
  read_time(doc, c, R);
  read_output(doc, c, R);
  c.resolved = std::move(doc);
  return c;
}

}  // namespace

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
  json doc = parse_text(ss.str(), path);
  fs::path base = fs::path(path).parent_path();
  return parse_impl(std::move(doc), path, overrides, base, true);
}

Case parse_case(nlohmann::json doc, const std::string& source,
                const std::vector<std::string>& overrides) {
  return parse_impl(std::move(doc), source, overrides, fs::path(source).parent_path(), false);
}

void check_case_against_mesh(const Case& c, const HostMesh& mesh) {
  const std::string src = c.file.empty() ? std::string("case") : c.file;
  auto fail = [&](const std::string& path, const std::string& msg) {
    throw InputError(src + ": " + path + ": " + msg);
  };
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
  std::vector<std::string> sets;
  for (const auto& kv : mesh.node_sets) sets.push_back(kv.first);
  auto check_set = [&](const std::string& set, const std::string& path) {
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
}

}  // namespace fdem
