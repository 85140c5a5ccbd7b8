// A run over several processes (docs/parallel.md): process 0 meshes the case, partitions and
// decomposes it and sends each process its part (a refined case: each process builds its own from
// the coarse mesh, solver/local_setup.hpp); every process runs its part; with contact the
// parts are cut anew when a run loop asks for it, and the next run loop goes on from the whole
// state on the new parts (ProcessesRun and its phases). One concern, so one file.
#include "solver/run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>
#include <utility>

#include "common/error.hpp"
#include "common/setup_times.hpp"
#include "io/case.hpp"
#include "io/checkpoint.hpp"
#include "io/output.hpp"
#include "mesh/memory_budget.hpp"
#include "mesh/mesh.hpp"
#include "parallel/comm.hpp"
#include "parallel/decompose.hpp"
#include "parallel/partition.hpp"
#include "solver/homogenise.hpp"
#include "solver/interface_materials.hpp"
#include "solver/kept_mesh.hpp"
#include "solver/local_setup.hpp"
#include "solver/run_loop.hpp"
#include "solver/run_state.hpp"
#include "solver/simulation.hpp"
#include "solver/summary.hpp"
#include "solver/whole_state.hpp"

#include "solver/run_setup.hpp"

namespace fdem {

namespace {

// The measurement switch FDEM_CUT_METHOD (docs/parallel.md, "Rebalancing"): "rcb" (or unset), the
// cut by Zoltan's RCB; "metis", by METIS's graph of the interfaces not handed over to contact.
bool cut_by_graph() {
  const char* m = std::getenv("FDEM_CUT_METHOD");
  if (!m || !*m || std::string(m) == "rcb") return false;
  if (std::string(m) == "metis") return true;
  throw InputError("FDEM_CUT_METHOD='" + std::string(m) + "': give rcb or metis (unset: rcb)");
}

// Process 0 at a restart: every row of an entry per node left in the checkpoint (StateArrays::by_rows),
// verified against its stored checksum, into `s`.
void whole_rows_of(StateArrays& s, const std::string& name, const HostMesh& mesh) {
  const int nn = mesh.num_nodes();
  std::vector<int> all(static_cast<size_t>(nn));
  std::iota(all.begin(), all.end(), 0);
  uint64_t hash = 0;
  std::vector<double> v = read_rows(s, name, all, all.size(), all.size(), 1, nn, mesh.dim, hash);
  if (!rows_checksum_matches(s, name, hash))
    throw InputError("restart file '" + s.file + "' is damaged: dataset '" + name + "' fails its checksum");
  s.f64[name] = std::move(v);
}

// A run over several processes (RunOptions::comm; docs/parallel.md): what it cannot do yet is
// refused, naming the key. Process 0 meshes the case, partitions and decomposes it and sends each
// process its part (the others never hold the whole mesh); every process runs its part; process 0
// alone touches the output folder (every process reads a restart's checkpoint). With contact the
// parts are cut anew when a run loop asks for it (RunLoop::run: LoopEnd::Kind::cut_due), and the
// next run loop goes on from the whole state, on the new parts.
class ProcessesRun {
 public:
  ProcessesRun(const std::string& case_path, Case& c, const RunOptions& opt)
      : comm_(*opt.comm), root_(comm_.rank() == 0), c_(c), opt_(opt), prep_(prepare_run(case_path, c, opt)) {
    opt_.progress = opt.progress && root_;
    cuts_.part = &part_;
  }
  nlohmann::json run();

 private:
  bool local_parts();
  void whole_mesh_for_cut();
  void first_parts();
  std::vector<int> restart_parts(const std::vector<double>& at, PartitionMethod bisection) const;
  void check_every_part_filled(const std::vector<int>& elem_part) const;
  void send_first_parts();
  void receive_part();
  void hold_part_only();
  void take_restart_cuts();
  LoopEnd run_part();
  void record_cut(const CutRequest& cut);
  void cut_anew();
  std::vector<int> parts_by_work(const std::vector<double>& x) const;
  void send_cut();

  const Comm& comm_;
  const bool root_;
  Case& c_;
  RunOptions opt_;  // (the progress lines on process 0 only)
  PreparedRun prep_;
  double mean_size_ = std::numeric_limits<double>::infinity();  // process 0's mean element size
  std::unique_ptr<PartBuilder> parts_;  // process 0: builds every process's part as it is sent
  SubMesh part_;                           // this process's part (its mesh let go by its run loop)
  // process 0, with contact: the whole mesh, to cut the parts anew (and for each run loop's set-up;
  // kept_ holds it during the run), and the contact zones' reach
  std::shared_ptr<const HostMesh> whole_;
  KeptMesh kept_{"for cutting the parts anew"};
  double whole_reach_ = 0;
  std::vector<int> elem_part_at_start_;  // process 0: the parts this run starts with
  CutHistory cuts_;
  const StateArrays* from_ = nullptr;  // the state the next parts start from (a checkpoint, a cut's)
};

nlohmann::json ProcessesRun::run() {
  if (!local_parts()) {
    if (root_) first_parts();
    // (an error on process 0 above ends every process: the others wait in the sending)
    send_first_parts();
  }
  take_restart_cuts();
  for (;;) {
    LoopEnd end = run_part();
    if (end.kind != LoopEnd::Kind::cut_due) return std::move(end.summary);
    // Cutting the parts anew: the nodes have moved so far that a contact zone may soon miss a
    // face, or the balance asks for it. Process 0 partitions the elements by coordinate bisection
    // at the current positions (the parts follow where the material is now, so each zone stays a
    // thin layer around a compact region; METIS's graph does not know where fragments have flown),
    // decomposes the whole mesh with the zones at the current positions and sends each process its
    // part and the whole state, which each takes its rows of, as from a checkpoint
    // (load_whole_state, solver/whole_state.hpp): elements, nodes, interface and contact histories move to
    // their new owners.
    const auto cut0 = std::chrono::steady_clock::now();
    record_cut(end.cut);
    whole_mesh_for_cut();
    if (root_) cut_anew();
    send_cut();
    cuts_.cut_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - cut0).count();
  }
}

// Whether the parts are built locally (process 0 decided in prepare_run: PreparedRun::local), and
// if so every process's part built (local_setup) and the defaults resolved. No process holds the
// whole mesh: its hash and report are summed over the processes, and process 0 builds it only at
// the first cut of the parts anew (whole_mesh_for_cut), from the coarse mesh it keeps until then.
bool ProcessesRun::local_parts() {
  std::vector<char> flag(1, prep_.local ? 1 : 0);
  comm_.broadcast_bytes(flag);
  if (!flag.at(0)) return false;
  const PartitionMethod method = partition_has_metis() ? PartitionMethod::Metis
                                 : partition_has_zoltan() ? PartitionMethod::ZoltanRcb
                                                          : PartitionMethod::Rcb;
  LocalSetup ls = local_setup(c_, comm_, prep_.coarse, method, region_sets_used(c_));
  part_ = std::move(ls.part);
  mean_size_ = ls.mean_size;
  if (ls.reach <= 0) prep_.coarse = HostMesh{};  // (no contact, no cut: process 0's only)
  prep_.id.mesh_hash = ls.mesh_hash;
  cuts_.mesh_report = std::move(ls.mesh_report);
  cuts_.mesh_by_parts = true;
  hold_part_only();
  if (!root_) return true;
  write_file_atomic(prep_.out + "/case.json", c_.resolved.dump(2) + "\n");
  elem_part_at_start_ = std::move(ls.elem_part);
  whole_reach_ = ls.reach;  // (a cut builds the whole mesh: whole_mesh_for_cut)
  return true;
}

// At the first cut of a locally set-up run: process 0 builds the whole mesh from the coarse one,
// as the whole set-up does (finish_mesh; the same mesh as the parts', which their sum of hashes
// checks), and keeps it for this cut and the next ones (kept_). The parts' meshes are gone by then
// (release_part_mesh): rebuilding costs process 0 more time at the first cut than gathering them
// did, and spares every process the set-up's writing of its part's mesh to a temporary file and
// the file itself (docs/parallel.md, "The part's mesh let go").
void ProcessesRun::whole_mesh_for_cut() {
  if (!cuts_.mesh_by_parts) return;
  setup_times::Phase phase("whole_mesh_rebuilt");
  if (root_) {
    if (prep_.coarse.num_elems() == 0)
      throw std::logic_error("a cut of the parts anew in a locally set-up run without contact (no coarse mesh kept)");
    setup_times::Folded one_phase;  // (finish_mesh's phases in this one)
    HostMesh whole = finish_mesh(c_, std::move(prep_.coarse), nullptr, false);
    prep_.coarse = HostMesh{};  // (moved from: no longer needed)
    const std::string hash = mesh_hash(whole);
    if (hash != prep_.id.mesh_hash)
      throw std::logic_error("the whole mesh rebuilt for a cut of the parts anew differs from the parts' (mesh hash " +
                             hash + " against " + prep_.id.mesh_hash + ")");
    kept_.write(whole);
  }
  cuts_.mesh_by_parts = false;
}

// Process 0: the partition and the builder of the first parts (receive_part builds each as it is
// sent). With contact each part holds the faces within its
// contact zone (reach: the search distance, the contact law's penetration depth, ContactSystem::set_law,
// and the skin, and contact.zone), and the whole mesh is kept for cutting the parts anew.
void ProcessesRun::first_parts() {
  const HostMesh& mesh = prep_.mesh;
  if (mesh.num_elems() < comm_.size())
    throw InputError(c_.file + ": the mesh has " + std::to_string(mesh.num_elems()) + " elements, fewer than the " +
                     std::to_string(comm_.size()) + " processes of this run: run it on at most " +
                     std::to_string(mesh.num_elems()) + " processes (mpirun -n), or with a finer mesh");
  setup_times::Phase phase("decomposition");
  const ElementSizes mq = mesh_sizes(mesh);
  mean_size_ = mean_element_size(c_, mesh);  // (what prepare_run's defaults derived from)
  const double reach = contact_wanted(c_, mesh) ? contact_penetration_depth(mq.min_size, mean_size_) +
                                                      c_.contact.skin + c_.contact.zone
                                                : 0.0;
  // METIS when the build has it, else coordinate bisection (Zoltan's RCB where the build has
  // Zoltan, as every MPI build does; docs/parallel.md). A restart with contact cuts its parts
  // where the run last cut them (the checkpoint's processes/cut_x), as the run did: coordinate
  // bisection there after a cut during the run; so its zones hold as they did, and on as many
  // processes the parts are the same (the run goes on to the bit)
  const PartitionMethod bisection =
      partition_has_zoltan() ? PartitionMethod::ZoltanRcb : PartitionMethod::Rcb;
  const PartitionMethod method = partition_has_metis() ? PartitionMethod::Metis : bisection;
  if (reach > 0) cut_by_graph();  // a bad FDEM_CUT_METHOD fails here, before the run
  StateArrays& restart = prep_.restart;
  if (reach > 0 && restart.by_rows.count("processes/cut_x")) whole_rows_of(restart, "processes/cut_x", mesh);
  const bool resumed = reach > 0 && restart.f64.count("processes/cut_x");
  const std::vector<double>* at =
      resumed ? &restart.array("processes/cut_x", static_cast<long long>(mesh.X.size())) : nullptr;
  std::vector<int> elem_part =
      resumed && restart.has("processes/contact_recuts") && restart.get_int("processes/contact_recuts") > 0
          ? restart_parts(*at, bisection)
          : prep_.coarse.num_elems() > 0 ? refined_partition(c_, prep_.coarse, comm_.size(), method)
                                         : partition_elements(mesh, comm_.size(), method);
  check_every_part_filled(elem_part);
  elem_part_at_start_ = std::move(elem_part);
  if (reach > 0) {  // kept for cutting the parts anew during the run
    whole_ = std::make_shared<const HostMesh>(std::move(prep_.mesh));
    whole_reach_ = reach;
  }
  parts_ = std::make_unique<PartBuilder>(whole_ ? *whole_ : prep_.mesh, elem_part_at_start_, comm_.size(), reach, at);
}

// A partitioner may leave a process without elements on a tiny mesh (METIS does): its part would
// have no time step. Refused with the counts and what to do.
void ProcessesRun::check_every_part_filled(const std::vector<int>& elem_part) const {
  std::vector<long> per(static_cast<size_t>(comm_.size()), 0);
  for (int p : elem_part) ++per[static_cast<size_t>(p)];
  for (size_t p = 0; p < per.size(); ++p)
    if (per[p] == 0)
      throw InputError(c_.file + ": the partition of the mesh's " + std::to_string(elem_part.size()) +
                       " elements leaves process " + std::to_string(p) + " of " + std::to_string(comm_.size()) +
                       " without an element: run it on fewer processes (mpirun -n), or with a finer mesh");
}

// Process 0 at a restart of a run that cut its parts anew: the parts of the last cut on as many
// processes (weighted by the work then); else coordinate bisection at the cut's positions `at`
// (checkpoints written before 2026-12-04 hold no parts).
std::vector<int> ProcessesRun::restart_parts(const std::vector<double>& at, PartitionMethod bisection) const {
  const StateArrays& restart = prep_.restart;
  const long long count = restart.has("processes/count") ? restart.get_int("processes/count") : 1;
  if (count != comm_.size() || !restart.i64.count("processes/cut_parts")) {
    HostMesh moved = prep_.mesh;
    moved.X = at;
    return partition_elements(moved, comm_.size(), bisection);
  }
  const std::vector<long long>& cp = restart.int_array("processes/cut_parts");
  const std::string& file = opt_.restart;
  if (cp.size() != static_cast<size_t>(prep_.mesh.num_elems()))
    throw InputError("checkpoint '" + file + "': processes/cut_parts has " + std::to_string(cp.size()) +
                     " entries, not " + std::to_string(prep_.mesh.num_elems()) + " (the file is damaged)");
  std::vector<int> elem_part;
  for (long long p : cp) {
    if (p < 0 || p >= comm_.size())
      throw InputError("checkpoint '" + file + "': processes/cut_parts holds part " + std::to_string(p) +
                       " outside [0, " + std::to_string(comm_.size() - 1) + "] (the file is damaged)");
    elem_part.push_back(static_cast<int>(p));
  }
  return elem_part;
}

// Every process: its first part from process 0, the case's derived values (the others: from
// process 0's mean element size, the same values) and case.json (process 0).
void ProcessesRun::send_first_parts() {
  {
    setup_times::Phase phase("parts_sent");
    receive_part();
  }
  comm_.min(&mean_size_, 1);  // process 0's
  if (root_) {
    write_file_atomic(prep_.out + "/case.json", c_.resolved.dump(2) + "\n");  // (defaults: prepare_run)
  } else {
    resolve_defaults(c_, mean_size_);  // the same values from the same mean size
    hold_part_only();
  }
}

// This process's part from process 0, where parts_ builds each as it is sent (so that it holds
// one part at a time beside the whole mesh), then its exchange lists (known once every part is
// built).
void ProcessesRun::receive_part() {
  std::vector<char> mine;
  comm_.scatter_each(
      [this](int r) {
        setup_times::Phase phase("decomposition");  // (the sending is parts_sent's)
        return pack_submesh(parts_->part(r));
      },
      mine);
  part_ = unpack_submesh(mine);
  std::vector<std::vector<char>> lists;
  for (int r = 0; root_ && r < comm_.size(); ++r) lists.push_back(pack_lists(parts_->lists(r)));
  comm_.scatter_bytes(lists, mine);
  complete_lists(part_, unpack_lists(mine));
  parts_.reset();
}

// A process other than process 0 holds no whole mesh: its run loop's is an empty one with the
// dimension and the part's body count.
void ProcessesRun::hold_part_only() {
  prep_.mesh = HostMesh{};
  prep_.mesh.dim = c_.dim;
  prep_.mesh.bodies = part_.mesh.bodies;
}

// The cuts so far of the run the checkpoint is of (a restart on as many processes cuts its parts
// where that run did: process 0's parts at the start are the last cut's), and the state the first
// parts start from.
void ProcessesRun::take_restart_cuts() {
  const StateArrays& restart = prep_.restart;
  cuts_.load(restart);
  if (root_ && cuts_.recuts > 0 && restart.has("processes/contact_recuts"))
    cuts_.cut_parts = elem_part_at_start_;
  cuts_.restarted = prep_.checkpoint();
  from_ = prep_.checkpoint();
}

// This process's part run from from_ until the run ends or its parts are to be cut anew. The run
// loop takes process 0's whole mesh (kept there when it cuts the parts anew) or the others' empty one.
LoopEnd ProcessesRun::run_part() {
  if (whole_ && !kept_.kept()) {
    setup_times::Phase phase("mesh_kept");
    kept_.write(*whole_);
  }
  // (the run loop lets go of it once the snapshots are set up, before it builds the model)
  std::shared_ptr<const HostMesh> mesh =
      whole_ ? std::move(whole_) : std::make_shared<const HostMesh>(std::move(prep_.mesh));
  return c_.dim == 2 ? run_dim<2>(c_, std::move(mesh), prep_.out, opt_, prep_.id, from_, &part_, &cuts_)
                     : run_dim<3>(c_, std::move(mesh), prep_.out, opt_, prep_.id, from_, &part_, &cuts_);
}

// A cut into the CutHistory: why (for the progress note of the next parts), the balance's excesses,
// this process's busy time in the parts that ended, the cut's time so far.
void ProcessesRun::record_cut(const CutRequest& cut) {
  ++cuts_.recuts;
  cuts_.cut_seconds += cut.gather_seconds + cut.setup_seconds;
  const bool work = cut.reason == "work";
  cuts_.excess_after_cuts.push_back(cut.after_cut);
  cuts_.excess_largest = std::max(cuts_.excess_largest, cut.largest);
  cuts_.busy_seconds += cut.busy;
  char why[200];
  if (work) {
    ++cuts_.rebalances;
    cuts_.excess_at_rebalances.push_back(cut.excess);
    std::snprintf(why, sizeof why,
                  "the most loaded process's work was %.0f %% above the mean, "
                  "parallel.rebalance_above = %.3g",
                  100.0 * cut.excess, c_.rebalance_above);
  } else {
    std::snprintf(why, sizeof why, "nodes had moved far into the contact zones");
  }
  cuts_.last_cut_reason = why;
  cuts_.cut_reasons.push_back(cut.reason);
}

// Process 0 at a cut: the new parts (parts_by_work; the test hook FDEM_TEST_RECUT moves every
// element to another process), the elements that change process counted, the builder of the parts
// (receive_part); the whole mesh read back from kept_ for it and for the next run loop.
void ProcessesRun::cut_anew() {
  setup_times::Phase phase("decomposition");
  whole_ = std::make_shared<const HostMesh>(kept_.read());
  const std::vector<double>& x = cuts_.state.array("model/x", static_cast<long long>(whole_->X.size()));
  std::vector<int> elem_part = parts_by_work(x);
  if (std::getenv("FDEM_TEST_RECUT"))  // test hook (Simulation): every element to another process
    for (int& p : elem_part) p = (p + cuts_.recuts) % comm_.size();
  const std::vector<int>& before = cuts_.cut_parts.empty() ? elem_part_at_start_ : cuts_.cut_parts;
  long long moved_now = 0;  // the elements that change process at this cut
  for (size_t e = 0; e < elem_part.size(); ++e) moved_now += e >= before.size() || before[e] != elem_part[e];
  cuts_.elements_moved_at_cuts.push_back(moved_now);
  cuts_.elements_moved += moved_now;
  cuts_.cut_parts = elem_part;  // (checkpoints: a restart on as many processes cuts the same parts)
  parts_ = std::make_unique<PartBuilder>(*whole_, cuts_.cut_parts, comm_.size(), whole_reach_, &x);
}

// The parts of a cut, at the current positions x: the elements weighted by their modelled work of
// a step (WorkModel: their own and their nodes' contact work; docs/parallel.md "Rebalancing"), so
// that the parts carry equal work, not equal element counts, where the contacts gather.
std::vector<int> ProcessesRun::parts_by_work(const std::vector<double>& x) const {
  const StateArrays& state = cuts_.state;
  const std::vector<double>& nw = state.array("recut/node_work", static_cast<long long>(whole_->num_nodes()));
  const std::vector<long long>& handed =
      state.int_array("model/icontact", static_cast<long long>(whole_->num_ifaces()));
  const std::vector<double> work = element_work(*whole_, nw, handed, c_.work_model);
  if (!cut_by_graph()) {  // (the bisection reads the elements at x: those alone are copied)
    HostMesh at;
    at.dim = whole_->dim;
    at.X = x;
    at.elems = whole_->elems;
    return partition_elements_weighted(at, comm_.size(), work);
  }
  // (measurement switch) METIS on the graph of the interfaces not handed over
  HostMesh moved = *whole_;
  moved.X = x;
  std::vector<double> x3(3 * static_cast<size_t>(moved.num_nodes()), 0.0), gone(handed.size());
  for (int n = 0; n < moved.num_nodes(); ++n)
    for (int k = 0; k < moved.dim; ++k)
      x3[3 * static_cast<size_t>(n) + k] = x[static_cast<size_t>(n) * moved.dim + k];
  for (size_t i = 0; i < handed.size(); ++i) gone[i] = handed[i] != 0;
  return partition_elements_weighted(moved_mesh(moved, x3, gone), comm_.size(), work, true);
}

// Process 0's state `s` to every process, an entry at a time (each packed, sent and unpacked in
// turn, process 0 letting go of each as it packs it), the others keeping only their part's rows of
// each as it arrives (`keep`, null on process 0): no process holds the whole state twice, as a
// single message would make it (the state and its bytes; 0.93 kB per tetrahedron each), and the
// others hold their rows only.
void broadcast_state(const Comm& comm, StateArrays& s, bool root, const PartRows* keep) {
  // first the index: every entry's name (index.str: k -> name), which are integers (index.i64), the
  // strings and the file name; then the entries in that order
  StateArrays index;
  std::vector<char> bytes;
  if (root) {
    index.file = s.file;
    std::vector<long long>& integer = index.i64["integer"];
    for (const auto& kv : s.f64) {
      index.str[std::to_string(integer.size())] = kv.first;
      integer.push_back(0);
    }
    for (const auto& kv : s.i64) {
      index.str[std::to_string(integer.size())] = kv.first;
      integer.push_back(1);
    }
    bytes = pack_state(index);
  }
  comm.broadcast_bytes(bytes);
  index = unpack_state(bytes);
  StateArrays out;
  out.file = index.file;
  const std::vector<long long>& integer = index.i64.at("integer");
  for (size_t k = 0; k < integer.size(); ++k) {
    const std::string& name = index.str.at(std::to_string(k));
    StateArrays one;
    if (root) {
      if (integer[k])
        one.i64[name] = std::move(s.i64.at(name)), s.i64.erase(name);
      else
        one.f64[name] = std::move(s.f64.at(name)), s.f64.erase(name);
      bytes = pack_state(one);
      one = StateArrays{};
    }
    comm.broadcast_bytes(bytes);
    one = unpack_state(bytes);
    for (auto& kv : one.f64) {
      if (keep) keep->keep(kv.first, kv.second);
      out.f64[kv.first] = std::move(kv.second);
    }
    for (auto& kv : one.i64) {
      if (keep) keep->keep(kv.first, kv.second);
      out.i64[kv.first] = std::move(kv.second);
    }
  }
  StateArrays strings;  // (small)
  if (root) {
    strings.str = std::move(s.str);
    bytes = pack_state(strings);
  }
  comm.broadcast_bytes(bytes);
  out.str = unpack_state(bytes).str;
  if (keep) PartRows::mark(out);
  s = std::move(out);
}

// Every process at a cut: its new part and the whole state at the cut from process 0
// (broadcast_state), which the next parts start from.
void ProcessesRun::send_cut() {
  receive_part();
  // (process 0 keeps the whole state: it checks the new parts against it, ManyParts::check_cut)
  const PartRows rows{c_.dim, &part_.node_global, &part_.iface_global, part_.whole_nodes, part_.whole_ifaces};
  broadcast_state(comm_, cuts_.state, root_, root_ ? nullptr : &rows);
  cuts_.state.file = "(the run's state where its parts were cut anew)";
  if (!root_) hold_part_only();
  from_ = &cuts_.state;
}

}  // namespace

nlohmann::json run_over_processes(const std::string& case_path, Case& c, const RunOptions& opt) {
  return ProcessesRun(case_path, c, opt).run();
}

}  // namespace fdem
