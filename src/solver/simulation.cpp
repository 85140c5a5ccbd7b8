#include "solver/simulation.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "solver/state_fields.hpp"

namespace fdem {

template <int D>
void Simulation<D>::set_strength_reduction(double factor) {
  if (!(factor > 0) || !std::isfinite(factor))
    throw InputError("strength reduction factor must be positive and finite (got " + std::to_string(factor) +
                     ")");
  srf_ = factor;
  m.coh.ft = coh0_.ft / factor;
  m.coh.c = coh0_.c / factor;
  m.coh.tanphi = coh0_.tanphi / factor;
  m.coh.tanphir = coh0_.tanphir > 0 ? coh0_.tanphir / factor : coh0_.tanphir;  // (< 0: the paper's law)
  m.coh.rescale = srf_hist_ / factor;
  m.srf = factor;  // interfaces with their own parameters (InterfaceData::params)
  if (contact_) {
    contact_->law.mu = mu0_ / factor;
    contact_->law.srf = factor;
  }
}

// One step of the method (docs/theory.md section 2): internal forces, platens, contact, the
// energy ledger at time t, the node update.
template <int D>
void Simulation<D>::step(bool sample) {
  sample = sample || !have_reference_;
  // The phases are timed on sampled steps only: a clock that stops when its phase's kernels have
  // finished needs a fence, and an unsampled step waits for nothing (tests/test_gpu_ready.cpp).
  const bool timed = sample;
  if (timed) fence("fdem::step: before the phase clocks");  // the work queued before is not this step's
  Kokkos::Timer clock;
  auto lap = [&clock, timed](double& phase) {  // the phase's kernels finish before its clock stops
    if (!timed) return;
    fence("fdem::step: phase clock");
    phase += clock.seconds();
    clock.reset();
  };
  // interfaces handed over to contact at this step's poll act no more in it (ContactSystem::poll)
  if (contact_) {
    contact_->poll(m);
    // the platens act on the faces handed over at the poll from this step on
    if (platens_.surfaces_changed(*contact_)) platens_.follow_surfaces(m, *contact_, t);
  }
  // (over several processes the force pass contributes, and contact adds its forces in a pass of
  // its own: Parts::force_pass_contributes)
  m.step_dt = dt;  // x(n) - x(n-1) = v(n - 1/2) dt (a step change applies from the step after it)
  compute_forces<D>(m, scatter_, force_pass_contributes_);
  if (m.coh.rescale != 1.0) {  // the histories now follow the present strength
    m.coh.rescale = 1.0;
    srf_hist_ = srf_;
  }
  lap(phase_times_.forces);
  // The platens add into m.f directly. Where contact's pass shares the force pass's scatter (one
  // process), they act after both passes and before the scatter's copies are added: m.f then
  // holds the first thread's sums, which the platens' forces commute with (kernels/fdem_kokkos.hpp,
  // ForceScatter); the same sums to the bit as adding them before both.
  const bool platens_last = contact_ && !force_pass_contributes_;
  if (!platens_last) {
    platens_.apply(m, t, dt);
    lap(phase_times_.platens);
  }
  if (contact_) {
    parts_.open_ghost_forces(m, scatter_);
    contact_->update(m, dt, scatter_);  // into the force kernel's scatter view, then one contribute
    if (platens_last) {
      lap(phase_times_.contact);
      platens_.apply(m, t, dt);
      lap(phase_times_.platens);
    }
    contribute_forces<D>(m.f, scatter_);
    parts_.return_ghost_forces(m, phase_times_.exchange);
    if (contact_->polled()) agree_on_contact();
    if (stable.contact_pending && surfaces_may_meet()) apply_contact_step();
    lap(phase_times_.contact);
  }
  if (sample_reactions_) loads_.sample_reactions(m, parts_);  // (from this step's forces)
  Energies e = sample_energies(sample);
  lap(phase_times_.ledger);
  const NodeSums w = update_nodes_now(sample);
  platens_.advance(m, parts_, dt, prm_.dtv);  // a driven platen moves with the nodes (none: nothing)
  lap(phase_times_.nodes);
  book_energies(e, w, sample);
  t += dt;
  ++step_count;
  lap(phase_times_.ledger);
  // the ghosts take their owners' new positions (one process: nothing); timed as `exchange` on
  // every step, apart from the phases above
  parts_.exchange_ghosts(m, phase_times_.exchange);
  ++phase_times_.steps;
  if (timed) ++phase_times_.timed;
}

template <int D>
Energies Simulation<D>::sample_energies(bool sample) {
  Energies e;
  e.time = t;
  e.step = step_count;
  if (!sample) return e;
  // state at time t: positions x(n), forces and interface history at x(n)
  e.strain = strain_energy<D>(m);
  if (m.ni > 0) {
    const InterfaceSums is = interface_state<D>(m);
    e.interface_elastic = is.elastic;
    e.fracture = is.fracture;
    e.friction = is.friction;  // (book_energies adds the platens' and the contacts')
    e.damaged = static_cast<long>(is.damaged);
    e.failed = static_cast<long>(is.failed);
  }
  e.contact_elastic = platens_.stored_energy(m, t) + (contact_ ? contact_->elastic_energy() : 0.0);
  return e;
}

template <int D>
void Simulation<D>::book_energies(Energies& e, const NodeSums& w, bool sample) {
  if (!sample) return;  // this step's works are in work_dev_
  pull_works();  // the works before this step
  {
    // Works done by time t: everything before this step plus the part of this step's increment
    // (centred on x(n): over [t - dt/2, t + dt/2]) up to t.
    double wp = 0;
    platens_.book(m, t, dt, step_count + 1, wp, e.friction);
    if (contact_) e.friction += contact_->dissipated();
    e.kinetic = w.kinetic;
    for (int k = 0; k < 3; ++k) e.momentum[k] = w.momentum[k];
    e.damping = work_damping_ + 0.5 * w.damping;
    e.work_external = wp + work_bc_ + 0.5 * w.bc_work + w.gravity_work + w.load_work;
    // ramped point loads: each step's work spans [t, t + dt] (kernels/nodes.hpp), so the work by
    // time t is that of the steps before
    if (prm_.load_ramps > 0) e.work_external += work_ramp_;
    // every part's own share, summed: the whole run's (the ledger's table, solver/ledger.hpp)
    sum_energies(e, [this](double* v, int n) { parts_.sum(v, n); });
    sample_added_terms(e);
    const double now = energy_now(e), work = energy_work(e);
    if (!have_reference_) {
      reference_ = now - work;
      have_reference_ = true;
    }
    e.balance_error = now - work - reference_;
    e.scale = std::max({std::fabs(now), std::fabs(reference_) + std::fabs(work), energy_floor_, 1e-300});
    energies_ = e;
  }
  add_node_works(work_dev_, w);  // (the host copies stay those before this step: read, not written)
}

template <int D>
void Simulation<D>::pull_works() const {
  auto h = Kokkos::create_mirror_view(work_dev_);
  Kokkos::deep_copy(h, work_dev_);
  work_damping_ = h(0);
  work_bc_ = h(1);
  work_ramp_ = h(2);
}

template <int D>
void Simulation<D>::push_works() {
  auto h = Kokkos::create_mirror_view(work_dev_);
  h(0) = work_damping_;
  h(1) = work_bc_;
  h(2) = work_ramp_;
  Kokkos::deep_copy(work_dev_, h);
}

template <int D>
void Simulation<D>::agree_time_step(const StepContributions& all) {
  if (step_count > 0) throw InputError("agree_time_step: the run has started");
  step_sources_ = all;
  const TimeStep ts = decide_stable_step(step_sources_);
  stable = ts.stable;
  dt = ts.dt;
}

template <int D>
void Simulation<D>::take_contact_step() {
  const TimeStep ts = decide_stable_step(step_sources_, /*contact_now=*/true, dt);
  dt = ts.dt;
  stable = ts.stable;
}

template <int D>
void Simulation<D>::apply_contact_step() {
  // Leap-frog with a step change at x(n): v(n+1/2) = v(n-1/2) + (dt_old + dt_new) / 2 a(n),
  // x(n+1) = x(n) + dt_new v(n+1/2). The contact forces of this step are already in m.f.
  dt_before_change_ = dt;
  dt_changed_at_ = step_count;
  take_contact_step();
  dtv_next_ = 0.5 * (dt_before_change_ + dt);
}

namespace {

// The node update of a step, sampled or not, with or without damping; Ramp: ramped point loads.
template <int D, bool Ramp>
NodeSums node_update(const Model<D>& m, const NodeUpdateParams& p, bool sample, bool damp,
                     const Kokkos::View<NodeSums>& sums, const Kokkos::View<double[3]>& work) {
  if (sample) return damp ? update_nodes<D, true, true, Ramp>(m, p) : update_nodes<D, true, false, Ramp>(m, p);
  if (damp)
    update_nodes_unsampled<D, true, Ramp>(m, p, sums, work);
  else
    update_nodes_unsampled<D, false, Ramp>(m, p, sums, work);
  return NodeSums{};
}

}  // namespace

template <int D>
NodeSums Simulation<D>::update_nodes_now(bool sample) {
  prm_.t = t;
  prm_.dt = dt;
  prm_.dtv = dtv_next_ > 0 ? dtv_next_ : dt;
  dtv_next_ = 0;
  const bool damp = !skips.damping || prm_.alpha != 0.0 || prm_.cmass != 0.0;
  // unsampled: the works are summed on the device (work_dev_; book_energies)
  return prm_.load_ramps > 0 ? node_update<D, true>(m, prm_, sample, damp, node_sums_, work_dev_)
                             : node_update<D, false>(m, prm_, sample, damp, node_sums_, work_dev_);
}

template <int D>
void Simulation<D>::check_finite() {
  const int bad = first_nonfinite_node<D>(m);
  if (bad < m.nn) {
    auto X_h = Kokkos::create_mirror_view(m.X);
    Kokkos::deep_copy(X_h, m.X);
    std::ostringstream os;
    os << "state became non-finite at step " << step_count << ", time " << t << " s: node " << bad
       << " at (";
    for (int k = 0; k < D; ++k) os << (k ? ", " : "") << X_h(bad, k);
    os << ") (reference position). The time step " << dt << " s may be above the stable limit "
       << stable.critical << " s.";
    throw NumericalError(os.str());
  }
}

template <int D>
long Simulation<D>::check_inverted(std::string* where) {
  const InvertedElements inv = inverted_elements<D>(m);
  const int local = inv.count, first = inv.first;
  double all = local;  // over the processes (each counts its own elements)
  parts_.sum(&all, 1);
  const long count = static_cast<long>(all);
  if (count > 0 && where && local == 0) {
    *where = std::to_string(count) + " element(s) turned inside out at step " + std::to_string(step_count) +
             " on other processes";
  } else if (count > 0 && where) {
    auto X_h = Kokkos::create_mirror_view(m.X);
    auto x_h = Kokkos::create_mirror_view(m.x);
    auto el_h = Kokkos::create_mirror_view(m.elem);
    Kokkos::deep_copy(X_h, m.X);
    Kokkos::deep_copy(x_h, m.x);
    Kokkos::deep_copy(el_h, m.elem);
    double c0[3] = {0, 0, 0}, c1[3] = {0, 0, 0};
    for (int a = 0; a <= D; ++a)
      for (int k = 0; k < D; ++k) {
        c0[k] += X_h(el_h(first, a), k) / (D + 1);
        c1[k] += x_h(el_h(first, a), k) / (D + 1);
      }
    std::ostringstream os;
    os << count << " element(s) turned inside out at step " << step_count << ", time " << t
       << " s; the first, element " << first << ", has its centroid at (";
    for (int k = 0; k < D; ++k) os << (k ? ", " : "") << c1[k];
    os << ") (reference (";
    for (int k = 0; k < D; ++k) os << (k ? ", " : "") << c0[k];
    os << "))";
    *where = os.str();
  }
  return count;
}

template <int D>
void Simulation<D>::check_stability() {
  check_finite();
  if (!warned_inverted_) {  // reported once per run (St Venant-Kirchhoff elements can be crushed
                            // inside out by violent compression; the run goes on)
    std::string where;
    if (check_inverted(&where) > 0) {
      std::fprintf(stderr, "fdem: warning: %s. An inverted element usually means a load or an impact too "
                   "violent for the mesh, or an unstable step.\n", where.c_str());
      warned_inverted_ = true;
    }
  }
  const Energies& e = energies_;
  if (!std::isfinite(e.kinetic) || !std::isfinite(e.strain)) {
    std::ostringstream os;
    os << "energy became non-finite at step " << step_count << ", time " << t << " s";
    throw NumericalError(os.str());
  }
  if (step_count > 10 && e.balance_error > 0.5 * e.scale) {
    std::ostringstream os;
    os << "energy balance blew up at step " << step_count << ", time " << t
       << " s: the energy in the system exceeds the work done on it by " << e.balance_error
       << " J (" << 100 * e.balance_error / e.scale << " % of " << e.scale << " J). The time step "
       << dt << " s is " << dt / stable.critical << " times the estimated critical step "
       << stable.critical << " s.";
    throw NumericalError(os.str());
  }
}

template <int D>
void Simulation<D>::download(std::vector<double>& x, std::vector<double>& u, std::vector<double>& v,
                             std::vector<double>& stress, std::vector<double>& damage, bool gather) {
  auto x_h = Kokkos::create_mirror_view(m.x);
  auto X_h = Kokkos::create_mirror_view(m.X);
  auto v_h = Kokkos::create_mirror_view(m.v);
  Kokkos::deep_copy(x_h, m.x);
  Kokkos::deep_copy(X_h, m.X);
  Kokkos::deep_copy(v_h, m.v);
  x.resize(static_cast<size_t>(m.nn) * D);
  u.resize(x.size());
  v.resize(x.size());
  for (int i = 0; i < m.nn; ++i)
    for (int k = 0; k < D; ++k) {
      x[static_cast<size_t>(i) * D + k] = x_h(i, k);
      u[static_cast<size_t>(i) * D + k] = x_h(i, k) - X_h(i, k);
      v[static_cast<size_t>(i) * D + k] = v_h(i, k);
    }
  Kokkos::View<double* [6]> s("fdem::stress", m.ne);
  element_stress<D>(m, s);
  auto s_h = Kokkos::create_mirror_view(s);
  Kokkos::deep_copy(s_h, s);
  stress.resize(static_cast<size_t>(m.ne) * 6);
  for (int e = 0; e < m.ne; ++e)
    for (int c = 0; c < 6; ++c) stress[static_cast<size_t>(e) * 6 + c] = s_h(e, c);
  Kokkos::View<double*> d("fdem::damage", m.ni);
  interface_damage<D>(m, d);
  auto d_h = Kokkos::create_mirror_view(d);
  Kokkos::deep_copy(d_h, d);
  damage.assign(d_h.data(), d_h.data() + m.ni);
  if (gather) gather_whole(x, u, v, stress, damage);
}

template <int D>
template <class Fields>
void Simulation<D>::checkpoint_fields(Fields& f) {
  f.real("simulation/time", t);
  f.real("simulation/dt", dt);  // load_state checks it against this case's step first
  f.integer("simulation/contact_step_pending", stable.contact_pending, /*optional=*/true);
  f.integer("simulation/dt_changed_at", dt_changed_at_, /*optional=*/true);
  f.real("simulation/dt_before_change", dt_before_change_, /*optional=*/true);
  f.integer("simulation/step", step_count);
  f.real("simulation/work_damping", work_damping_);
  f.real("simulation/work_bc", work_bc_);
  if (prm_.load_ramps > 0)  // ramped point loads (optional: checkpoints from before had none)
    f.real("simulation/work_ramped_loads", work_ramp_, /*optional=*/true);
  f.real("simulation/energy_reference", reference_);
  f.integer("simulation/have_reference", have_reference_);
  // (the ledger's layout, solver/ledger.hpp: older checkpoints hold its first kEnergyFieldCount values)
  f.values("simulation/energies", -1, [&] { return energies_to_vector(energies_); },
           [&](const std::vector<double>& a) { energies_ = energies_from_vector(a, "simulation/energies"); });
  f.values("simulation/damping", 2, [&] { return std::array<double, 2>{prm_.alpha, prm_.cmass}; },
           [&](const std::vector<double>& a) {
             prm_.alpha = a[0];
             prm_.cmass = a[1];
           });
  // (checkpoints from before the residual friction hold 8 values: cohesive_params_from_array)
  f.values("model/cohesive", -1, [&] { return to_array(m.coh); },
           [&](const std::vector<double>& a) {
             if (a.size() != 8 && a.size() != static_cast<size_t>(kCohesiveArraySize))
               throw InputError("checkpoint entry model/cohesive has " + std::to_string(a.size()) +
                                " values (8 or " + std::to_string(kCohesiveArraySize) + " expected)");
             m.coh = cohesive_params_from_array(a.data(), static_cast<int>(a.size()));
           });
  // older checkpoints: no reduction applied yet
  f.values("simulation/strength_reduction", 3,
           [&] { return std::array<double, 3>{srf_, srf_hist_, m.coh.rescale}; },
           [&](const std::vector<double>& a) {
             srf_ = a[0];
             srf_hist_ = a[1];
             m.srf = srf_;
             m.coh.rescale = a[2];
           },
           /*optional=*/true);
  f.view("model/x", m.x);
  f.view("model/v", m.v);
  f.view("model/f", m.f);
  f.view("model/ihist", m.ihist);
  f.view("model/islip", m.islip, m.has_slip());
  f.view("model/icontact", m.icontact);
  f.view("model/icontact_pending", m.icontact_pending, m.icontact_pending.data() != nullptr);
  platens_.checkpoint_fields(f, m);
}

template <int D>
void Simulation<D>::save_state(StateArrays& s) const {
  pull_works();
  StateSaver saver(s);
  const_cast<Simulation*>(this)->checkpoint_fields(saver);  // the saver only reads
  if (contact_) contact_->save_state(s, parts_.node_global());  // (empty on one process)
}

template <int D>
void Simulation<D>::load_state(const StateArrays& s) {
  const double saved_dt = s.get("simulation/dt");
  // The step of this case at the checkpoint: before or after contact's stable step applied
  // (checkpoints written before that was lazy have no flag: the contact step from the start).
  const bool pending =
      s.has("simulation/contact_step_pending") && s.get_int("simulation/contact_step_pending") != 0;
  if (stable.contact_pending && !pending) {
    take_contact_step();
    if (saved_dt != dt)
      throw InputError("checkpoint '" + s.file + "': time step " + std::to_string(saved_dt) +
                       " s differs from this case's " + std::to_string(dt) + " s (contact on)");
  } else if (saved_dt != dt || pending != stable.contact_pending) {
    throw InputError("checkpoint '" + s.file + "': time step " + std::to_string(saved_dt) +
                     " s differs from this case's " + std::to_string(dt) + " s");
  }
  if (contact_ && !s.has("contact/pair_count") && !s.has("contact/pairs"))
    throw InputError("checkpoint '" + s.file + "' has no contact state but this case has contact");
  if (!contact_ && s.has("contact/pair_count"))
    throw InputError("checkpoint '" + s.file + "' has contact state but this case has no contact");
  if (m.has_slip() && !s.has("model/islip"))
    throw InputError("checkpoint '" + s.file +
                     "' holds no slip states of softening interfaces: it was written with the paper's interface "
                     "law (or before the residual friction); restart it with \"law\": \"paper\" on "
                     "the case's interface materials");
  StateLoader loader(s);
  checkpoint_fields(loader);
  push_works();
  if (!contact_) platens_.settle_loaded(m);  // (with contact: follow_surfaces below)
  if (contact_) {
    contact_->load_state(s, m, parts_.node_global());
    platens_.follow_surfaces(m, *contact_, t);
    contact_->law.mu = mu0_ / srf_;
    contact_->law.srf = srf_;
    agree_on_meeting();  // (over processes: collective, as the restart is)
  }
  parts_.exchange_ghosts(m, phase_times_.exchange);  // (one process: no ghosts)
}

template class Simulation<2>;
template class Simulation<3>;

}  // namespace fdem
