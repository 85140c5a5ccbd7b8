#pragma once
// The progress line of a run on stderr.
#include <chrono>
#include <string>

namespace fdem {

// A duration for people: "42 s", "3.5 min", "2.1 h"; "?" when not finite.
std::string fmt_time(double s);

// The time left ("left" in the progress line), from the pace since the first update: `since`
// seconds of wall time and `steps` steps in which `done` of the end time was simulated, `left` of
// the end time still to go. NaN (shown "?") until the pace is known: kPaceSeconds and kPaceSteps
// since the first update (the first step and the set-up before it are no measure of it); 0 once
// nothing is left.
constexpr double kPaceSeconds = 2.0;
constexpr long kPaceSteps = 10;
double time_left(double since, long steps, double done, double left);

// Progress: a line rewritten in place on a terminal; on a log, a line every 10 % or 60 s.
class Progress {
 public:
  using Clock = std::chrono::steady_clock;
  // step0, t0: where this process started (a restart goes on from there; the time left counts
  // from the first update, whatever t0)
  Progress(bool on, long step0, double t0);
  void update(long step, double t, double end_time, bool force = false);
  void done();
  // A line of its own between progress updates.
  void note(const std::string& line);

 private:
  bool on_, tty_;
  Clock::time_point start_, last_{};
  Clock::time_point first_{};  // the first update: step and time then (step -1: none yet)
  long first_step_ = -1;
  double first_t_ = 0;
  int last_decile_ = -1;
  long step0_;
};

}  // namespace fdem
