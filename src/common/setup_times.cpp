#include "common/setup_times.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <vector>

namespace fdem::setup_times {

namespace {

using Clock = std::chrono::steady_clock;

struct Entry {
  std::string name;
  double wall = 0, cpu = 0;
  double rss = -1;  // resident memory at the phase's last end
};

struct State {
  std::vector<Entry> phases;
  double recorded_wall = 0, recorded_cpu = 0;  // sums over the phases
  Clock::time_point wall0 = Clock::now();
  double cpu0 = 0;
  double total_wall = -1, total_cpu = -1;  // at finish()
  double peak_at_finish = -1;
  double gmsh_peak = 0;
  int folded = 0;  // Folded scopes alive
};

State& state() {
  static State s;
  return s;
}

double status_kb(const std::string& key) {
  std::ifstream f("/proc/self/status");
  std::string l;
  while (std::getline(f, l))
    if (l.rfind(key + ":", 0) == 0) {
      std::istringstream s(l.substr(key.size() + 1));
      double kb = -1;
      if (s >> kb) return kb * 1024.0;
    }
  return -1;
}

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

}  // namespace

void reset() {
  state() = State{};
  state().cpu0 = process_cpu_seconds();
}

void finish() {
  State& s = state();
  if (s.total_wall >= 0) return;
  s.total_wall = seconds_since(s.wall0);
  s.total_cpu = process_cpu_seconds() - s.cpu0;
  const double other_wall = s.total_wall - s.recorded_wall, other_cpu = s.total_cpu - s.recorded_cpu;
  if (other_wall > 0) add("other", other_wall, std::max(0.0, other_cpu));
  s.peak_at_finish = peak_rss_bytes();
}

void add(const std::string& name, double wall, double cpu) {
  State& s = state();
  auto it = std::find_if(s.phases.begin(), s.phases.end(), [&](const Entry& e) { return e.name == name; });
  if (it == s.phases.end()) it = s.phases.insert(s.phases.end(), Entry{name, 0, 0});
  it->wall += wall;
  it->cpu += cpu;
  it->rss = rss_bytes();
  s.recorded_wall += wall;
  s.recorded_cpu += cpu;
}

double process_cpu_seconds() {
  double sum = 0;
  for (int who : {RUSAGE_SELF, RUSAGE_CHILDREN}) {
    rusage ru{};
    if (getrusage(who, &ru) != 0) continue;
    sum += static_cast<double>(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
           1e-6 * static_cast<double>(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
  }
  return sum;
}

double peak_rss_bytes() { return status_kb("VmHWM"); }
double rss_bytes() { return status_kb("VmRSS"); }

void note_gmsh_peak(double bytes) { state().gmsh_peak = std::max(state().gmsh_peak, bytes); }
double gmsh_peak_bytes() { return state().gmsh_peak; }

nlohmann::json report() {
  const State& s = state();
  nlohmann::json phases = nlohmann::json::array();
  for (const auto& e : s.phases)
    phases.push_back(
        {{"name", e.name}, {"wall_seconds", e.wall}, {"cpu_seconds", e.cpu}, {"rss_bytes", e.rss}});
  return {{"phases", phases},
          {"wall_seconds", s.total_wall >= 0 ? s.total_wall : s.recorded_wall},
          {"cpu_seconds", s.total_cpu >= 0 ? s.total_cpu : s.recorded_cpu},
          {"peak_rss_bytes", s.peak_at_finish},
          {"gmsh_peak_rss_bytes", s.gmsh_peak}};
}

std::string line() {
  const State& s = state();
  const double wall = s.total_wall >= 0 ? s.total_wall : s.recorded_wall;
  char buf[128];
  std::snprintf(buf, sizeof buf, "set-up %.2f s:", wall);
  std::string out = buf;
  bool first = true;
  for (const auto& e : s.phases) {
    if (e.wall < 0.02 * wall) continue;
    std::snprintf(buf, sizeof buf, "%s %s %.2f", first ? "" : ",", e.name.c_str(), e.wall);
    out += buf;
    first = false;
  }
  std::snprintf(buf, sizeof buf, " s; peak memory %.0f MB (Gmsh %.0f MB)", s.peak_at_finish / 1e6,
                s.gmsh_peak / 1e6);
  return out + buf;
}

Folded::Folded() { ++state().folded; }
Folded::~Folded() { --state().folded; }

Phase::Phase(std::string name)
    : name_(std::move(name)),
      outer_(state().folded == 0),
      wall0_(Clock::now()),
      cpu0_(process_cpu_seconds()),
      inner_wall0_(state().recorded_wall),
      inner_cpu0_(state().recorded_cpu) {}

void Phase::stop() {
  if (!open_) return;
  open_ = false;
  const State& s = state();
  if (s.folded > 0 && !outer_) return;  // (counted by the phase that holds the Folded scope)
  const double inner_wall = s.recorded_wall - inner_wall0_, inner_cpu = s.recorded_cpu - inner_cpu0_;
  add(name_, std::max(0.0, seconds_since(wall0_) - inner_wall),
      std::max(0.0, process_cpu_seconds() - cpu0_ - inner_cpu));
}

}  // namespace fdem::setup_times
