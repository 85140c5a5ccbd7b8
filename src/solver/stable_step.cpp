#include "solver/stable_step.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "common/error.hpp"

namespace fdem {

TimeStep decide_stable_step(const StepContributions& c, bool contact_now, double dt_now) {
  StableStep s;
  s.bulk = c.bulk;
  s.bulk_element = c.bulk_element;
  s.springs = std::min(c.interfaces, c.platens);
  s.springs_contact = s.springs;
  if (c.has_contact) s.springs_contact = std::min({s.springs, c.contact, c.platens_on_surfaces});
  auto combine = [&](double springs) {
    return 1.0 / std::sqrt(1.0 / (s.bulk * s.bulk) +
                           (std::isfinite(springs) ? 1.0 / (springs * springs) : 0.0));
  };
  s.critical_contact = combine(s.springs_contact);
  s.critical_summed = s.critical_contact;
  if (c.has_contact) {  // the contact springs and the interface springs of a crack face's node at once
    double inv2 = 1.0 / (s.bulk * s.bulk);
    for (double t : {c.interfaces, c.contact})
      if (std::isfinite(t)) inv2 += 1.0 / (t * t);
    s.critical_summed = std::min(s.critical_contact, 1.0 / std::sqrt(inv2));
  }
  // Until surfaces can meet (a single body whose interfaces are all intact) the contact springs
  // and the platens' springs on crack faces act on nothing: the step is set without them.
  s.contact_pending = c.has_contact && !c.may_meet && s.springs_contact < s.springs;
  if (!s.contact_pending) s.springs = s.springs_contact;
  s.critical = combine(s.springs);
  TimeStep out;
  if (!contact_now) {
    out.stable = s;
    out.dt = c.safety * s.critical;
    if (c.dt_cap > 0 && c.dt_cap < out.dt) out.dt = c.dt_cap;
    return out;
  }
  double next = dt_now * s.critical_contact / s.critical;
  if (c.dt_cap > 0) next = std::max(next, std::min({dt_now, c.dt_cap, c.safety * s.critical_contact}));
  out.dt = std::min(next, dt_now);
  s.springs = s.springs_contact;
  s.critical = s.critical_contact;
  s.contact_pending = false;
  out.stable = s;
  return out;
}

namespace {
std::string num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}
}  // namespace

std::string contact_step_warning(const StableStep& stable, double safety, double dt_cap) {
  if (!(stable.critical_summed > 0) || !(stable.critical_summed < stable.critical_contact)) return "";
  double dt = safety * stable.critical_contact;
  if (dt_cap > 0) dt = std::min(dt, dt_cap);
  if (!(dt > stable.critical_summed)) return "";
  const double ratio = stable.critical_summed / stable.critical_contact;
  return "the time step once surfaces meet, " + num(dt) + " s (time.safety_factor " + num(safety) +
         " x the critical step with contact " + num(stable.critical_contact) + " s), is above " +
         num(stable.critical_summed) + " s, the estimate with a crack face's contact and interface springs summed (" +
         num(ratio) + " of the critical step), from about 1.1 times which fragmenting runs have blown up "
         "(docs/robustness.md section 1.9): a time.safety_factor of at most " + num(ratio) + " stays below it";
}

void check_step_count(const std::string& file, double dt, double end_time, long max_steps,
                      const StableStep& stable) {
  const std::string crit = "the critical step is " + num(stable.critical) + " s (bulk " + num(stable.bulk) +
                           " s, springs " + num(stable.springs) + " s)";
  if (!(dt > 0) || !std::isfinite(dt))
    throw InputError(file + ": the time step dt = " + num(dt) + " s is not positive and finite; " + crit +
                     " (check materials.*.density and E, the interface stiffnesses and time.dt)");
  const double to_end = std::ceil(end_time / dt);
  const double steps = max_steps > 0 ? std::min(to_end, static_cast<double>(max_steps)) : to_end;
  if (!(steps <= kMaxRunSteps))
    throw InputError(file + ": time.end_time / dt = " + num(end_time) + " s / " + num(dt) +
                     " s = " + num(to_end) + " steps, above the limit of " + num(kMaxRunSteps) +
                     " steps (a run that long cannot finish): give time.end_time <= " +
                     num(kMaxRunSteps * dt) + " s, a larger time.dt or time.max_steps; " + crit);
}

}  // namespace fdem
