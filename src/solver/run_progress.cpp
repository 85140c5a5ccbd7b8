#include "solver/run_progress.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>

namespace fdem {

std::string fmt_time(double s) {
  char buf[64];
  if (!std::isfinite(s)) return "?";
  if (s < 120) std::snprintf(buf, sizeof buf, "%.0f s", s);
  else if (s < 7200) std::snprintf(buf, sizeof buf, "%.1f min", s / 60);
  else std::snprintf(buf, sizeof buf, "%.1f h", s / 3600);
  return buf;
}

double time_left(double since, long steps, double done, double left) {
  if (!(left > 1e-9)) return 0.0;  // (the loop ends at end_time (1 - 1e-12))
  if (since < kPaceSeconds || steps < kPaceSteps || !(done > 0)) return NAN;
  return since * left / done;
}

Progress::Progress(bool on, long step0, double /*t0*/)
    : on_(on), tty_(isatty(fileno(stderr))), start_(Clock::now()), step0_(step0) {}

void Progress::update(long step, double t, double end_time, bool force) {
  if (!on_) return;
  const auto now = Clock::now();
  if (first_step_ < 0) {  // (whether a line is due or not)
    first_ = now;
    first_step_ = step;
    first_t_ = t;
  }
  const double wall = std::chrono::duration<double>(now - start_).count();
  const double since = std::chrono::duration<double>(now - last_).count();
  const double frac = end_time > 0 ? t / end_time : 0;
  const int decile = static_cast<int>(frac * 10);
  const bool due = tty_ ? since > 0.5 : (since > 60 || decile > last_decile_);
  if (!due && !force) return;
  last_ = now;
  last_decile_ = decile;
  const double rate = wall > 0 ? (step - step0_) / wall : 0;
  const double paced = std::chrono::duration<double>(now - first_).count();
  const double eta =
      end_time > 0 ? time_left(paced, step - first_step_, (t - first_t_) / end_time, 1 - frac) : NAN;
  std::fprintf(stderr, "%sstep %ld  t = %.4e s (%5.1f %%)  %.3g steps/s  elapsed %s  left %s%s",
               tty_ ? "\r" : "", step, t, 100 * frac, rate, fmt_time(wall).c_str(),
               fmt_time(eta).c_str(), tty_ ? "   " : "\n");
  std::fflush(stderr);
}

void Progress::done() {
  if (on_ && tty_) std::fprintf(stderr, "\n");
}

void Progress::note(const std::string& line) {
  if (!on_) return;
  std::fprintf(stderr, "%s%s\n", tty_ ? "\r" : "", line.c_str());
  std::fflush(stderr);
}

}  // namespace fdem
