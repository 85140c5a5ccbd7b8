// JSON side of the case reader: the text parser with its limits and the typed Reader.
#include "io/json_reader.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <utility>

#include "common/error.hpp"

namespace fdem::case_detail {
namespace {

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

struct DuplicateKey {
  std::string path;
};

// Parser callback state: the key path of the current container, and the keys seen in each open
// object; throws DuplicateKey for a key seen twice in one object.
class KeyTracker {
 public:
  bool on_event(json::parse_event_t ev, json& parsed) {
    switch (ev) {
      case json::parse_event_t::object_start:
      case json::parse_event_t::array_start: {
        names_.push_back(member_name());
        Frame f;
        f.array = ev == json::parse_event_t::array_start;
        frames_.push_back(std::move(f));
        break;
      }
      case json::parse_event_t::key: {
        std::string k = parsed.get<std::string>();
        if (!frames_.back().keys.insert(k).second) {
          std::string p;
          for (size_t i = 1; i < names_.size(); ++i) p = child(p, names_[i]);
          throw DuplicateKey{child(p, k)};
        }
        frames_.back().key = k;
        break;
      }
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        frames_.pop_back();
        names_.pop_back();
        element_done();
        break;
      case json::parse_event_t::value:
        element_done();
        break;
    }
    return true;
  }

 private:
  struct Frame {
    bool array = false;
    size_t index = 0;
    std::string key;
    std::set<std::string> keys;
  };
  std::string member_name() const {
    if (frames_.empty()) return {};
    const Frame& f = frames_.back();
    return f.array ? std::to_string(f.index) : f.key;
  }
  void element_done() {
    if (!frames_.empty() && frames_.back().array) ++frames_.back().index;
  }
  std::vector<Frame> frames_;
  std::vector<std::string> names_;  // path of the current container
};

// "invalid JSON at line L, column C (byte B): <what>" for a syntax error.
std::string syntax_error_text(const json::parse_error& e, const std::string& text) {
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
  return "invalid JSON at line " + std::to_string(line) + ", column " + std::to_string(col) +
         " (byte " + std::to_string(e.byte) + "): " + what;
}

}  // namespace

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

void Reader::fail(const std::string& path, const std::string& msg) const {
  throw InputError(src_ + ": " + (path.empty() ? std::string() : path + ": ") + msg);
}

void Reader::require_object(const json& v, const std::string& path) const {
  if (!v.is_object()) fail(path, "expected an object, got " + describe(v));
}

void Reader::keys(const json& obj, const std::string& path,
                  const std::vector<std::string>& allowed) const {
  require_object(obj, path);
  for (auto it = obj.begin(); it != obj.end(); ++it) {
    if (std::find(allowed.begin(), allowed.end(), it.key()) != allowed.end()) continue;
    throw InputError(src_ + ": unknown key '" + child(path, it.key()) + "'" +
                     did_you_mean(it.key(), allowed) + " (allowed keys" +
                     (path.empty() ? std::string() : " in '" + path + "'") + ": " +
                     join(allowed) + ")");
  }
}

double Reader::number_value(const json& v, const std::string& p, const Range& r) const {
  if (!v.is_number()) fail(p, "expected a number, got " + describe(v));
  double x = v.get<double>();
  if (!std::isfinite(x)) fail(p, "value is not a finite number");
  if (!r.contains(x))
    fail(p, "value " + fmt_num(x) + " is out of range (allowed: " + r.text() + ")");
  return x;
}

double Reader::number(json& obj, const std::string& path, const char* key, const Range& r,
                      std::optional<double> def) const {
  const std::string p = child(path, key);
  auto it = obj.find(key);
  if (it == obj.end()) {
    if (!def) fail(p, "required key is missing");
    obj[key] = *def;
    return *def;
  }
  return number_value(*it, p, r);
}

long Reader::integer_value(const json& v, const std::string& p, long lo, long hi) const {
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

long Reader::integer(json& obj, const std::string& path, const char* key, long lo, long hi,
                     std::optional<long> def) const {
  const std::string p = child(path, key);
  auto it = obj.find(key);
  if (it == obj.end()) {
    if (!def) fail(p, "required key is missing");
    obj[key] = *def;
    return *def;
  }
  return integer_value(*it, p, lo, hi);
}

std::string Reader::string_value(const json& v, const std::string& p) const {
  if (!v.is_string()) fail(p, "expected a string, got " + describe(v));
  return v.get<std::string>();
}

std::string Reader::string(json& obj, const std::string& path, const char* key,
                           std::optional<std::string> def) const {
  const std::string p = child(path, key);
  auto it = obj.find(key);
  if (it == obj.end()) {
    if (!def) fail(p, "required key is missing");
    obj[key] = *def;
    return *def;
  }
  return string_value(*it, p);
}

std::string Reader::name(json& obj, const std::string& path, const char* key,
                         std::optional<std::string> def) const {
  std::string s = string(obj, path, key, def);
  if (!valid_name(s))
    fail(child(path, key), "'" + s + "' is not a valid name (allowed: letters, digits, '_', '-', '.')");
  return s;
}

Vec3 Reader::vec_value(const json& v, const std::string& p, int dim, const Range& r) const {
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

Vec3 Reader::vec(json& obj, const std::string& path, const char* key, int dim, std::optional<Vec3> def,
                 const Range& r) const {
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

json& Reader::object(json& obj, const std::string& path, const char* key, bool required) const {
  auto it = obj.find(key);
  if (it == obj.end()) {
    if (required) fail(child(path, key), "required key is missing");
    obj[key] = json::object();
    return obj[key];
  }
  require_object(*it, child(path, key));
  return *it;
}

json& Reader::array(json& obj, const std::string& path, const char* key, bool required) const {
  auto it = obj.find(key);
  if (it == obj.end()) {
    if (required) fail(child(path, key), "required key is missing");
    obj[key] = json::array();
    return obj[key];
  }
  if (!it->is_array()) fail(child(path, key), "expected an array, got " + describe(*it));
  return *it;
}

std::array<bool, 3> Reader::components(json& obj, const std::string& path, int dim) const {
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

void check_depth(const json& j, const std::string& src, const std::string& what) {
  if (json_depth(j) > kMaxDepth)
    throw InputError(src + ": " + what + " nests objects/arrays more than " +
                     std::to_string(kMaxDepth) + " levels deep");
}

json parse_text(const std::string& text, const std::string& src) {
  KeyTracker tracker;
  json::parser_callback_t cb = [&tracker](int, json::parse_event_t ev, json& parsed) -> bool {
    return tracker.on_event(ev, parsed);
  };
  try {
    return json::parse(text, cb, /*allow_exceptions=*/true, /*ignore_comments=*/true);
  } catch (const DuplicateKey& d) {
    throw InputError(src + ": " + d.path + ": duplicate key (each key may appear once per object)");
  } catch (const json::parse_error& e) {
    throw InputError(src + ": " + syntax_error_text(e, text));
  } catch (const json::exception& e) {
    // e.g. "number overflow parsing '1e400'"
    std::string what = e.what();
    size_t close = what.find("] ");
    if (close != std::string::npos) what = what.substr(close + 2);
    throw InputError(src + ": invalid JSON: " + what + " (numbers must be finite)");
  }
}

json parse_value_text(const std::string& text, std::string& dup) {
  KeyTracker tracker;
  json::parser_callback_t cb = [&tracker](int, json::parse_event_t ev, json& parsed) -> bool {
    return tracker.on_event(ev, parsed);
  };
  dup.clear();
  try {
    return json::parse(text, cb, /*allow_exceptions=*/true);
  } catch (const DuplicateKey& d) {
    dup = d.path;
  } catch (const json::exception&) {
    // not JSON
  }
  return json(json::value_t::discarded);
}

void check_finite(const json& j, const std::string& path, const Reader& R) {
  if (j.is_number_float() && !std::isfinite(j.get<double>()))
    R.fail(path, "value is not a finite number");
  if (j.is_object())
    for (auto it = j.begin(); it != j.end(); ++it) check_finite(*it, child(path, it.key()), R);
  if (j.is_array())
    for (size_t i = 0; i < j.size(); ++i) check_finite(j[i], child(path, i), R);
}

}  // namespace fdem::case_detail
