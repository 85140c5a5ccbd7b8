#pragma once
// The stable time step of a run (docs/theory.md section 7, "Time step and energy error through
// fracture"): every contribution to it, and the one function that decides the estimates and the
// step from them.
#include <limits>
#include <string>

namespace fdem {

struct StableStep {
  double bulk = 0;       // min over elements of altitude / P-wave speed
  double springs = 0;    // min over interface pairs and platen springs of 2 / omega (in force now)
  double critical = 0;   // combined estimate (1/bulk^2 + 1/springs^2)^(-1/2) (in force now)
  int bulk_element = -1;
  // With contact: the springs' and the combined estimate once surfaces can meet (contact springs
  // and the platens on crack faces counted). They apply from the step on which the first surfaces
  // can meet (a second body from the start, or the first failed interface): until then the step
  // is not shortened by springs that do not act (contact_pending).
  double springs_contact = 0, critical_contact = 0;
  bool contact_pending = false;
  // With contact: the estimate with a node's contact springs and its interface springs summed,
  // (1/bulk^2 + 1/interfaces^2 + 1/contact^2)^(-1/2), instead of the stiffer kind alone. Once
  // fragments touch, a node on a crack face carries both at once: the 3D impact's runs held to
  // 1.0 - 1.03 of this estimate and blew up from 1.11 - 1.14 of it, with stiff or soft interfaces,
  // while against critical_contact they blew up at 1.0 with the one and held there with the other
  // (docs/robustness.md section 1.9). Not the step (it would shorten every fragmenting run's step
  // by 10 - 16 % and move every published figure, while the cases' factors, chosen for accuracy,
  // sit 2 - 3 times below it); the solver warns when the step after contact is above it
  // (contact_step_warning). critical_contact without contact.
  double critical_summed = 0;
};

// Every contribution to the stable step (s), each the smallest over its items: a bulk element's
// shortest altitude over its P-wave speed, a spring's 2 / omega (omega^2 = k A / m). Infinite
// where there is none. Filled while the model is built (src/solver/model_builder.cpp).
struct StepContributions {
  static constexpr double kNone = std::numeric_limits<double>::infinity();
  double bulk = kNone;         // bulk elements
  int bulk_element = -1;       // the element that sets `bulk`
  double interfaces = kNone;   // cohesive interface node pairs, at the larger of kn and ks
  double platens = kNone;      // platen springs on the outer boundary nodes
  // With contact, once surfaces can meet: the contact springs (ContactSystem::stable_step) and
  // the platen springs on every potential surface node (crack faces included) at its largest area.
  double contact = kNone;
  double platens_on_surfaces = kNone;
  bool has_contact = false;    // the case has contact
  bool may_meet = false;       // surfaces can meet from the start (more than one body)
  double dt_cap = 0;           // the case's time.dt (0: none)
  double safety = 1;           // the case's time.safety_factor
};

// The contributions that are the smallest over the items, in one list: the parts of a decomposed
// run take the smallest of each over the parts (smallest(); over processes
// Simulation::set_decomposition), so a new contribution listed here is reduced everywhere.
// (An alias, as EnergyField in src/solver/ledger.hpp: nvcc's front end writes a spelled-out
// pointer to member with parentheses, on which g++ 12 warns.)
using StepField = double StepContributions::*;
inline constexpr StepField kSmallestOverParts[] = {
    &StepContributions::bulk, &StepContributions::interfaces, &StepContributions::platens,
    &StepContributions::contact, &StepContributions::platens_on_surfaces};
inline constexpr int kSmallestOverPartsCount =
    static_cast<int>(sizeof kSmallestOverParts / sizeof kSmallestOverParts[0]);
// A tripwire for the list above: a field added to StepContributions changes its size. List the
// new field in kSmallestOverParts when it is a smallest-over-the-items contribution (most are),
// then set the size here.
static_assert(sizeof(StepContributions) == 9 * sizeof(double),
              "StepContributions changed: is the new field in kSmallestOverParts? (then update this size)");

// The contributions of two parts of a decomposed run of one case as one (each the smaller;
// bulk_element, a part's own index, -1; dt_cap and safety, the case's, from a): the parts then
// decide the whole run's time step.
inline StepContributions smallest(const StepContributions& a, const StepContributions& b) {
  StepContributions c = a;
  for (auto f : kSmallestOverParts)
    if (b.*f < c.*f) c.*f = b.*f;
  c.bulk_element = -1;
  c.has_contact = a.has_contact || b.has_contact;
  c.may_meet = a.may_meet || b.may_meet;
  return c;
}

struct TimeStep {
  StableStep stable;
  double dt = 0;
};

// The stable-step estimates and the time step. contact_now = false: at the start of a run, the
// step safety * critical capped by time.dt, without the springs that act only once surfaces can
// meet (contact_pending) while none can yet. contact_now = true: once surfaces can meet, from the
// present step dt_now: the same fraction of the critical step with contact as before; a case's
// time.dt stays the limit.
TimeStep decide_stable_step(const StepContributions& c, bool contact_now = false, double dt_now = 0);

// A warning (empty if none) when the step the run takes once surfaces can meet (safety *
// critical_contact, or time.dt where that is smaller: dt_cap > 0) is above stable.critical_summed,
// where fragmenting runs have blown up (docs/robustness.md section 1.9).
std::string contact_step_warning(const StableStep& stable, double safety, double dt_cap);

// Most steps a run may take: 1e12. The smallest test case (the 40-element bar of
// tests/data/cases/bar.json) takes about 45 microseconds a step on one core (docs/developing.md,
// "Refusals"): 1e12 steps would take it about 1.4 years, and any real mesh longer.
inline constexpr double kMaxRunSteps = 1e12;

// Refuses (InputError naming `file` and the numbers) a time step dt that is not positive and
// finite, and a run of more than kMaxRunSteps steps: ceil(end_time / dt), or max_steps if that is
// set (> 0) and smaller. `stable` gives the critical step for the message.
void check_step_count(const std::string& file, double dt, double end_time, long max_steps,
                      const StableStep& stable);

}  // namespace fdem
