#pragma once
// The run's outputs besides history.csv (solver/history_table.hpp): when each output is due
// (OutputSchedule), snapshots (RunSnapshots) and the fragment analysis (RunFragments).
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/case.hpp"
#include "io/output.hpp"
#include "io/snapshot_parallel.hpp"
#include "mesh/mesh.hpp"
#include "solver/fragment_analysis.hpp"
#include "solver/fragment_parts.hpp"
#include "solver/run_state.hpp"
#include "solver/simulation.hpp"

namespace fdem {

// Simulated times of the next history row, snapshot and checkpoint, and the step interval of the
// stability checks. History rows and checks sample the state at the start of a step.
class OutputSchedule {
 public:
  // checkpoint_every: s of simulated time (<= 0: none)
  OutputSchedule(const Case& c, double checkpoint_every);
  bool history_due(double t) const { return t >= next_hist_ * (1 - 1e-12); }
  // step: the steps done before the one to come
  bool check_due(long step) const { return check_every_ > 0 && (step + 1) % check_every_ == 0; }
  // After a step; `row`: it was sampled for a history row (the next row is then one interval on).
  void stepped(bool row);
  bool last_was_row() const { return last_was_row_; }
  // Due at time t (after a step): true, and the next one scheduled.
  bool take_snapshot(double t);
  bool take_checkpoint(double t);
  double checkpoint_every() const { return ckpt_dt_; }
  // InputError unless the checkpoint interval is 0 (none) or finite and at least one step dt
  // (shorter, the schedule would never catch up). `source`: the option or key that set it.
  void check_checkpoint_interval(double dt, const std::string& source, const std::string& file) const;

  void save(RunState& s) const;
  // t: the time of the restart point (the next checkpoint after it when the interval changed)
  void restore(const RunState& s, double t);

 private:
  double hist_dt_, snap_dt_, ckpt_dt_;
  long check_every_;
  double next_hist_ = 0, next_snap_, next_ckpt_;
  bool last_was_row_ = false;
};

// Fragments (runs with interfaces): fragments.csv at every history row, the fragment id of every
// element for the snapshots and the final statistics for summary.json.
template <int D>
class RunFragments {
 public:
  // Starts out/fragments.csv; restart: rewrites it with the checkpoint's rows (those a killed run
  // wrote after the checkpoint are dropped), then goes on. Throws InputError naming the checkpoint
  // `file` when its rows do not fit the columns.
  RunFragments(const Model<D>& m, const std::string& out, const RunState* restart = nullptr,
               const std::string& file = "");
  // A run over several processes (sim.parts().many()): each process labels its part, process 0
  // joins them (solver/fragment_parts.hpp) and alone writes (`writes`). Every process makes every
  // call below, at the same steps. restart: as above.
  RunFragments(const Simulation<D>& sim, const std::string& out, bool writes, const RunState* restart = nullptr,
               const std::string& file = "");
  // Statistics of the present state (labelled once per step).
  const FragmentStats& now(const Simulation<D>& sim);
  // The row of the instant `e` of the last history row (the present state).
  void write_row(const Simulation<D>& sim, const Energies& e);
  // Every element's fragment id: one process, its own; several, the own elements' (whole = false)
  // or the whole mesh's gathered on process 0 (whole = true; the others get none).
  void element_ids(const Simulation<D>& sim, std::vector<int>& ids, bool whole = true);
  nlohmann::json summary(const Simulation<D>& sim);
  // summary.json fragment_labelling: the labellings of this invocation, their wall time (over
  // several processes: with the exchange and the gathering) and the bytes of the last gathering.
  nlohmann::json labelling_report() const;
  void save(RunState& s) const { s.fragment_rows = rows_; }
  // The labellings so far and their wall time (summary.json fragments.labelling), and those of the
  // parts before a cut to count on from.
  std::pair<long, double> labelling() const { return {labellings_, label_seconds_}; }
  void count_from(long labellings, double seconds) {
    labellings_ += labellings;
    label_seconds_ += seconds;
  }

 private:
  std::unique_ptr<PartFragments<D>> parts_;       // over several processes
  std::unique_ptr<FragmentAnalysis<D>> analysis_;  // one process
  long labellings_ = 0;       // the labellings so far (one per step at most) and their wall time
  double label_seconds_ = 0;  // (over several processes: with the gathering)
  const Comm* comm_ = nullptr;
  nlohmann::json bodies_summary(const std::vector<BodyFragments>& b) const;
  void open_csv(const RunState* restart, const std::string& file, bool writes);
  std::string out_;
  std::vector<int> body_;  // initial body of every element (fragment_bodies.hpp)
  int bodies_ = 0;
  std::unique_ptr<HistoryWriter> csv_;
  std::vector<double> rows_;  // every row so far (row-major), for checkpoints
  long step_ = -1;  // the step the statistics are of
};

// FDEM_GATHER_OUTPUT=1 (given to every process: mpirun -x): the snapshots and checkpoints of a run
// over several processes are gathered on process 0 and written there even with the parallel HDF5,
// to measure one way against the other (docs/parallel.md, "Output").
bool gather_outputs();

// Snapshots (when the case asks for them): out/snapshots.h5 + .xdmf, one frame per step at most.
template <int D>
class RunSnapshots {
 public:
  // restart: continue the file with the frames the checkpoint lists (a warning on stderr when
  // that cannot be done and a new file is started).
  // writes = false: a process of a run over several that does not write (not process 0): it takes
  // part in every frame's gathering (Simulation::download) and writes nothing.
  RunSnapshots(const Case& c, const std::string& out, const HostMesh& mesh, const RunState* restart,
               bool writes = true);
  // A run over processes whose whole mesh no process holds (solver/local_setup.hpp): /mesh written
  // at the first frame from every process's own rows of `part` (held by the caller until then), or,
  // without the parallel HDF5, from the mesh gathered on process 0 for it.
  RunSnapshots(const Case& c, const std::string& out, const SubMesh& part, bool writes);
  bool on() const { return writer_ != nullptr; }
  // The next frame writes /mesh from the part's mesh (a run whose whole mesh no process holds).
  bool needs_part() const { return rows_ != nullptr; }
  int frames() const { return writer_ ? writer_->frames() : 0; }
  // A frame of the present state, unless there is one of this step already.
  void take(Simulation<D>& sim, RunFragments<D>* frag);
  void save(RunState& s) const;

 private:
  // Over several processes: each writes its own rows (parallel HDF5) or they are gathered on
  // process 0, which writes them (serial HDF5). Decided at the first frame.
  bool parallel(const Simulation<D>& sim);
  // The first frame of the second constructor's: /mesh from the parts (collective).
  void mesh_from_parts(const Simulation<D>& sim, bool own_rows);
  const Case* case_ = nullptr;
  const SubMesh* rows_ = nullptr;  // until the first frame: the part /mesh comes from
  std::unique_ptr<SnapshotWriter> writer_;
  bool gathers_ = false;  // takes part in the frames without writing them
  int parallel_ = -1;     // -1: not decided yet; 0: gathered on process 0; 1: ParallelFrames
  std::unique_ptr<ParallelFrames> frames_;
  std::string out_;
  long last_step_ = -1;
  std::vector<double> x_, u_, v_, stress_, damage_;
  std::vector<int> fragment_;
};

extern template class RunFragments<2>;
extern template class RunFragments<3>;
extern template class RunSnapshots<2>;
extern template class RunSnapshots<3>;

}  // namespace fdem
