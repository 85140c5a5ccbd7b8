// Seeds and minerals of the grain generators (src/mesh/grains_internal.hpp).
#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>
#include <utility>

#include "common/error.hpp"
#include "mesh/grains_internal.hpp"
#include "mesh/mesh_internal.hpp"

namespace fdem::grain_detail {

using mesh_detail::fmt;

namespace {

// "give a grain_size <relation> D m (<what>)": the grain size D that puts `grains` grains in a
// specimen of this area (2D) or volume (3D), from the measure alone (a bound scaled from the given
// grain size came out as 0 m when that one was huge); a measure that is zero or not finite has no
// such size, and the text says so.
std::string grain_size_for(int dim, double measure, double grains, const std::string& relation,
                           const std::string& what) {
  const double pi = 3.14159265358979323846;
  const double unit = dim == 2 ? 0.25 * pi : pi / 6;  // a grain's measure over d^dim
  const double d = std::pow(measure / (grains * unit), dim == 2 ? 0.5 : 1.0 / 3.0);
  if (d > 0 && std::isfinite(d)) return "give a grain_size " + relation + " " + fmt(d) + " m (" + what + ")";
  const std::string m = dim == 2 ? "area " + fmt(measure) + " m^2" : "volume " + fmt(measure) + " m^3";
  return "no grain_size gives " + what + ": the specimen's " + m +
         " is beyond double precision; give a specimen of ordinary size";
}

// A mineral that got no grain: its fraction is under about one grain of the specimen's, and the
// other minerals took its share. An error, not a warning: the specimen would lack a phase the case
// asks for (and the mineral's regions entry would name a region the mesh does not have).
[[noreturn]] void no_grain_of(const std::pair<std::string, double>& mineral, std::size_t grains,
                              double measure, int dim, const std::string& who) {
  const std::string& name = mineral.first;
  // grains for about one of this mineral (twice as many where it missed out with more)
  const double f = mineral.second, need = std::max(std::ceil(1 / f), 2.0 * static_cast<double>(grains));
  const std::string fix = need <= 20000
                              ? grain_size_for(dim, measure, need, "below",
                                               "about " + fmt(need) + " grains, enough for '" + name +
                                                   "'; element_size at most half of it") +
                                    ", or remove"
                              : "no grain_size gives it one within the limit of 20000 grains: remove";
  throw InputError(who + ": mesh.minerals." + name + ": no grain is '" + name + "': its fraction " + fmt(f) +
                   " of the " + std::to_string(grains) + " grains is " +
                   fmt(f * static_cast<double>(grains)) + " grain, which the other minerals took; " + fix +
                   " '" + name + "' from mesh.minerals (and from regions)");
}

}  // namespace

std::vector<std::array<double, 3>> draw_seeds(
    int dim, const double lo[3], const double hi[3], double measure, double d, std::uint64_t seed,
    const std::string& who, const std::function<bool(const std::array<double, 3>&)>& inside) {
  if (!(measure > 0) || !std::isfinite(measure))
    throw InputError(who + ": the specimen's " + (dim == 2 ? "area is " : "volume is ") + fmt(measure) +
                     (dim == 2 ? " m^2" : " m^3") + ", beyond double precision: give it an ordinary size");
  const double pi = 3.14159265358979323846;
  const double one = dim == 2 ? 0.25 * pi * d * d : pi * d * d * d / 6;  // a circle's area, a sphere's volume
  const double n_target = measure / one;
  if (!(n_target >= 1.5))  // also a grain_size so large that `one` overflows: n_target 0
    throw InputError(who + ": the specimen holds " + fmt(n_target) + " grains of grain_size " + fmt(d) +
                     " m; " + grain_size_for(dim, measure, 2, "below", "at least 2 grains"));
  if (n_target > 20000)
    throw InputError(who + ": the specimen would hold " + fmt(n_target) + " grains (limit 20000); " +
                     grain_size_for(dim, measure, 20000, "of at least", "at most 20000 grains"));
  const int n = static_cast<int>(std::lround(n_target));
  const double rmin2 = 0.25 * d * d;  // seeds at least half a grain size apart
  Stream rng(seed);
  std::vector<std::array<double, 3>> s;
  long tries = 0;
  const long max_tries = 2000L * n;
  while (static_cast<int>(s.size()) < n) {
    if (++tries > max_tries)
      throw InputError(who + ": could place only " + std::to_string(s.size()) + " of " + std::to_string(n) +
                       " grain seeds half a grain size apart; give another seed");
    std::array<double, 3> p{0, 0, 0};
    for (int k = 0; k < dim; ++k) p[k] = lo[k] + rng.uniform() * (hi[k] - lo[k]);
    if (!inside(p)) continue;
    bool ok = true;
    for (const auto& q : s) {
      double r2 = 0;
      for (int k = 0; k < dim; ++k) r2 += (p[k] - q[k]) * (p[k] - q[k]);
      if (r2 < rmin2) {
        ok = false;
        break;
      }
    }
    if (ok) s.push_back(p);
  }
  return s;
}

void assign_minerals(const std::vector<double>& measure, const MeshSpec& spec, const std::string& who,
                     std::vector<int>& mineral, std::vector<std::string>& names,
                     std::vector<double>& mineral_measure) {
  std::vector<std::pair<std::string, double>> mins = spec.minerals;
  if (mins.empty()) mins.push_back({spec.region.empty() ? std::string("body") : spec.region, 1.0});
  const size_t ng = measure.size();
  double total = 0;
  for (double a : measure) total += a;
  names.clear();
  for (const auto& m : mins) names.push_back(m.first);
  mineral_measure.assign(mins.size(), 0.0);
  mineral.assign(ng, 0);
  std::vector<int> order(ng);
  std::iota(order.begin(), order.end(), 0);
  Stream rng(spec.seed ^ 0x5bd1e995ULL);
  for (size_t i = ng; i > 1; --i)
    std::swap(order[i - 1], order[static_cast<size_t>(rng.uniform() * static_cast<double>(i))]);
  for (int c : order) {
    size_t best = 0;
    double deficit = -1e300;
    for (size_t m = 0; m < mins.size(); ++m) {
      const double df = mins[m].second * total - mineral_measure[m];
      if (df > deficit + 1e-15 * total) {
        deficit = df;
        best = m;
      }
    }
    mineral[c] = static_cast<int>(best);
    mineral_measure[best] += measure[c];
  }
  for (size_t m = 0; m < mins.size(); ++m)
    if (!(mineral_measure[m] > 0)) no_grain_of(mins[m], ng, total, spec.shape == "box" ? 3 : 2, who);
}

}  // namespace fdem::grain_detail
