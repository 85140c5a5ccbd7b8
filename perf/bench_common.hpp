#pragma once
// Helpers shared by the benchmarks (perf/bench_*.cpp): option lists, the machine and date for the
// JSON records, and the timing loop (every function in turn, `reps` rounds, median, min, max).
#include <Kokkos_Core.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "kernels/fdem_kokkos.hpp"

namespace fdem_bench {

using Clock = std::chrono::steady_clock;
using nlohmann::json;

// Comma-separated numbers ("1e4,1e5").
inline std::vector<double> parse_list(const std::string& s) {
  std::vector<double> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ','))
    if (!item.empty()) out.push_back(std::stod(item));
  return out;
}

// The command line as one string (for the JSON records).
inline std::string command_line(int argc, char** argv) {
  std::string out;
  for (int i = 0; i < argc; ++i) out += (i ? " " : "") + std::string(argv[i]);
  return out;
}

// Walks the arguments argv[1..]: `while (args.next())` visits each (`arg()`); `value()` takes the
// one after it, or calls `missing` (which does not return) with "missing value after ARG".
class Args {
 public:
  Args(int argc, char** argv, std::function<void(const std::string&)> missing)
      : argc_(argc), argv_(argv), missing_(std::move(missing)) {}
  bool next() {
    if (++i_ >= argc_) return false;
    arg_ = argv_[i_];
    return true;
  }
  const std::string& arg() const { return arg_; }
  std::string value() {
    if (i_ + 1 >= argc_) missing_("missing value after " + arg_);
    return argv_[++i_];
  }

 private:
  int argc_, i_ = 0;
  char** argv_;
  std::function<void(const std::string&)> missing_;
  std::string arg_;
};

// ---------------------------------------------------------------------------------------------
// machine

inline std::string cpu_model() {
  std::ifstream f("/proc/cpuinfo");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("model name", 0) == 0) {
      const auto p = line.find(':');
      return p == std::string::npos ? line : line.substr(p + 2);
    }
  return "unknown";
}

inline std::string env(const char* name) {
  const char* v = std::getenv(name);
  return v ? v : "";
}

inline std::string utc_now() {
  const std::time_t t = std::time(nullptr);
  char buf[64];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}

inline double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// The fields every benchmark's JSON record starts with: its name, command line, date, machine (the
// CPU model; a benchmark may add to it), backend and threads.
inline json record_header(const std::string& name, const std::string& command) {
  json doc;
  doc["benchmark"] = name;
  doc["command"] = command;
  doc["date_utc"] = utc_now();
  doc["machine"] = {{"cpu_model", cpu_model()}};
  doc["backend"] = fdem::ExecSpace::name();
  doc["threads"] = fdem::ExecSpace().concurrency();
  return doc;
}

// Writes `doc` to `file` (nothing when `file` is empty).
inline void write_json(const std::string& file, const json& doc) {
  if (file.empty()) return;
  std::ofstream f(file);
  f << doc.dump(1) << "\n";
}

// ---------------------------------------------------------------------------------------------
// timing: every function in turn, `reps` rounds, each call repeated to last `min_time`

struct Stat {
  double median = 0, min = 0, max = 0;  // ns per call
  long calls = 0;                       // per round
};

// after[k] (optional, not timed) runs after each batch of calls of fns[k]; before[k] before it.
inline std::vector<Stat> measure(const std::vector<std::function<void()>>& fns, int reps, double min_time,
                                 const std::vector<std::function<void()>>& after = {},
                                 const std::vector<std::function<void()>>& before = {}) {
  const size_t n = fns.size();
  auto post = [&](size_t k) {
    if (k < after.size() && after[k]) after[k]();
  };
  auto pre = [&](size_t k) {
    if (k < before.size() && before[k]) before[k]();
  };
  std::vector<long> calls(n, 1);
  for (size_t k = 0; k < n; ++k) {  // warm-up and calibration
    pre(k);
    fns[k]();
    Kokkos::fence();
    const auto t0 = Clock::now();
    fns[k]();
    Kokkos::fence();
    const double t = std::chrono::duration<double>(Clock::now() - t0).count();
    post(k);
    const long want = static_cast<long>(std::ceil(min_time / std::max(t, 1e-9)));
    calls[k] = std::max<long>(1, std::min<long>(1000000, want));
  }
  std::vector<std::vector<double>> samples(n);
  for (int r = 0; r < reps; ++r)
    for (size_t k = 0; k < n; ++k) {
      pre(k);
      Kokkos::fence();
      const auto t0 = Clock::now();
      for (long c = 0; c < calls[k]; ++c) fns[k]();
      Kokkos::fence();
      samples[k].push_back(std::chrono::duration<double, std::nano>(Clock::now() - t0).count() / calls[k]);
      post(k);
    }
  std::vector<Stat> out(n);
  for (size_t k = 0; k < n; ++k) {
    auto s = samples[k];
    std::sort(s.begin(), s.end());
    const size_t m = s.size();
    out[k].median = m % 2 ? s[m / 2] : 0.5 * (s[m / 2 - 1] + s[m / 2]);
    out[k].min = s.front();
    out[k].max = s.back();
    out[k].calls = calls[k];
  }
  return out;
}

inline json stat_json(const Stat& s) {
  return {{"ns_median", s.median}, {"ns_min", s.min}, {"ns_max", s.max}, {"calls_per_round", s.calls}};
}

}  // namespace fdem_bench
