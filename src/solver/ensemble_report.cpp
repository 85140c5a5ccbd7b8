// The report of an ensemble (ensemble.hpp): DIR/ensemble.csv, one row per realisation (its status,
// seeds, drawn values, results and timings), and DIR/ensemble.json, the statistics of every result
// over the realisations that are done and the mean cumulative fragment mass distribution with its
// band. Both are made from the realisation folders alone, in index order, so that the same
// realisations give the same bits whatever order they ran in; the timings stay out of the json.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "common/statistics.hpp"
#include "io/output.hpp"
#include "solver/ensemble.hpp"

namespace fdem {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using Values = std::vector<std::pair<std::string, double>>;

void add(Values& out, const json& j, const std::string& key, const std::string& name) {
  if (j.is_object() && j.contains(key) && j[key].is_number()) out.emplace_back(name, j[key].get<double>());
}

// Every number under `j` (objects only, arrays left out), by its key path.
void flatten(Values& out, const json& j, const std::string& prefix) {
  if (!j.is_object()) return;
  for (const auto& [k, v] : j.items()) {
    if (v.is_number()) out.emplace_back(prefix + k, v.get<double>());
    if (v.is_object()) flatten(out, v, prefix + k + ".");
  }
}

json stats_json(const std::vector<double>& x) {
  const stats::Summary s = stats::summarise(x);
  return {{"n", s.n}, {"mean", s.mean}, {"sd", s.sd}, {"se", s.se},
          {"ci95", {s.ci_low, s.ci_high}}, {"min", s.min}, {"max", s.max}};
}

// One realisation as read back: its record and, when done, its summary.
struct Row {
  long index = 0;
  std::string status;  // done, failed, error, "" (not run yet or not finished)
  Values inputs, results, timings;
  std::vector<std::pair<std::string, std::uint64_t>> seeds;
  std::vector<double> cumulative;
};

Row read_row(const std::string& dir, long i) {
  Row r;
  r.index = i;
  const json rec = read_json_file(realisation_folder(dir, i) + "/realisation.json");
  if (!rec.is_object()) return r;
  r.status = rec.value("status", "");
  const json seeds = rec.value("seeds", json::object()), values = rec.value("values", json::object());
  for (const auto& [k, v] : seeds.items()) r.seeds.emplace_back(k, v.get<std::uint64_t>());
  for (const auto& [k, v] : values.items()) r.inputs.emplace_back(k, v.get<double>());
  if (r.status != "done") return r;
  const json s = read_json_file(realisation_folder(dir, i) + "/summary.json");
  r.results = ensemble_results(s);
  r.timings = ensemble_timings(s);
  if (s.contains("fragments") && s["fragments"].is_object() && s["fragments"].contains("cumulative_mass"))
    r.cumulative = s["fragments"]["cumulative_mass"]["mass_fraction"].get<std::vector<double>>();
  return r;
}

// The column names of one kind over all rows, in the order of first appearance.
std::vector<std::string> columns(const std::vector<Row>& rows, Values Row::*member) {
  std::vector<std::string> out;
  for (const Row& r : rows)
    for (const auto& [k, v] : r.*member)
      if (std::find(out.begin(), out.end(), k) == out.end()) out.push_back(k);
  return out;
}

std::map<std::string, double> as_map(const Values& v) { return {v.begin(), v.end()}; }

void write_csv(const std::string& dir, const std::vector<Row>& rows, const std::vector<std::string>& sources) {
  const auto in = columns(rows, &Row::inputs), res = columns(rows, &Row::results), tim = columns(rows, &Row::timings);
  std::string text = "realisation,status";
  for (const auto& s : sources) text += ",seed_" + s;
  for (const auto* cols : {&in, &res, &tim})
    for (const auto& k : *cols) text += "," + k;
  text += "\n";
  for (const Row& r : rows) {
    text += std::to_string(r.index) + "," + (r.status.empty() ? "pending" : r.status);
    const std::map<std::string, std::uint64_t> seeds(r.seeds.begin(), r.seeds.end());
    for (const auto& s : sources) text += "," + (seeds.count(s) ? std::to_string(seeds.at(s)) : "");
    const std::pair<const std::vector<std::string>*, Values Row::*> parts[] = {
        {&in, &Row::inputs}, {&res, &Row::results}, {&tim, &Row::timings}};
    for (const auto& [cols, member] : parts) {
      const auto m = as_map(r.*member);
      for (const auto& k : *cols) text += "," + (m.count(k) ? exact_number(m.at(k)) : "");
    }
    text += "\n";
  }
  write_file_atomic(dir + "/ensemble.csv", text);
}

// Statistics of every column of `member` over the rows that have it.
json column_stats(const std::vector<Row>& rows, Values Row::*member) {
  json out = json::object();
  for (const auto& k : columns(rows, member)) {
    std::vector<double> x;
    for (const Row& r : rows) {
      const auto m = as_map(r.*member);
      if (m.count(k)) x.push_back(m.at(k));
    }
    out[k] = stats_json(x);
  }
  return out;
}

// The mean cumulative mass distribution (fragments.cumulative_mass of each summary) with its 95 %
// interval, its minimum and maximum at each point of the grid.
json distribution_stats(const std::vector<Row>& rows) {
  std::vector<const std::vector<double>*> curves;
  for (const Row& r : rows)
    if (!r.cumulative.empty()) curves.push_back(&r.cumulative);
  if (curves.empty()) return nullptr;
  json grid = json::array(), mean = json::array(), lo = json::array(), hi = json::array(),
       mn = json::array(), mx = json::array();
  for (size_t k = 0; k < curves[0]->size(); ++k) {
    std::vector<double> x;
    for (const auto* c : curves) x.push_back((*c)[k]);
    const stats::Summary s = stats::summarise(x);
    grid.push_back(std::pow(10.0, -0.25 * static_cast<double>(k)));
    mean.push_back(s.mean);
    lo.push_back(s.ci_low);
    hi.push_back(s.ci_high);
    mn.push_back(s.min);
    mx.push_back(s.max);
  }
  return {{"fragment_fraction_at_least", grid}, {"realisations", curves.size()}, {"mean_mass_fraction", mean},
          {"ci95_low", lo}, {"ci95_high", hi}, {"min", mn}, {"max", mx}};
}

}  // namespace

std::string realisation_folder(const std::string& dir, long i) {
  char b[32];
  std::snprintf(b, sizeof b, "/r%04ld", i);
  return dir + b;
}

json read_json_file(const std::string& path) {
  std::ifstream f(path);
  if (!f) return nullptr;
  std::stringstream s;
  s << f.rdbuf();
  try {
    return json::parse(s.str());
  } catch (const json::exception&) {
    return nullptr;
  }
}

std::string exact_number(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

std::vector<std::pair<std::string, double>> ensemble_results(const json& s) {
  Values out;
  if (!s.is_object()) return out;
  for (const char* k : {"steps", "end_time_s", "interfaces_damaged", "interfaces_failed"}) add(out, s, k, k);
  if (s.contains("time_step")) add(out, s["time_step"], "dt_s", "time_step.dt_s");
  if (s.contains("counts"))
    for (const char* k : {"elements", "nodes", "interfaces"}) add(out, s["counts"], k, std::string("counts.") + k);
  if (s.contains("energy"))
    for (const auto& [k, v] : s["energy"].items())
      if (v.is_number() && k != "warning_threshold") out.emplace_back("energy." + k, v.get<double>());
  if (s.contains("fragments") && s["fragments"].is_object()) {
    const json& f = s["fragments"];
    for (const char* k : {"count", "largest_fraction", "single_element_fragments"})
      add(out, f, k, std::string("fragments.") + k);
    if (f.contains("largest_fractions") && f["largest_fractions"].size() >= 1)
      out.emplace_back("fragments.second_largest_fraction",
                       f["largest_fractions"].size() >= 2 ? f["largest_fractions"][1].get<double>() : 0.0);
    if (f.contains("distribution")) {  // fragments of at least 1 % of the mass: the bins 1e-1 and 1e-2
      const json& d = f["distribution"];
      double n = 0;
      for (size_t b = 0; b < d["bin_lower_edge"].size(); ++b)
        if (d["bin_lower_edge"][b] == "1e-1" || d["bin_lower_edge"][b] == "1e-2") n += d["count"][b].get<double>();
      out.emplace_back("fragments.count_at_least_1pct", n);
    }
    if (f.contains("per_body")) flatten(out, f["per_body"], "fragments.per_body.");
  }
  if (s.contains("results")) flatten(out, s["results"], "results.");
  return out;
}

std::vector<std::pair<std::string, double>> ensemble_timings(const json& s) {
  Values out;
  if (!s.is_object()) return out;
  add(out, s, "wall_seconds", "wall_seconds");
  add(out, s, "loop_wall_seconds", "loop_wall_seconds");
  if (s.contains("setup")) add(out, s["setup"], "wall_seconds", "setup.wall_seconds");
  return out;
}

json write_ensemble_report(const std::string& dir, long n, const json& plan) {
  std::vector<Row> rows;
  for (long i = 0; i < n; ++i) rows.push_back(read_row(dir, i));
  const std::vector<std::string> sources = plan.value("vary", std::vector<std::string>{});
  write_csv(dir, rows, sources);
  std::vector<Row> done;
  json failed = json::array(), pending = json::array();
  for (const Row& r : rows) {
    if (r.status == "done") done.push_back(r);
    else if (r.status == "failed") failed.push_back(r.index);
    else pending.push_back(r.index);
  }
  json report = {{"case_file", plan.value("case_file", "")},
                 {"vary", plan["vary"]},
                 {"seed", plan["seed"]},
                 {"realisations", n},
                 {"done", done.size()},
                 {"failed", failed.size()},
                 {"failed_realisations", failed},
                 {"pending_realisations", pending},
                 {"confidence", "ci95: mean -/+ t(0.975, n - 1) sd / sqrt(n) (Student's t)"},
                 {"inputs", column_stats(done, &Row::inputs)},
                 {"results", column_stats(done, &Row::results)},
                 {"fragment_mass_distribution", distribution_stats(done)}};
  write_file_atomic(dir + "/ensemble.json", report.dump(2) + "\n");
  return report;
}

}  // namespace fdem
