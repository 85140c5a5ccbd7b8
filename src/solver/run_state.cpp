#include "solver/run_state.hpp"

#include "solver/simulation.hpp"

namespace fdem {

template <class Self, class F>
void RunState::fields(Self& s, F&& f, long long platens) {
  f("run/history_columns", s.history_columns, -1);
  f("run/next_history", s.next_history, 1);
  f("run/next_snapshot", s.next_snapshot, 1);
  f("run/next_checkpoint", s.next_checkpoint, 1);
  f("run/checkpoint_every", s.checkpoint_every, 1);
  f("run/peak_load", s.peak_load, platens);
  f("run/peak_displacement", s.peak_displacement, platens);
  f("run/max_relative_balance_error", s.max_relative_balance_error, 1);
  f("run/last_row_energies", s.last_row_energies, -1);  // (the ledger's layout: solver/ledger.hpp)
  f("run/last_was_row", s.last_was_row, 1);
  f("run/last_snapshot_step", s.last_snapshot_step, 1);
  f("run/history_rows", s.history_rows, -1);
  f("run/fragment_rows", s.fragment_rows, -1);
  f("run/wall_seconds", s.wall_seconds, 1);
  f("run/loop_wall_seconds", s.loop_wall_seconds, 1);
  f("run/checkpoint_seconds", s.checkpoint_seconds, 1);
  f("run/checkpoints_written", s.checkpoints_written, 1);
  f("run/snapshot_steps", s.snapshot_steps, -1);
  // (its size is that of snapshot_steps, read just before)
  f("run/snapshot_times", s.snapshot_times, static_cast<long long>(s.snapshot_steps.size()));
}

namespace {

struct Writer {
  StateArrays& s;
  void operator()(const char* n, const std::string& v, long long) const { s.str[n] = v; }
  void operator()(const char* n, double v, long long) const { s.put(n, v); }
  void operator()(const char* n, long long v, long long) const { s.put_int(n, v); }
  void operator()(const char* n, const std::vector<double>& v, long long) const { s.f64[n] = v; }
  void operator()(const char* n, const std::vector<long long>& v, long long) const { s.i64[n] = v; }
};

struct Reader {
  const StateArrays& s;
  void operator()(const char* n, std::string& v, long long) const { v = s.string(n); }
  void operator()(const char* n, double& v, long long) const { v = s.get(n); }
  void operator()(const char* n, long long& v, long long) const { v = s.get_int(n); }
  void operator()(const char* n, std::vector<double>& v, long long size) const { v = s.array(n, size); }
  void operator()(const char* n, std::vector<long long>& v, long long size) const {
    v = s.int_array(n, size);
  }
};

}  // namespace

void RunState::save(StateArrays& s) const {
  fields(*this, Writer{s}, -1);
  s.f64["run/load_samples"] = load_samples;
  s.f64["run/balance_warning"] = balance_warning;
}

void RunState::load(const StateArrays& s, int platens) {
  fields(*this, Reader{s}, platens);
  if (s.has("run/load_samples")) load_samples = s.array("run/load_samples");
  if (s.has("run/balance_warning")) balance_warning = s.array("run/balance_warning", 3);
}

void CutHistory::save(StateArrays& s) const {
  s.put_int("processes/contact_recuts", recuts);  // (how a restart cuts its parts: solver/run.cpp)
  s.put_int("processes/rebalances", rebalances);
  s.put_int("processes/elements_moved", elements_moved);
  if (!cut_parts.empty()) s.i64["processes/cut_parts"].assign(cut_parts.begin(), cut_parts.end());
}

void CutHistory::load(const StateArrays& s) {
  if (s.has("processes/contact_recuts")) recuts = static_cast<int>(s.get_int("processes/contact_recuts"));
  if (s.has("processes/rebalances")) rebalances = static_cast<int>(s.get_int("processes/rebalances"));
  if (s.has("processes/elements_moved")) elements_moved = s.get_int("processes/elements_moved");
}

}  // namespace fdem
