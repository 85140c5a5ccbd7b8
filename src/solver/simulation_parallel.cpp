// Simulation's side of a run over several processes (docs/parallel.md): the set-up of a part
// (time step, energy floor, the first exchange), the exchange of the ghost positions after each
// node update, the gathering of the own fields on process 0 for the snapshots, and the whole run's
// checkpoint state.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "kernels/parts.hpp"
#include "solver/simulation.hpp"

namespace fdem {

template <int D>
void Simulation<D>::set_decomposition(std::shared_ptr<const Comm> comm, const SubMesh& part) {
  if (step_count > 0) throw InputError("set_decomposition: the run has started");
  if (part.mesh.num_nodes() != m.nn || part.mesh.num_elems() != m.ne || part.mesh.num_ifaces() != m.ni)
    throw InputError("set_decomposition: the model was not built from this part's mesh");
  if (contact_ && !(part.contact_reach > contact_->radius))
    throw InputError("set_decomposition: contact over processes needs a part decomposed with a contact reach "
                     "beyond the search distance (" + std::to_string(contact_->radius) + " m; got " +
                     std::to_string(part.contact_reach) + " m)");
  comm_ = std::move(comm);
  // with contact the ghosts' velocities travel too (a contact's friction reads the face's)
  halo_ = std::make_unique<Halo<D>>(part.neighbours, part.send, part.recv, /*velocities=*/contact_ != nullptr);
  zone_reach_ = part.contact_reach;
  if (const char* every = std::getenv("FDEM_TEST_RECUT")) test_recut_every_ = std::atol(every);
  if (contact_) {  // where the zones were taken: the reference positions, or those of a cut during the run
    const int own = m.owned_nodes();
    xcut_ = Kokkos::View<double* [D]>("fdem::contact::cut_positions", own);
    auto h = Kokkos::create_mirror_view(xcut_);
    auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.X);
    if (!part.cut_x.empty() && part.cut_x.size() != static_cast<size_t>(m.nn) * D)
      throw InputError("set_decomposition: the part's cut positions do not match its nodes");
    for (int i = 0; i < own; ++i)
      for (int k = 0; k < D; ++k) h(i, k) = part.cut_x.empty() ? X(i, k) : part.cut_x[static_cast<size_t>(i) * D + k];
    Kokkos::deep_copy(xcut_, h);
  }
  node_global_ = part.node_global;
  elem_global_ = part.elem_global;
  iface_global_ = part.iface_global;
  whole_nn_ = part.whole_nodes;
  whole_ne_ = part.whole_elems;
  whole_ni_ = part.whole_ifaces;
  // the time step: the smallest contributions over the processes, decided as one run would
  StepContributions& sc = step_sources_;
  double v[5] = {sc.bulk, sc.interfaces, sc.platens, sc.contact, sc.platens_on_surfaces};
  comm_->min(v, 5);
  StepContributions all = sc;
  all.bulk = v[0];
  all.interfaces = v[1];
  all.platens = v[2];
  all.contact = v[3];
  all.platens_on_surfaces = v[4];
  all.bulk_element = -1;
  if (contact_) {  // surfaces may meet on some process: on all (one time step)
    double meet = contact_->may_meet() ? -1.0 : 0.0;
    comm_->min(&meet, 1);
    all.may_meet = contact_meet_ = meet < 0;
  }
  agree_time_step(all);
  // the energy floor from the whole body's volume (each element once)
  auto vol = Kokkos::create_mirror_view(m.vol0);
  Kokkos::deep_copy(vol, m.vol0);
  double own[2] = {0, 0};
  for (int e = 0; e < m.ne; ++e) own[e < m.owned_elems() ? 0 : 1] += vol(e);
  double whole = own[0];
  comm_->sum(&whole, 1);
  if (own[0] + own[1] > 0) energy_floor_ *= whole / (own[0] + own[1]);
  exchange_ghosts();
}

template <int D>
void Simulation<D>::exchange_ghosts() {
  Kokkos::Timer clock;
  halo_->pack(m);
  fence("fdem::halo: packed");  // MPI reads the buffer
  comm_->exchange(halo_->neighbours, halo_->send_buf, halo_->send_off, halo_->recv_buf, halo_->recv_off,
                  halo_->per);
  halo_->unpack(m);  // runs before the next force pass on the same execution space: no fence
  phase_times_.exchange += clock.seconds();  // pack, MPI and the unpack's launch
}

// The contact pass of a step over several processes, after the force pass has contributed its
// forces to m.f: the ghosts' forces zeroed, the contacts of the own surface nodes added through the
// scatter view, then the forces on the ghosts sent to their owners, which add them (in the order
// of their neighbours). Every contact is computed once, by its node's owner.
template <int D>
void Simulation<D>::contact_over_parts() {
  zero_ghost_forces(m);
  scatter_.reset();
  contact_->update(m, dt, scatter_);
  Kokkos::Experimental::contribute(m.f, scatter_);
  Kokkos::Timer clock;
  halo_->pack_forces(m);
  fence("fdem::halo: ghost forces packed");  // MPI reads the buffer
  comm_->exchange(halo_->neighbours, halo_->recv_buf, halo_->recv_off, halo_->send_buf, halo_->send_off, D);
  halo_->add_forces(m);
  phase_times_.exchange += clock.seconds();
  if (contact_->polled()) agree_on_contact();
}

// On the steps the contact systems poll for failed interfaces (the same on every process): whether
// surfaces may meet anywhere (the contact time step then applies on all), and the contact zones'
// check. A process holds every element that came within zone_reach_ of its own nodes where the
// parts were cut; a face it does not hold stays beyond the search distance while
// 2 (d + 25 v dt) < zone_reach_ - search distance, with d the largest displacement since the cut
// and v the largest speed of any node (25 steps: to the next check). When that fails the parts
// are cut anew at the current positions (recut_due_; d is 0 after it), unless the speed alone
// (2 * 25 v dt) fills the zone: then no cut helps and the run stops, naming contact.zone.
//
// The same steps check the balance (Balance): each process's modelled work of a step, its largest
// and its mean over the processes; when the largest exceeds the mean by more than
// rebalance_above_ and by more than twice what it did at the first check after the last cut (so a
// cut that could not do better is not repeated at once), the parts are cut anew, weighted by the
// work (recut_reason_ "work"; solver/run.cpp).
template <int D>
void Simulation<D>::agree_on_contact() {
  double d2 = 0, v2 = 0;
  largest_drift(m, xcut_, d2, v2);
  double work = modelled_work();
  double w[4] = {contact_->may_meet() ? -1.0 : 0.0, -std::sqrt(d2), -std::sqrt(v2), -work};
  comm_->min(w, 4);  // the largest over the processes
  comm_->sum(&work, 1);
  contact_meet_ = w[0] < 0;
  const double d = -w[1], speed = -w[2], room = zone_reach_ - contact_->radius;
  const double ahead = 2.0 * 25.0 * speed * dt, need = 2.0 * d + ahead;
  Balance& b = balance_;
  b.work_most = -w[3];
  b.work_mean = work / comm_->size();
  b.excess = b.work_mean > 0 ? b.work_most / b.work_mean - 1.0 : 0.0;
  b.largest = std::max(b.largest, b.excess);
  if (b.after_cut < 0) b.after_cut = b.excess;
  auto due = [this](const char* why) {
    if (!recut_due_) recut_reason_ = why;
    recut_due_ = true;
  };
  if (b.excess > rebalance_above_ && b.excess > 2.0 * b.after_cut && ahead < room) due("work");
  if (test_recut_every_ > 0) {  // test hook: cut anew every that many steps (FDEM_TEST_RECUT)
    if (next_test_cut_ < 0) next_test_cut_ = step_count + test_recut_every_;
    if (step_count >= next_test_cut_ && ahead < room) due("test");
  }
  if (need < room) return;
  if (ahead < room) {  // valid again once cut at the current positions
    due("zones");
    return;
  }
  char msg[640];
  std::snprintf(msg, sizeof msg,
                "contact over %d processes: at step %ld (t = %.4g s) nodes move at up to %.3g m/s, so far within "
                "the 25 steps between two checks of the contact zones that each process's zone (contact.zone = "
                "%.3g m beyond the search distance) may miss a face its contacts can touch even right after the "
                "parts are cut anew: give a larger contact.zone (docs/parallel.md) or run on one process",
                comm_->size(), step_count, t, speed, room);
  throw InputError(msg);
}

// The own rows of each field gathered on process 0 in the whole mesh's order; empty elsewhere.
template <int D>
void Simulation<D>::gather_whole(std::vector<double>& x, std::vector<double>& u, std::vector<double>& v,
                                 std::vector<double>& stress, std::vector<double>& damage) {
  const size_t nn = static_cast<size_t>(m.owned_nodes()), ne = static_cast<size_t>(m.owned_elems()),
               ni = static_cast<size_t>(m.owned_ifaces());
  for (auto* a : {&x, &u, &v}) *a = gather_rows(*comm_, a->data(), nn, D, node_global_, whole_nn_);
  stress = gather_rows(*comm_, stress.data(), ne, 6, elem_global_, whole_ne_);
  damage = gather_rows(*comm_, damage.data(), ni, 1, iface_global_, whole_ni_);
}

namespace {

// Checkpoint entries with rows per node or per interface: `blocks` blocks (one per platen for the
// platens' per-node springs) of one row of `width` values per item.
struct ItemEntry {
  const char* name;
  bool nodes;  // else interfaces
  int blocks, width;
};

template <int D>
std::vector<ItemEntry> item_entries(int platens) {
  return {{"model/x", true, 1, D},           {"model/v", true, 1, D},
          {"model/f", true, 1, D},           {"model/platen_area", true, 1, 1},
          {"model/platen_fs", true, platens, D}, {"model/platen_g0", true, platens, 1},
          {"model/ihist", false, 1, 4 * D},  {"model/icontact", false, 1, 1}};
}

// Accumulators of what each process's own items did (their sum is the whole run's).
const char* const kSummedEntries[] = {"simulation/work_damping", "simulation/work_bc",
                                      "simulation/work_ramped_loads", "model/platen_acc"};

const std::string kProcessesPrefix = "processes/";

// An entry's values as doubles (the integer entries are flags and counts: exact).
std::vector<double> entry_values(const StateArrays& s, const std::string& name) {
  if (s.f64.count(name)) return s.f64.at(name);
  const std::vector<long long>& v = s.int_array(name);
  return std::vector<double>(v.begin(), v.end());
}

void put_entry(StateArrays& s, const std::string& name, const std::vector<double>& v, bool integer) {
  if (!integer) {
    s.f64[name] = v;
    return;
  }
  std::vector<long long>& out = s.i64[name];
  out.assign(v.size(), 0);
  for (size_t i = 0; i < v.size(); ++i) out[i] = static_cast<long long>(v[i]);
}

}  // namespace

template <int D>
void Simulation<D>::save_state_whole(StateArrays& whole, std::vector<RowPart>* rows) const {
  StateArrays local;
  save_state(local);
  const bool root = comm_->rank() == 0;
  whole = StateArrays{};
  if (root) whole = local;  // the entries every process holds alike; the others replaced below
  for (const ItemEntry& e : item_entries<D>(m.platens.count)) {
    double absent = local.has(e.name) ? 0.0 : 1.0;  // the same decision on every process
    comm_->min(&absent, 1);
    if (absent > 0) continue;
    const bool integer = local.i64.count(e.name) > 0;
    const std::vector<double> v = entry_values(local, e.name);
    const size_t n = static_cast<size_t>(e.nodes ? m.nn : m.ni);
    const size_t own = static_cast<size_t>(e.nodes ? m.owned_nodes() : m.owned_ifaces());
    const size_t w = static_cast<size_t>(e.width), blocks = static_cast<size_t>(e.blocks);
    if (v.size() != blocks * n * w)
      throw InputError("checkpoint: " + std::string(e.name) + " has " + std::to_string(v.size()) +
                       " values, not " + std::to_string(blocks * n * w));
    if (rows) {  // each process writes its own rows (io/checkpoint.hpp: write_checkpoint_rows)
      RowPart r;
      r.name = e.name;
      r.integer = integer;
      r.whole_rows = e.nodes ? whole_nn_ : whole_ni_;
      r.blocks = e.blocks;
      r.width = e.width;
      r.ids = e.nodes ? &node_global_ : &iface_global_;
      r.own = own;
      for (size_t b = 0; b < blocks; ++b)
        r.values.insert(r.values.end(), v.begin() + b * n * w, v.begin() + (b * n + own) * w);
      rows->push_back(std::move(r));
      whole.f64.erase(e.name);
      whole.i64.erase(e.name);
      continue;
    }
    std::vector<double> out;
    for (size_t b = 0; b < blocks; ++b) {  // each block's own rows
      const std::vector<double> rows = gather_rows(*comm_, v.data() + b * n * w, own, w,
                                                   e.nodes ? node_global_ : iface_global_,
                                                   static_cast<size_t>(e.nodes ? whole_nn_ : whole_ni_));
      out.insert(out.end(), rows.begin(), rows.end());
    }
    if (!root) continue;
    whole.f64.erase(e.name);
    whole.i64.erase(e.name);
    put_entry(whole, e.name, out, integer);
  }
  for (const char* name : kSummedEntries) {
    if (!local.f64.count(name)) continue;  // (the same on every process: the case decides)
    const std::vector<double>& v = local.f64.at(name);
    std::vector<double> all;
    comm_->gather(v, all);
    if (!root || v.empty()) continue;
    std::vector<double> total(v.size(), 0.0);
    for (size_t j = 0; j < all.size(); ++j) total[j % v.size()] += all[j];
    whole.f64[name] = total;
    whole.f64[kProcessesPrefix + name] = all;
  }
  if (root) whole.put_int(kProcessesPrefix + "count", comm_->size());
  if (contact_) {
    save_contact_whole(local, whole);
    // where the parts were cut (a restart cuts its parts there: the zones then hold as they did)
    auto xc = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), xcut_);
    std::vector<double> own(xc.extent(0) * D);
    for (size_t i = 0; i < xc.extent(0); ++i)
      for (int k = 0; k < D; ++k) own[i * D + k] = xc(i, k);
    if (rows) {
      RowPart r;
      r.name = kProcessesPrefix + "cut_x";
      r.whole_rows = whole_nn_;
      r.width = D;
      r.ids = &node_global_;
      r.own = xc.extent(0);
      r.values = std::move(own);
      rows->push_back(std::move(r));
    } else {
      std::vector<double> cut = gather_rows(*comm_, own.data(), xc.extent(0), D, node_global_, whole_nn_);
      if (root) whole.f64[kProcessesPrefix + "cut_x"] = std::move(cut);
    }
  }
}

// Contact in the whole state: every process's own entries as they are, under "processes/" with
// their sizes under "processes/sizes/" (a restart on as many processes, cut the same way, takes its
// own back and goes on to the bit); for a restart on another count (or on one process) the pairs
// with a history in whole-mesh numbering ("contact/pairs": every process's rows), the counters
// summed, whether surfaces may meet on any process, and the poll counter (the same on all).
template <int D>
void Simulation<D>::save_contact_whole(const StateArrays& local, StateArrays& whole) const {
  const bool root = comm_->rank() == 0;
  std::vector<std::pair<std::string, bool>> names;  // (the same on every process: the same code wrote them)
  for (const auto& e : local.f64)
    if (e.first.rfind("contact/", 0) == 0) names.emplace_back(e.first, false);
  for (const auto& e : local.i64)
    if (e.first.rfind("contact/", 0) == 0) names.emplace_back(e.first, true);
  for (const auto& [name, integer] : names) {
    const std::vector<double> v = entry_values(local, name);
    std::vector<double> all, sizes;
    comm_->gather(v, all);
    comm_->gather({static_cast<double>(v.size())}, sizes);
    if (!root) continue;
    whole.f64.erase(name);
    whole.i64.erase(name);
    put_entry(whole, name == "contact/pairs" ? name : kProcessesPrefix + name, all, integer);
    whole.f64[kProcessesPrefix + "sizes/" + name] = sizes;
  }
  std::vector<double> cut;
  comm_->gather(decomposition_print(), cut);
  if (!root) return;
  whole.f64[kProcessesPrefix + "contact_parts"] = cut;
  auto per = [&whole](const char* name) { return entry_values(whole, kProcessesPrefix + name); };
  auto sum = [&per](const char* name) {
    double t = 0;
    for (double v : per(name)) t += v;
    return t;
  };
  for (const char* name : {"contact/builds", "contact/handed_over", "contact/list_updates", "contact/active"})
    whole.put_int(name, static_cast<long long>(sum(name)));
  whole.put("contact/dissipated", sum("contact/dissipated"));
  const std::vector<double> meet = per("contact/may_meet");
  whole.put_int("contact/may_meet", *std::max_element(meet.begin(), meet.end()) != 0 ? 1 : 0);
  whole.put_int("contact/since_check", static_cast<long long>(per("contact/since_check").at(0)));
  whole.put_int("contact/pair_row", ContactSystem<D>::kPairRow);
}

// What identifies this process's part (its node count, own nodes and a hash of their whole-mesh
// ids): a restart takes its own contact lists back only when its part is the same.
template <int D>
std::vector<double> Simulation<D>::decomposition_print() const {
  const uint64_t h = fnv1a(node_global_.data(), node_global_.size() * sizeof(int));
  return {static_cast<double>(m.nn), static_cast<double>(m.owned_nodes()), static_cast<double>(h >> 32),
          static_cast<double>(h & 0xffffffffu)};
}

// This process's contact entries from the whole state (load_state_whole): its own as they were
// where the run had as many processes cut the same way; else (another count, or a single
// process's checkpoint) the pairs in whole-mesh numbering, from which ContactSystem::load_state
// takes those of its own nodes (counters: process 0 the sums, the others nothing).
template <int D>
void Simulation<D>::load_contact_whole(const StateArrays& whole, long long count, StateArrays& mine) const {
  for (auto it = mine.f64.begin(); it != mine.f64.end();)
    it = it->first.rfind("contact/", 0) == 0 ? mine.f64.erase(it) : std::next(it);
  for (auto it = mine.i64.begin(); it != mine.i64.end();)
    it = it->first.rfind("contact/", 0) == 0 ? mine.i64.erase(it) : std::next(it);
  const std::string parts = kProcessesPrefix + "contact_parts", sizes = kProcessesPrefix + "sizes/";
  const std::vector<double> print = decomposition_print();
  const size_t w = print.size(), r = static_cast<size_t>(comm_->rank());
  const bool same = count == comm_->size() && whole.f64.count(parts) &&
                    whole.f64.at(parts).size() == w * static_cast<size_t>(count) &&
                    std::equal(print.begin(), print.end(), whole.f64.at(parts).begin() + r * w);
  if (same) {
    for (const auto& e : whole.f64) {
      if (e.first.rfind(sizes + "contact/", 0) != 0) continue;
      const std::string name = e.first.substr(sizes.size());
      const std::string from = name == "contact/pairs" ? name : kProcessesPrefix + name;
      const std::vector<double> all = entry_values(whole, from);
      const std::vector<double>& n = e.second;
      size_t begin = 0;
      for (size_t p = 0; p < r && p < n.size(); ++p) begin += static_cast<size_t>(n[p]);
      const size_t len = r < n.size() ? static_cast<size_t>(n[r]) : 0;
      if (n.size() != static_cast<size_t>(count) || begin + len > all.size())
        throw InputError("checkpoint '" + whole.file + "': " + e.first + " does not match " + from +
                         " (the file is damaged)");
      put_entry(mine, name, std::vector<double>(all.begin() + begin, all.begin() + begin + len),
                whole.i64.count(from) > 0);
    }
    return;
  }
  if (!whole.has("contact/pairs"))
    throw InputError("checkpoint '" + whole.file + "' holds its contacts in one process's numbering only (written "
                     "before checkpoints with contact over processes): restart it on one process");
  for (const char* name : {"contact/pairs", "contact/pair_row", "contact/may_meet", "contact/since_check",
                           "contact/builds", "contact/handed_over", "contact/list_updates", "contact/dissipated"}) {
    const bool integer = whole.i64.count(name) > 0;
    std::vector<double> v = entry_values(whole, name);
    const std::string n = name;
    if (comm_->rank() != 0 && (n == "contact/builds" || n == "contact/handed_over" || n == "contact/list_updates" ||
                               n == "contact/dissipated"))
      std::fill(v.begin(), v.end(), 0.0);
    put_entry(mine, name, v, integer);
  }
}

// The rows read by every process (load_state_whole): each row is one process's own, so the sum of
// their checksum terms over the processes is the entry's checksum (exact: 32-bit halves summed as
// doubles). The same verdict on every process.
template <int D>
void Simulation<D>::verify_rows(const StateArrays& whole, const std::vector<std::string>& names,
                                const std::vector<uint64_t>& own_hash) const {
  std::vector<double> halves;
  for (uint64_t x : own_hash) {
    halves.push_back(static_cast<double>(x >> 32));
    halves.push_back(static_cast<double>(x & 0xffffffffull));
  }
  comm_->sum(halves.data(), static_cast<int>(halves.size()));
  for (size_t k = 0; k < names.size(); ++k) {
    const uint64_t total =
        (static_cast<uint64_t>(halves[2 * k]) << 32) + static_cast<uint64_t>(halves[2 * k + 1]);
    if (!rows_checksum_matches(whole, names[k], total)) {
      char sum[32];
      std::snprintf(sum, sizeof sum, "%016llx", static_cast<unsigned long long>(total));
      throw InputError("restart file '" + whole.file + "' is damaged: dataset '" + names[k] +
                       "' fails its checksum (stored " + whole.by_rows.at(names[k]) + "; the rows read by the " +
                       std::to_string(comm_->size()) + " processes give " + sum + ")");
    }
  }
}

template <int D>
void Simulation<D>::load_state_whole(const StateArrays& whole) {
  // This part's state as it stands (just built): the rows the whole state does not give (the
  // ghost nodes' velocities, forces and platen springs, which no step reads and the run leaves as
  // they were built) stay as they are.
  StateArrays local;
  save_state(local);
  StateArrays mine = whole;
  std::vector<std::string> by_rows;  // the entries read by rows from the file, and the checksum
  std::vector<uint64_t> own_hash;    // terms of this process's own rows of each
  for (const ItemEntry& e : item_entries<D>(m.platens.count)) {
    if (!local.has(e.name)) continue;
    const bool integer = local.i64.count(e.name) > 0;
    std::vector<double> v = entry_values(local, e.name);
    const size_t n = static_cast<size_t>(e.nodes ? m.nn : m.ni);
    const size_t whole_n = static_cast<size_t>(e.nodes ? whole_nn_ : whole_ni_);
    const size_t w = static_cast<size_t>(e.width), blocks = static_cast<size_t>(e.blocks);
    // the own nodes' rows (the exchanged ghosts' positions follow from them below); every local
    // interface's (each part computes its interfaces from the same history)
    const size_t rows = e.nodes ? static_cast<size_t>(m.owned_nodes()) : n;
    const std::vector<int>& ids = e.nodes ? node_global_ : iface_global_;
    if (whole.by_rows.count(e.name)) {  // left in the file (write_checkpoint_rows): these rows only
      const size_t own = static_cast<size_t>(e.nodes ? m.owned_nodes() : m.owned_ifaces());
      uint64_t h = 0;
      const std::vector<double> got = read_rows(whole, e.name, ids, rows, own, e.blocks,
                                                static_cast<long long>(whole_n), e.width, h);
      for (size_t b = 0; b < blocks; ++b)
        std::copy(got.begin() + b * rows * w, got.begin() + (b + 1) * rows * w, v.begin() + b * n * w);
      by_rows.push_back(e.name);
      own_hash.push_back(h);
    } else {
      const std::vector<double> all = entry_values(whole, e.name);
      if (all.size() != blocks * whole_n * w)
        throw InputError("checkpoint '" + whole.file + "': " + e.name + " has " + std::to_string(all.size()) +
                         " values, not " + std::to_string(blocks * whole_n * w) + " (the file is damaged)");
      for (size_t b = 0; b < blocks; ++b)
        for (size_t i = 0; i < rows; ++i)
          for (size_t k = 0; k < w; ++k)
            v[(b * n + i) * w + k] = all[(b * whole_n + static_cast<size_t>(ids[i])) * w + k];
    }
    mine.f64.erase(e.name);
    mine.i64.erase(e.name);
    put_entry(mine, e.name, v, integer);
  }
  verify_rows(whole, by_rows, own_hash);
  // the accumulators: each process its own where the count is the same, else all on process 0
  const long long count = whole.i64.count(kProcessesPrefix + "count") ? whole.get_int(kProcessesPrefix + "count") : 1;
  for (const char* name : kSummedEntries) {
    if (!whole.f64.count(name)) continue;
    std::vector<double> v = whole.f64.at(name);
    const std::string parts = kProcessesPrefix + name;
    if (count == comm_->size() && whole.f64.count(parts) && whole.f64.at(parts).size() == v.size() * count)
      std::copy(whole.f64.at(parts).begin() + comm_->rank() * v.size(),
                whole.f64.at(parts).begin() + (comm_->rank() + 1) * v.size(), v.begin());
    else if (comm_->rank() != 0)
      std::fill(v.begin(), v.end(), 0.0);
    mine.f64[name] = v;
  }
  if (contact_) load_contact_whole(whole, count, mine);
  load_state(mine);
  exchange_ghosts();
}

template <int D>
std::vector<double> Simulation<D>::whole_mass_momentum() const {
  double s[5];
  mass_momentum(m, s);
  comm_->sum(s, 5);
  return {s[0], s[1], s[2], s[3], s[4]};
}

template <int D>
void Simulation<D>::check_state_whole(const StateArrays& given) const {
  StateArrays again;
  save_state_whole(again);
  // each node, element and interface owned once (a duplicate would also leave one without owner)
  double owned[3] = {static_cast<double>(m.owned_nodes()), static_cast<double>(m.owned_elems()),
                     static_cast<double>(m.owned_ifaces())};
  comm_->sum(owned, 3);
  if (comm_->rank() != 0) return;
  std::string diff;
  const double whole[3] = {static_cast<double>(whole_nn_), static_cast<double>(whole_ne_),
                           static_cast<double>(whole_ni_)};
  const char* what[3] = {"nodes", "elements", "interfaces"};
  for (int k = 0; k < 3; ++k)
    if (owned[k] != whole[k])
      diff += std::string(" ") + what[k] + " owned " + std::to_string(static_cast<long>(owned[k])) + " times for " +
              std::to_string(static_cast<long>(whole[k]));
  for (const char* name : {"model/x", "model/v", "model/ihist", "model/icontact"})
    if (given.has(name) && entry_values(given, name) != entry_values(again, name)) diff += std::string(" ") + name;
  if (contact_) {  // the pairs with a history, in any order
    const size_t w = ContactSystem<D>::kPairRow;
    auto rows = [w](const std::vector<double>& v) {
      std::vector<std::vector<double>> r;
      for (size_t j = 0; j + w <= v.size(); j += w) r.emplace_back(v.begin() + j, v.begin() + j + w);
      std::sort(r.begin(), r.end());
      return r;
    };
    const auto a = rows(given.array("contact/pairs")), b = rows(again.array("contact/pairs"));
    if (a != b)
      diff += " contact/pairs (" + std::to_string(a.size()) + " pairs with a history given, " +
              std::to_string(b.size()) + " held)";
  }
  if (!diff.empty())
    throw std::logic_error("internal error: the parts cut anew do not hold the run's state they were given:" + diff);
}

#define FDEM_SIMULATION_PARALLEL(D)                                                            \
  template void Simulation<D>::set_decomposition(std::shared_ptr<const Comm>, const SubMesh&); \
  template void Simulation<D>::exchange_ghosts();                                              \
  template void Simulation<D>::contact_over_parts();                                           \
  template void Simulation<D>::agree_on_contact();                                             \
  template void Simulation<D>::save_state_whole(StateArrays&, std::vector<RowPart>*) const;   \
  template void Simulation<D>::verify_rows(const StateArrays&, const std::vector<std::string>&, \
                                           const std::vector<uint64_t>&) const;                \
  template std::vector<double> Simulation<D>::whole_mass_momentum() const;                     \
  template void Simulation<D>::check_state_whole(const StateArrays&) const;                    \
  template void Simulation<D>::save_contact_whole(const StateArrays&, StateArrays&) const;     \
  template void Simulation<D>::load_contact_whole(const StateArrays&, long long, StateArrays&) const; \
  template std::vector<double> Simulation<D>::decomposition_print() const;                     \
  template void Simulation<D>::load_state_whole(const StateArrays&);                           \
  template void Simulation<D>::gather_whole(std::vector<double>&, std::vector<double>&,        \
                                            std::vector<double>&, std::vector<double>&,        \
                                            std::vector<double>&);
FDEM_SIMULATION_PARALLEL(2)
FDEM_SIMULATION_PARALLEL(3)
#undef FDEM_SIMULATION_PARALLEL

}  // namespace fdem
