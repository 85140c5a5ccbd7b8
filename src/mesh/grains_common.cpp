// Seeds and minerals of the grain generators (src/mesh/grains_internal.hpp).
#include <cmath>
#include <numeric>

#include "common/error.hpp"
#include "mesh/grains_internal.hpp"
#include "mesh/mesh_internal.hpp"

namespace fdem::grain_detail {

using mesh_detail::fmt;

std::vector<std::array<double, 3>> draw_seeds(
    int dim, const double lo[3], const double hi[3], double measure, double d, std::uint64_t seed,
    const std::string& who, const std::function<bool(const std::array<double, 3>&)>& inside) {
  const double pi = 3.14159265358979323846;
  const double one = dim == 2 ? 0.25 * pi * d * d : pi * d * d * d / 6;  // a circle's area, a sphere's volume
  const double n_target = measure / one;
  const double root = dim == 2 ? 0.5 : 1.0 / 3.0;
  if (n_target < 1.5)
    throw InputError(who + ": the specimen holds " + fmt(n_target) + " grains of grain_size " + fmt(d) +
                     " m; give a grain_size below " + fmt(d * std::pow(n_target / 2, root)) +
                     " m (at least 2 grains)");
  if (n_target > 20000)
    throw InputError(who + ": the specimen would hold " + fmt(n_target) + " grains (limit 20000); give a " +
                     "grain_size of at least " + fmt(d * std::pow(n_target / 20000, root)) + " m");
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

void assign_minerals(const std::vector<double>& measure, const MeshSpec& spec, std::vector<int>& mineral,
                     std::vector<std::string>& names, std::vector<double>& mineral_measure) {
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
}

}  // namespace fdem::grain_detail
