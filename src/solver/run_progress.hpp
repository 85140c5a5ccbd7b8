#pragma once
// The progress line of a run on stderr.
#include <chrono>
#include <string>

namespace fdem {

// A duration for people: "42 s", "3.5 min", "2.1 h"; "?" when not finite.
std::string fmt_time(double s);

// Progress: a line rewritten in place on a terminal; on a log, a line every 10 % or 60 s.
class Progress {
 public:
  using Clock = std::chrono::steady_clock;
  // step0, t0: where this process started (a restart goes on from there)
  Progress(bool on, long step0, double t0);
  void update(long step, double t, double end_time, bool force = false);
  void done();
  // A line of its own between progress updates.
  void note(const std::string& line);

 private:
  bool on_, tty_;
  Clock::time_point start_, last_{};
  int last_decile_ = -1;
  long step0_;
  double t0_;
};

}  // namespace fdem
