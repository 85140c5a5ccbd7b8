// `--set key.path=value` overrides of a case.
#include "io/overrides.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <utility>
#include <vector>

#include "common/error.hpp"

namespace fdem::case_detail {
namespace {

// "a.b.0" -> {"a", "b", "0"} (empty segments kept, to be reported).
std::vector<std::string> split_key(const std::string& key) {
  std::vector<std::string> segs;
  size_t start = 0;
  while (true) {
    size_t dot = key.find('.', start);
    segs.push_back(key.substr(start, dot == std::string::npos ? std::string::npos : dot - start));
    if (dot == std::string::npos) break;
    start = dot + 1;
  }
  return segs;
}

// The value text as JSON, or as a string when it is not JSON (a number that overflows is an error).
json parse_value(const std::string& text, const std::string& key, const std::string& where, const Reader& R) {
  std::string dup;
  json value = parse_value_text(text, dup);
  // the value's objects take each key once, as in a case file (json_reader.cpp, parse_text)
  if (!dup.empty())
    throw InputError(R.src() + ": " + where + ": " + child(key, dup) +
                     ": duplicate key (each key may appear once per object)");
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
  return value;
}

// The existing member `seg` of object `cur` (at key path `path`).
json* member(json& cur, const std::string& seg, const std::string& path, const std::string& where,
             const Reader& R) {
  auto it = cur.find(seg);
  if (it == cur.end()) {
    const std::string here = child(path, seg);
    std::vector<std::string> existing;
    for (auto jt = cur.begin(); jt != cur.end(); ++jt) existing.push_back(jt.key());
    throw InputError(R.src() + ": " + where + ": '" + here + "' does not exist" +
                     did_you_mean(seg, existing) + " (existing keys" +
                     (path.empty() ? std::string() : " in '" + path + "'") + ": " +
                     join(existing) + "; to add a missing object set it whole, e.g. --set '" +
                     here + "={...}')");
  }
  return &*it;
}

// The index `seg` of array `cur` (at key path `path`), which must exist.
size_t element(const json& cur, const std::string& seg, const std::string& path,
               const std::string& where, const Reader& R) {
  bool digits = !seg.empty() && std::all_of(seg.begin(), seg.end(), [](char ch) {
    return std::isdigit(static_cast<unsigned char>(ch));
  });
  if (!digits)
    throw InputError(R.src() + ": " + where + ": '" + path + "' is an array; '" + seg +
                     "' is not an index (use 0, 1, ...)");
  size_t idx = seg.size() > 9 ? std::numeric_limits<size_t>::max() : std::stoul(seg);
  if (idx >= cur.size())
    throw InputError(R.src() + ": " + where + ": '" + path + "' has " +
                     std::to_string(cur.size()) + " elements; index " + seg +
                     " does not exist (allowed: 0 to " +
                     std::to_string(cur.empty() ? 0 : cur.size() - 1) + ")");
  return idx;
}

// doc[segs...] = value.
void set_at(json& doc, const std::vector<std::string>& segs, json value, const std::string& where,
            const Reader& R) {
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
      cur = member(*cur, seg, path, where, R);
    } else if (cur->is_array()) {
      size_t idx = element(*cur, seg, path, where, R);
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

}  // namespace

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
  const std::vector<std::string> segs = split_key(key);
  for (const auto& s : segs)
    if (s.empty())
      throw InputError(R.src() + ": " + where + ": empty key in '" + key +
                       "' (expected key.path=value, e.g. platens.0.velocity.1=-0.1)");

  json value = parse_value(text, key, where, R);
  check_depth(value, R.src(), where + ": the value");
  set_at(doc, segs, std::move(value), where, R);
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

}  // namespace fdem::case_detail
