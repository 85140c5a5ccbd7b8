#pragma once
// `fdem ensemble`: N realisations of one case that differ only in named random sources, each an
// ordinary run folder DIR/r0000 ..., run J at a time as child processes (`fdem run`), and the
// statistics of their results (DIR/ensemble.csv, DIR/ensemble.json). docs/ensembles.md says what
// each source means. The driver (plan, child processes, resume) is src/solver/ensemble.cpp; the
// table and the statistics src/solver/ensemble_report.cpp.
#include <csignal>
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace fdem {

struct EnsembleOptions {
  std::string case_path, out_dir;
  std::vector<std::string> sets;     // --set key.path=value, for every realisation
  long realisations = 0;             // N, in [1, 100000]
  std::vector<std::string> vary;     // strength, orientation, mesh, velocity; empty: the default
  std::uint64_t seed = 1;            // S: every realisation's seeds derive from it and its index
  int jobs = 1;                      // realisations at once, each with its share of the cores
  int threads = 0;                   // threads per realisation; 0: the cores available / jobs
  double velocity_size = 1e-6;       // velocity: relative standard deviation of the speed factor
  double jitter = 0.2;               // mesh: the interior node jitter's amplitude (mesh.jitter)
  std::string binary;                // the fdem executable the realisations run with
  bool progress = true;
  const volatile std::sig_atomic_t* interrupt = nullptr;  // set by a signal: stop, keep what is done
};

// The sources an ensemble may vary, in the order of the table's columns.
const std::vector<std::string>& ensemble_sources();

// One realisation: its index, its seed per varied source, and the --set options that make it.
struct Realisation {
  long index = 0;
  std::vector<std::pair<std::string, std::uint64_t>> seeds;  // (source, seed)
  std::vector<std::pair<std::string, double>> values;        // drawn values (velocity_factor, ...)
  std::vector<std::string> sets;
};

// Realisation i's seeds and settings: a pure function of the options (not of the run order or the
// machine). `dim` is the case's dimension (the orientation's draw).
Realisation plan_realisation(const EnsembleOptions& o, long i, int dim);

// The seed of `source` in realisation i of an ensemble seeded S (32 bits: the range of the case's
// seeds).
std::uint64_t ensemble_seed(std::uint64_t S, long i, const std::string& source);

// Checks the options and the case (InputError naming the option or the case key; nothing is written
// then), runs what is not done yet, and writes the report. Returns the exit status: 0 all done,
// 3 some realisations failed numerically (the report says which), 128 + signal when interrupted.
int run_ensemble(EnsembleOptions o);

// The report of the realisation folders 0 .. n-1 of `dir` that are done: writes dir/ensemble.csv
// and dir/ensemble.json and returns the latter's content (src/solver/ensemble_report.cpp).
nlohmann::json write_ensemble_report(const std::string& dir, long n, const nlohmann::json& plan);

// The scalar results of one summary.json that an ensemble gathers, by key path ("energy.fracture_J"),
// in a fixed order; the timings (which differ between runs of the same realisation) apart.
std::vector<std::pair<std::string, double>> ensemble_results(const nlohmann::json& summary);
std::vector<std::pair<std::string, double>> ensemble_timings(const nlohmann::json& summary);

// Shared by the ensemble's two files (defined in src/solver/ensemble_report.cpp): realisation i's
// folder DIR/r000i, a JSON file read back (null when absent or cut short by a kill), and a number
// written with every digit (%.17g: reads back to the same double).
std::string realisation_folder(const std::string& dir, long i);
nlohmann::json read_json_file(const std::string& path);
std::string exact_number(double v);

}  // namespace fdem
