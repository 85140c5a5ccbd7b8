#include "solver/interface_materials.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <utility>

#include "common/error.hpp"
#include "common/random.hpp"  // splitmix64: a factor depends on (seed, q, draw) only
#include "kernels/host_loops.hpp"

namespace fdem {

namespace {

// Uniform in (0, 1) from (seed, q, draw).
double uniform(std::uint64_t seed, long q, int draw) {
  const std::uint64_t h =
      splitmix64(splitmix64(seed * 0x2545f4914f6cdd1dULL + static_cast<std::uint64_t>(q)) +
                 static_cast<std::uint64_t>(draw));
  return (static_cast<double>(h >> 11) + 0.5) * 0x1.0p-53;
}

double normal_pdf(double x) { return std::exp(-0.5 * x * x) / std::sqrt(2 * M_PI); }
double normal_cdf(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }

// Standard normal from (seed, q, draw, draw + 1) (Box-Muller).
double gauss(std::uint64_t seed, long q, int draw) {
  return std::sqrt(-2 * std::log(uniform(seed, q, draw))) * std::cos(2 * M_PI * uniform(seed, q, draw + 1));
}

// Weibull scale for mean 1: lambda = 1 / Gamma(1 + 1/m).
double weibull_lambda(const StrengthScatter& s) { return 1.0 / std::tgamma(1.0 + 1.0 / s.modulus); }

// Mean of 1 + cov z with z standard normal truncated to [a, b] (the bounds lower, upper of w).
double truncated_mean(const StrengthScatter& s, double a, double b) {
  return 1.0 + s.cov * (normal_pdf(a) - normal_pdf(b)) / (normal_cdf(b) - normal_cdf(a));
}

// The standard normal quantile: bisection on normal_cdf (host, set-up only).
double normal_quantile(double u) {
  double lo = -40, hi = 40;
  for (int i = 0; i < 200 && hi - lo > 1e-13; ++i) {
    const double mid = 0.5 * (lo + hi);
    (normal_cdf(mid) < u ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace

CorrelatedField::CorrelatedField(const StrengthScatter& s, int dim) : dim_(dim) {
  k_.resize(static_cast<std::size_t>(kModes) * dim);
  phase_.resize(kModes);
  // the modes draw from interface indices -1, -2, ... (the independent factors use q >= 0)
  for (int i = 0; i < kModes; ++i) {
    for (int d = 0; d < dim; ++d)
      k_[static_cast<std::size_t>(i) * dim + d] =
          std::sqrt(2.0) / s.correlation_length * gauss(s.seed, -1 - i, 2 * d);
    phase_[i] = 2 * M_PI * uniform(s.seed, -1 - i, 2 * dim);
  }
}

double CorrelatedField::gaussian(const double* x) const {
  double g = 0;
  for (int i = 0; i < kModes; ++i) {
    double a = phase_[i];
    for (int d = 0; d < dim_; ++d) a += k_[static_cast<std::size_t>(i) * dim_ + d] * x[d];
    g += std::cos(a);
  }
  return g * std::sqrt(2.0 / kModes);
}

double factor_from_gaussian(const StrengthScatter& s, double g) {
  if (s.distribution == "weibull") {
    const double lambda = weibull_lambda(s);
    const double tail = normal_cdf(-g);  // 1 - Phi(g), accurate far out in the upper tail
    return lambda * std::pow(-std::log(tail), 1.0 / s.modulus);
  }
  if (s.distribution == "normal") {
    const double a = (s.lower - 1.0) / s.cov, b = (s.upper - 1.0) / s.cov;
    const double Pa = normal_cdf(a), Pb = normal_cdf(b);
    const double mean = truncated_mean(s, a, b);
    const double z = normal_quantile(Pa + normal_cdf(g) * (Pb - Pa));  // truncated normal at Phi(g)
    return (1.0 + s.cov * z) / mean;
  }
  return 1.0;
}

double strength_factor(const StrengthScatter& s, long q) {
  if (s.distribution == "weibull") {
    // w = lambda (-ln U)^(1/m) with lambda = 1 / Gamma(1 + 1/m): mean 1.
    const double lambda = weibull_lambda(s);
    return lambda * std::pow(-std::log(uniform(s.seed, q, 0)), 1.0 / s.modulus);
  }
  if (s.distribution == "normal") {
    // 1 + cov N(0,1) truncated to [lower, upper] (rejection, Box-Muller), divided by the mean of
    // the truncated distribution so that the mean stays 1.
    const double a = (s.lower - 1.0) / s.cov, b = (s.upper - 1.0) / s.cov;
    const double mean = truncated_mean(s, a, b);
    for (int draw = 0; draw < 2000; draw += 2) {
      const double w = 1.0 + s.cov * gauss(s.seed, q, draw);
      if (w >= s.lower && w <= s.upper) return w / mean;
    }
    return 1.0 / mean;  // not reached for any allowed bounds (probability below 1e-300)
  }
  return 1.0;
}

bool interface_fields_wanted(const Case& c) {
  return !c.region_iface_material.empty() || !c.pair_iface_material.empty() || !c.surface_iface_material.empty() ||
         !c.scatter.distribution.empty();
}

InterfaceMaterialMap interface_material_map(const Case& c, const HostMesh& mesh) {
  InterfaceMaterialMap map;
  const long ni = mesh.num_ifaces();
  map.count.assign(c.interface_materials.size(), 0);
  if (ni == 0) return map;
  if (c.fracture_material < 0) throw InputError(c.file + ": fracture: no interface material");
  const bool by_place =
      !c.region_iface_material.empty() || !c.pair_iface_material.empty() || !c.surface_iface_material.empty();
  const bool scatter = !c.scatter.distribution.empty();
  if (!by_place) {
    map.count[c.fracture_material] = ni;
  } else {
    // Material of each (region A, region B) pair of region indices.
    const int nr = static_cast<int>(mesh.region_names.size());
    std::vector<int> of_pair(static_cast<size_t>(nr) * nr, c.fracture_material);
    for (int a = 0; a < nr; ++a)
      for (int b = 0; b < nr; ++b) {
        const std::string& ra = mesh.region_names[a];
        const std::string& rb = mesh.region_names[b];
        int& m = of_pair[static_cast<size_t>(a) * nr + b];
        if (a == b) {
          const auto it = c.region_iface_material.find(ra);
          if (it != c.region_iface_material.end()) m = it->second;
        } else {
          const auto it =
              c.pair_iface_material.find(ra < rb ? std::make_pair(ra, rb) : std::make_pair(rb, ra));
          if (it != c.pair_iface_material.end()) m = it->second;
        }
      }
    if (mesh.iface_elems.size() != 2 * static_cast<size_t>(ni))
      throw InputError(c.file + ": fracture: interface materials by region need the interfaces' elements");
    map.material.resize(ni);
    for (long q = 0; q < ni; ++q) {
      const int ra = mesh.elem_region[mesh.iface_elems[2 * q]],
                rb = mesh.elem_region[mesh.iface_elems[2 * q + 1]];
      map.material[q] = of_pair[static_cast<size_t>(ra) * nr + rb];
    }
    // named surfaces win (a surface's interfaces, listed by insert_interfaces)
    for (const auto& [name, m] : c.surface_iface_material) {
      const auto it = mesh.iface_sets.find(name);
      if (it == mesh.iface_sets.end())
        throw InputError(c.file + ": fracture.surfaces." + name +
                         ": the mesh's interfaces on it are not known");
      for (int q : it->second) map.material[q] = m;
    }
    for (long q = 0; q < ni; ++q) ++map.count[map.material[q]];
  }
  if (scatter) {
    if (map.material.empty()) map.material.assign(ni, c.fracture_material);
    map.scale.resize(ni);
    if (c.scatter.correlation_length > 0) {
      // the field at each interface's centre (its side-A nodes' mean, reference positions)
      const CorrelatedField field(c.scatter, mesh.dim);
      const int D = mesh.dim;
      host_for("fdem::correlated_strength", static_cast<int>(ni), [&](int q) {
        double x[3] = {0, 0, 0};
        for (int k = 0; k < D; ++k)
          for (int i = 0; i < D; ++i)
            x[i] += mesh.X[static_cast<std::size_t>(mesh.ifaces[2 * D * q + k]) * D + i] / D;
        map.scale[q] = static_cast<float>(factor_from_gaussian(c.scatter, field.gaussian(x)));
      });
    } else {
      // drawn from the whole mesh's index of the interface (a part's: mesh.iface_ids)
      const bool part = !mesh.iface_ids.empty();
      for (long q = 0; q < ni; ++q)
        map.scale[q] = static_cast<float>(strength_factor(c.scatter, part ? mesh.iface_ids[q] : q));
    }
  }
  return map;
}

std::vector<long> region_pair_counts(const HostMesh& mesh, long ifaces) {
  const size_t nr = mesh.region_names.size();
  std::vector<long> between(nr * nr, 0);
  const size_t ni = static_cast<size_t>(std::min<long>(ifaces, mesh.num_ifaces()));
  if (mesh.iface_elems.size() >= 2 * ni)
    for (size_t q = 0; q < ni; ++q)
      ++between[static_cast<size_t>(mesh.elem_region[mesh.iface_elems[2 * q]]) * nr +
                static_cast<size_t>(mesh.elem_region[mesh.iface_elems[2 * q + 1]])];
  return between;
}

std::vector<std::string> unused_material_rules(const Case& c, const HostMesh& mesh) {
  return unused_material_rules(c, mesh.region_names, region_pair_counts(mesh, mesh.num_ifaces()));
}

std::vector<std::string> unused_material_rules(const Case& c, const std::vector<std::string>& region_names,
                                               const std::vector<long>& between) {
  const size_t nr = region_names.size(), absent = ~size_t{0};
  auto index = [&](const std::string& r) {
    const auto it = std::find(region_names.begin(), region_names.end(), r);
    return it == region_names.end() ? absent : static_cast<size_t>(it - region_names.begin());
  };
  auto count = [&](const std::string& ra, const std::string& rb) {
    const size_t a = index(ra), b = index(rb);
    if (a == absent || b == absent) return 0L;
    return between[a * nr + b] + (a == b ? 0 : between[b * nr + a]);
  };
  const std::string kept = " (the rule applies to none; a warning: the run goes on without it)";
  std::vector<std::string> out;
  for (const auto& rule : c.region_iface_material)
    if (count(rule.first, rule.first) == 0)
      out.push_back(c.file + ": fracture.region_materials." + rule.first + ": no interface has both sides in region '" +
                    rule.first + "'" + kept);
  for (const auto& rule : c.pair_iface_material)
    if (count(rule.first.first, rule.first.second) == 0)
      out.push_back(c.file + ": fracture.pair_materials [" + rule.first.first + ", " + rule.first.second +
                    "]: no interface lies between regions '" + rule.first.first + "' and '" + rule.first.second +
                    "'" + kept);
  return out;
}

nlohmann::json interface_material_report(const Case& c, const InterfaceMaterialMap& map) {
  nlohmann::json j = nlohmann::json::object();
  nlohmann::json counts = nlohmann::json::object();
  for (size_t m = 0; m < map.count.size(); ++m)
    if (map.count[m] > 0) counts[c.interface_materials[m].name] = map.count[m];
  j["interfaces_per_material"] = counts;
  if (!map.scale.empty()) {
    double lo = map.scale[0], hi = map.scale[0], sum = 0;
    for (float w : map.scale) {
      lo = std::min(lo, static_cast<double>(w));
      hi = std::max(hi, static_cast<double>(w));
      sum += w;
    }
    j["strength_scatter"] = {{"distribution", c.scatter.distribution},
                             {"seed", c.scatter.seed},
                             {"factor_mean", sum / map.scale.size()},
                             {"factor_min", lo},
                             {"factor_max", hi},
                             {"energy_scaled", c.scatter.energy},
                             {"correlation_length_m", c.scatter.correlation_length}};
  }
  return j;
}

}  // namespace fdem
