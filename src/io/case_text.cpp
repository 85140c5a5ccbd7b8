// Text helpers of the case reader and its "did you mean" suggestions.
#include "io/case_text.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <limits>
#include <map>
#include <string>
#include <vector>

namespace fdem::case_detail {
namespace {

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

}  // namespace

std::string fmt_num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

std::string join(const std::vector<std::string>& v, const char* sep) {
  std::string s;
  for (size_t i = 0; i < v.size(); ++i) {
    if (i) s += sep;
    s += v[i];
  }
  return s;
}

std::string quoted_list(std::vector<std::string> v, bool sort) {
  if (sort) std::sort(v.begin(), v.end());
  if (v.empty()) return "none";
  for (auto& s : v) s = "'" + s + "'";
  return join(v);
}

std::string child(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}
std::string child(const std::string& path, size_t i) { return child(path, std::to_string(i)); }

// Known aliases first, then the smallest edit distance, then a prefix.
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

bool valid_name(const std::string& s) {
  if (s.empty()) return false;
  for (char ch : s)
    if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '-' || ch == '.'))
      return false;
  return true;
}

}  // namespace fdem::case_detail
