#include "solver/stable_step.hpp"

#include <algorithm>
#include <cmath>

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

}  // namespace fdem
