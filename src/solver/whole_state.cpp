// The whole run's state over several processes (solver/whole_state.hpp): the gather of a
// checkpoint or a cut (save_whole_state; with the parallel HDF5 each process's own rows left to it
// to write), a part's state taken from it (load_whole_state), and the checks made after every cut
// (whole_mass_momentum, check_whole_state). Contact's lists travel as each process holds them,
// and as pairs in whole-mesh numbering for a restart on another count.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "kernels/parts.hpp"
#include "solver/whole_state.hpp"

namespace fdem {

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
          {"model/ihist", false, 1, kPointHistory * D},  {"model/icontact", false, 1, 1},
          {"model/islip", false, 1, slip_state_size<D>() * D}};  // (only with slip states: Model::islip)
}

// Accumulators of what each process's own items did (their sum is the whole run's).
const char* const kSummedEntries[] = {"simulation/work_damping", "simulation/work_bc",
                                      "simulation/work_ramped_loads", "model/platen_acc"};

const std::string kProcessesPrefix = "processes/";
const std::string kPartRowsMark = "processes/part_rows";  // (PartRows::mark)

// The per-node or per-interface entry `name` of a D-dimensional run (null: none such).
template <int D>
const ItemEntry* item_entry(const std::string& name) {
  static const std::vector<ItemEntry> items = item_entries<D>(1);  // (the platens' blocks from the size)
  for (const ItemEntry& e : items)
    if (name == e.name) return &e;
  return nullptr;
}

// v's rows of the part (PartRows::keep): each block's rows ids[i], in the order of i.
template <int D, class T>
void keep_rows(const PartRows& p, const std::string& name, std::vector<T>& v) {
  const ItemEntry* e = item_entry<D>(name);
  if (!e) return;
  const std::vector<int>& ids = e->nodes ? *p.node_global : *p.iface_global;
  const size_t whole_n = static_cast<size_t>(e->nodes ? p.whole_nodes : p.whole_ifaces);
  const size_t w = static_cast<size_t>(e->width), row = whole_n * w;
  if (row == 0 || v.size() % row != 0)
    throw InputError("the run's state at a cut: " + name + " has " + std::to_string(v.size()) +
                     " values, not a multiple of " + std::to_string(row));
  const size_t blocks = v.size() / row, n = ids.size();
  std::vector<T> mine(blocks * n * w);
  for (size_t b = 0; b < blocks; ++b)
    for (size_t i = 0; i < n; ++i)
      std::copy_n(v.begin() + static_cast<std::ptrdiff_t>((b * whole_n + static_cast<size_t>(ids[i])) * w), w,
                  mine.begin() + static_cast<std::ptrdiff_t>((b * n + i) * w));
  v = std::move(mine);
}

// An entry's values as doubles (the integer entries are flags and counts: exact).
std::vector<double> entry_values(const StateArrays& s, const std::string& name) {
  if (s.f64.count(name)) return s.f64.at(name);
  const std::vector<long long>& v = s.int_array(name);
  return std::vector<double>(v.begin(), v.end());
}

// entry_values, taking the entry out of s (no copy of a double entry)
std::vector<double> take_entry(StateArrays& s, const std::string& name) {
  std::vector<double> v;
  if (auto it = s.f64.find(name); it != s.f64.end()) {
    v = std::move(it->second);
    s.f64.erase(it);
  } else {
    v = entry_values(s, name);
    s.i64.erase(name);
  }
  return v;
}

// s without its per-node and per-interface entries (their rows are each process's own)
template <int D>
StateArrays copy_except_items(const StateArrays& s) {
  StateArrays out;
  for (const auto& [name, v] : s.f64)
    if (!item_entry<D>(name)) out.f64.emplace(name, v);
  for (const auto& [name, v] : s.i64)
    if (!item_entry<D>(name)) out.i64.emplace(name, v);
  out.str = s.str;
  out.file = s.file;
  out.by_rows = s.by_rows;
  return out;
}

// Whether some process holds the entry (the same answer on every process: collective).
template <int D>
bool held_somewhere(const Simulation<D>& sim, const StateArrays& local, const std::string& name) {
  double absent = local.has(name) ? 0.0 : 1.0;
  sim.parts().comm().min(&absent, 1);
  return absent == 0;
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

// What identifies this process's part (its node count, own nodes and a hash of their whole-mesh
// ids): a restart takes its own contact lists back only when its part is the same.
template <int D>
std::vector<double> decomposition_print(const Simulation<D>& sim) {
  const uint64_t h = fnv1a(sim.parts().node_global().data(), sim.parts().node_global().size() * sizeof(int));
  return {static_cast<double>(sim.m.nn), static_cast<double>(sim.m.owned_nodes()), static_cast<double>(h >> 32),
          static_cast<double>(h & 0xffffffffu)};
}

// Contact in the whole state: every process's own entries as they are, under "processes/" with
// their sizes under "processes/sizes/" (a restart on as many processes, cut the same way, takes its
// own back and goes on to the bit); for a restart on another count (or on one process) the pairs
// with a history in whole-mesh numbering ("contact/pairs": every process's rows), the counters
// summed, whether surfaces may meet on any process, and the poll counter (the same on all).
template <int D>
void save_contact_whole(const Simulation<D>& sim, const StateArrays& local, StateArrays& whole) {
  const bool root = sim.parts().comm().rank() == 0;
  std::vector<std::pair<std::string, bool>> names;  // (the same on every process: the same code wrote them)
  for (const auto& e : local.f64)
    if (e.first.rfind("contact/", 0) == 0) names.emplace_back(e.first, false);
  for (const auto& e : local.i64)
    if (e.first.rfind("contact/", 0) == 0) names.emplace_back(e.first, true);
  for (const auto& [name, integer] : names) {
    const std::vector<double> v = entry_values(local, name);
    std::vector<double> all, sizes;
    sim.parts().comm().gather(v, all);
    sim.parts().comm().gather({static_cast<double>(v.size())}, sizes);
    if (!root) continue;
    whole.f64.erase(name);
    whole.i64.erase(name);
    put_entry(whole, name == "contact/pairs" ? name : kProcessesPrefix + name, all, integer);
    whole.f64[kProcessesPrefix + "sizes/" + name] = sizes;
  }
  std::vector<double> cut;
  sim.parts().comm().gather(decomposition_print(sim), cut);
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

// This process's contact entries from the whole state (load_whole_state): its own as they were
// where the run had as many processes cut the same way; else (another count, or a single
// process's checkpoint) the pairs in whole-mesh numbering, from which ContactSystem::load_state
// takes those of its own nodes (counters: process 0 the sums, the others nothing).
template <int D>
void load_contact_whole(const Simulation<D>& sim, const StateArrays& whole, long long count, StateArrays& mine) {
  for (auto it = mine.f64.begin(); it != mine.f64.end();)
    it = it->first.rfind("contact/", 0) == 0 ? mine.f64.erase(it) : std::next(it);
  for (auto it = mine.i64.begin(); it != mine.i64.end();)
    it = it->first.rfind("contact/", 0) == 0 ? mine.i64.erase(it) : std::next(it);
  const std::string parts = kProcessesPrefix + "contact_parts", sizes = kProcessesPrefix + "sizes/";
  const std::vector<double> print = decomposition_print(sim);
  const size_t w = print.size(), r = static_cast<size_t>(sim.parts().comm().rank());
  const bool same = count == sim.parts().comm().size() && whole.f64.count(parts) &&
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
    if (sim.parts().comm().rank() != 0 && (n == "contact/builds" || n == "contact/handed_over" || n == "contact/list_updates" ||
                               n == "contact/dissipated"))
      std::fill(v.begin(), v.end(), 0.0);
    put_entry(mine, name, v, integer);
  }
}

// The rows read by every process (load_whole_state): each row is one process's own, so the sum of
// their checksum terms over the processes is the entry's checksum. The same verdict on every
// process.
template <int D>
void verify_rows(const Simulation<D>& sim, const StateArrays& whole, const std::vector<std::string>& names,
                 const std::vector<uint64_t>& own_hash) {
  const std::vector<uint64_t> totals =
      fdem::sum_hashes_over_processes(own_hash, [&sim](double* v, int n) { sim.parts().sum(v, n); });
  for (size_t k = 0; k < names.size(); ++k) {
    const uint64_t total = totals[k];
    if (!rows_checksum_matches(whole, names[k], total)) {
      char sum[32];
      std::snprintf(sum, sizeof sum, "%016llx", static_cast<unsigned long long>(total));
      throw InputError("restart file '" + whole.file + "' is damaged: dataset '" + names[k] +
                       "' fails its checksum (stored " + whole.by_rows.at(names[k]) + "; the rows read by the " +
                       std::to_string(sim.parts().comm().size()) + " processes give " + sum + ")");
    }
  }
}

// The whole mesh's rows of the per-node or per-interface entry e (one process's values v, each
// block all of its local rows) from every process's own rows: on process 0 (empty elsewhere).
// Collective.
template <int D>
std::vector<double> gather_entry(const Simulation<D>& sim, const ItemEntry& e, const std::vector<double>& v) {
  const size_t n = static_cast<size_t>(e.nodes ? sim.m.nn : sim.m.ni);
  const size_t own = static_cast<size_t>(e.nodes ? sim.m.owned_nodes() : sim.m.owned_ifaces());
  const size_t w = static_cast<size_t>(e.width), blocks = static_cast<size_t>(e.blocks);
  std::vector<double> out;
  for (size_t b = 0; b < blocks; ++b) {  // each block's own rows
    const std::vector<double> rows = gather_rows(sim.parts().comm(), v.data() + b * n * w, own, w,
                                                 e.nodes ? sim.parts().node_global() : sim.parts().iface_global(),
                                                 static_cast<size_t>(e.nodes ? sim.parts().whole_nodes() : sim.parts().whole_ifaces()));
    out.insert(out.end(), rows.begin(), rows.end());
  }
  return out;
}

// This process's own rows of the entry e (its values v, each block all of its local rows) for
// write_checkpoint_rows; a one-block entry's own rows come first and move in without a copy.
template <int D>
RowPart own_row_part(const Simulation<D>& sim, const ItemEntry& e, std::vector<double> v, bool integer) {
  const size_t n = static_cast<size_t>(e.nodes ? sim.m.nn : sim.m.ni);
  const size_t own = static_cast<size_t>(e.nodes ? sim.m.owned_nodes() : sim.m.owned_ifaces());
  const size_t w = static_cast<size_t>(e.width), blocks = static_cast<size_t>(e.blocks);
  RowPart r;
  r.name = e.name;
  r.integer = integer;
  r.whole_rows = e.nodes ? sim.parts().whole_nodes() : sim.parts().whole_ifaces();
  r.blocks = e.blocks;
  r.width = e.width;
  r.ids = e.nodes ? &sim.parts().node_global() : &sim.parts().iface_global();
  r.own = own;
  if (blocks == 1) {
    v.resize(own * w);  // (the ghost rows' capacity stays: a few per cent)
    r.values = std::move(v);
  } else {
    for (size_t b = 0; b < blocks; ++b)
      r.values.insert(r.values.end(), v.begin() + b * n * w, v.begin() + (b * n + own) * w);
  }
  return r;
}

}  // namespace

template <int D>
void save_whole_state(const Simulation<D>& sim, StateArrays& whole, std::vector<RowPart>* rows) {
  StateArrays local;
  sim.save_state(local);
  const bool root = sim.parts().comm().rank() == 0;
  whole = StateArrays{};
  // Each per-node and per-interface entry is taken out of `local` as it is handled (its rows into
  // `rows`, or gathered), so that this process holds its state about once, not once in `local` and
  // again in its rows (and on process 0 a third time in a copy of `local`): the checkpoint's and the
  // cut's peak memory. Process 0 keeps what is left (the entries every process holds alike) after.
  for (const ItemEntry& e : item_entries<D>(sim.m.platens.count)) {
    if (!held_somewhere(sim, local, e.name)) continue;
    const bool integer = local.i64.count(e.name) > 0;
    std::vector<double> v = take_entry(local, e.name);
    const size_t n = static_cast<size_t>(e.nodes ? sim.m.nn : sim.m.ni);
    const size_t w = static_cast<size_t>(e.width), blocks = static_cast<size_t>(e.blocks);
    if (v.size() != blocks * n * w)
      throw InputError("checkpoint: " + std::string(e.name) + " has " + std::to_string(v.size()) +
                       " values, not " + std::to_string(blocks * n * w));
    if (rows) {  // each process writes its own rows (io/checkpoint.hpp: write_checkpoint_rows)
      rows->push_back(own_row_part(sim, e, std::move(v), integer));
      continue;
    }
    const std::vector<double> out = gather_entry(sim, e, v);
    if (root) put_entry(whole, e.name, out, integer);
  }
  if (root) {  // the entries every process holds alike (those gathered above stay as gathered)
    for (auto& kv : local.f64) whole.f64.insert(kv);
    for (auto& kv : local.i64) whole.i64.insert(kv);
    for (auto& kv : local.str) whole.str.insert(kv);
  }
  for (const char* name : kSummedEntries) {
    if (!local.f64.count(name)) continue;  // (the same on every process: the case decides)
    const std::vector<double>& v = local.f64.at(name);
    std::vector<double> all;
    sim.parts().comm().gather(v, all);
    if (!root || v.empty()) continue;
    std::vector<double> total(v.size(), 0.0);
    for (size_t j = 0; j < all.size(); ++j) total[j % v.size()] += all[j];
    whole.f64[name] = total;
    whole.f64[kProcessesPrefix + name] = all;
  }
  if (root) whole.put_int(kProcessesPrefix + "count", sim.parts().comm().size());
  if (sim.contact()) {
    save_contact_whole(sim, local, whole);
    // where the parts were cut (a restart cuts its parts there: the zones then hold as they did)
    auto xc = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.cut_checks().cut_positions());
    std::vector<double> own(xc.extent(0) * D);
    for (size_t i = 0; i < xc.extent(0); ++i)
      for (int k = 0; k < D; ++k) own[i * D + k] = xc(i, k);
    if (rows) {
      RowPart r;
      r.name = kProcessesPrefix + "cut_x";
      r.whole_rows = sim.parts().whole_nodes();
      r.width = D;
      r.ids = &sim.parts().node_global();
      r.own = xc.extent(0);
      r.values = std::move(own);
      rows->push_back(std::move(r));
    } else {
      std::vector<double> cut = gather_rows(sim.parts().comm(), own.data(), xc.extent(0), D, sim.parts().node_global(), sim.parts().whole_nodes());
      if (root) whole.f64[kProcessesPrefix + "cut_x"] = std::move(cut);
    }
  }
}

template <int D>
void load_whole_state(Simulation<D>& sim, const StateArrays& whole) {
  // This part's state as it stands (just built): the rows the whole state does not give (the
  // ghost nodes' velocities, forces and platen springs, which no step reads and the run leaves as
  // they were built) stay as they are.
  StateArrays local;
  sim.save_state(local);
  // this process's state: the whole state's entries but the per-node and per-interface ones, which
  // are this part's rows of them (no copy of the whole state, which process 0 holds at a cut)
  const std::vector<ItemEntry> items = item_entries<D>(sim.m.platens.count);
  StateArrays mine = copy_except_items<D>(whole);
  const bool part_rows = whole.str.count(kPartRowsMark) > 0;
  mine.str.erase(kPartRowsMark);
  std::vector<std::string> by_rows;  // the entries read by rows from the file, and the checksum
  std::vector<uint64_t> own_hash;    // terms of this process's own rows of each
  for (const ItemEntry& e : items) {
    if (!local.has(e.name)) {  // (not this case's: passed on as the whole state has it)
      if (whole.f64.count(e.name)) mine.f64[e.name] = whole.f64.at(e.name);
      if (whole.i64.count(e.name)) mine.i64[e.name] = whole.i64.at(e.name);
      continue;
    }
    const bool integer = local.i64.count(e.name) > 0;
    std::vector<double> v = take_entry(local, e.name);
    const size_t n = static_cast<size_t>(e.nodes ? sim.m.nn : sim.m.ni);
    // (a part's rows already, PartRows: the rows in the part's local order)
    const size_t whole_n = part_rows ? n : static_cast<size_t>(e.nodes ? sim.parts().whole_nodes() : sim.parts().whole_ifaces());
    const size_t w = static_cast<size_t>(e.width), blocks = static_cast<size_t>(e.blocks);
    // the own nodes' rows (the exchanged ghosts' positions follow from them below); every local
    // interface's (each part computes its interfaces from the same history)
    const size_t rows = e.nodes ? static_cast<size_t>(sim.m.owned_nodes()) : n;
    const std::vector<int>& ids = e.nodes ? sim.parts().node_global() : sim.parts().iface_global();
    if (whole.by_rows.count(e.name)) {  // left in the file (write_checkpoint_rows): these rows only
      const size_t own = static_cast<size_t>(e.nodes ? sim.m.owned_nodes() : sim.m.owned_ifaces());
      uint64_t h = 0;
      const std::vector<double> got = read_rows(whole, e.name, ids, rows, own, e.blocks,
                                                static_cast<long long>(whole_n), e.width, h);
      for (size_t b = 0; b < blocks; ++b)
        std::copy(got.begin() + b * rows * w, got.begin() + (b + 1) * rows * w, v.begin() + b * n * w);
      by_rows.push_back(e.name);
      own_hash.push_back(h);
    } else {
      std::vector<double> converted;  // (an integer entry as doubles; a double entry is read in place)
      if (!whole.f64.count(e.name)) converted = entry_values(whole, e.name);
      const std::vector<double>& all = whole.f64.count(e.name) ? whole.f64.at(e.name) : converted;
      if (all.size() != blocks * whole_n * w)
        throw InputError("checkpoint '" + whole.file + "': " + e.name + " has " + std::to_string(all.size()) +
                         " values, not " + std::to_string(blocks * whole_n * w) + " (the file is damaged)");
      for (size_t b = 0; b < blocks; ++b)
        for (size_t i = 0; i < rows; ++i)
          for (size_t k = 0; k < w; ++k)
            v[(b * n + i) * w + k] = all[(b * whole_n + (part_rows ? i : static_cast<size_t>(ids[i]))) * w + k];
    }
    if (integer)
      put_entry(mine, e.name, v, integer);
    else
      mine.f64[e.name] = std::move(v);
  }
  verify_rows(sim, whole, by_rows, own_hash);
  // the accumulators: each process its own where the count is the same, else all on process 0
  const long long count = whole.i64.count(kProcessesPrefix + "count") ? whole.get_int(kProcessesPrefix + "count") : 1;
  for (const char* name : kSummedEntries) {
    if (!whole.f64.count(name)) continue;
    std::vector<double> v = whole.f64.at(name);
    const std::string parts = kProcessesPrefix + name;
    if (count == sim.parts().comm().size() && whole.f64.count(parts) && whole.f64.at(parts).size() == v.size() * count)
      std::copy(whole.f64.at(parts).begin() + sim.parts().comm().rank() * v.size(),
                whole.f64.at(parts).begin() + (sim.parts().comm().rank() + 1) * v.size(), v.begin());
    else if (sim.parts().comm().rank() != 0)
      std::fill(v.begin(), v.end(), 0.0);
    mine.f64[name] = v;
  }
  if (sim.contact()) load_contact_whole(sim, whole, count, mine);
  sim.load_state(mine);  // (which ends with the ghosts taking their owners' state)
}

void PartRows::keep(const std::string& name, std::vector<double>& v) const {
  dim == 2 ? keep_rows<2>(*this, name, v) : keep_rows<3>(*this, name, v);
}
void PartRows::keep(const std::string& name, std::vector<long long>& v) const {
  dim == 2 ? keep_rows<2>(*this, name, v) : keep_rows<3>(*this, name, v);
}
void PartRows::mark(StateArrays& s) { s.str[kPartRowsMark] = "yes"; }

template <int D>
std::vector<double> whole_mass_momentum(const Simulation<D>& sim) {
  double s[5];
  mass_momentum(sim.m, s);
  sim.parts().comm().sum(s, 5);
  return {s[0], s[1], s[2], s[3], s[4]};
}

template <int D>
void check_whole_state(const Simulation<D>& sim, const StateArrays& given) {
  // The state gathered again an entry at a time, each compared on process 0 and let go of (process 0
  // holds the given whole state already: a second whole copy would double its peak at a cut).
  StateArrays local;
  sim.save_state(local);
  const bool root = sim.parts().comm().rank() == 0;
  std::string diff;
  for (const ItemEntry& e : item_entries<D>(sim.m.platens.count)) {
    const std::string name = e.name;
    if (name != "model/x" && name != "model/v" && name != "model/ihist" && name != "model/icontact" &&
        name != "model/islip")
      continue;
    if (!held_somewhere(sim, local, name)) continue;
    const std::vector<double> again = gather_entry(sim, e, take_entry(local, name));
    if (!root || !given.has(name)) continue;
    const bool same = given.f64.count(name) ? given.f64.at(name) == again : entry_values(given, name) == again;
    if (!same) diff += " " + name;
  }
  StateArrays again;  // (the contact pairs with a history)
  if (sim.contact()) save_contact_whole(sim, local, again);
  // each node, element and interface owned once (a duplicate would also leave one without owner)
  double owned[3] = {static_cast<double>(sim.m.owned_nodes()), static_cast<double>(sim.m.owned_elems()),
                     static_cast<double>(sim.m.owned_ifaces())};
  sim.parts().comm().sum(owned, 3);
  if (!root) return;
  const double whole[3] = {static_cast<double>(sim.parts().whole_nodes()), static_cast<double>(sim.parts().whole_elems()),
                           static_cast<double>(sim.parts().whole_ifaces())};
  const char* what[3] = {"nodes", "elements", "interfaces"};
  for (int k = 0; k < 3; ++k)
    if (owned[k] != whole[k])
      diff += std::string(" ") + what[k] + " owned " + std::to_string(static_cast<long>(owned[k])) + " times for " +
              std::to_string(static_cast<long>(whole[k]));
  if (sim.contact()) {  // the pairs with a history, in any order
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

#define FDEM_WHOLE_STATE(D)                                                                    \
  template void save_whole_state<D>(const Simulation<D>&, StateArrays&, std::vector<RowPart>*); \
  template void load_whole_state<D>(Simulation<D>&, const StateArrays&);                       \
  template std::vector<double> whole_mass_momentum<D>(const Simulation<D>&);                   \
  template void check_whole_state<D>(const Simulation<D>&, const StateArrays&);
FDEM_WHOLE_STATE(2)
FDEM_WHOLE_STATE(3)
#undef FDEM_WHOLE_STATE

}  // namespace fdem
