// Ensembles (src/solver/ensemble.hpp): the statistics against tabulated values, the random sources
// (mesh rotation and jitter, the velocity factor, the seeds), and `fdem ensemble` end to end: the
// statistics recomputed from ensemble.csv, the same command giving the same ensemble.json bit for
// bit, an ensemble killed and started again giving the same, and bad input refused with exit
// status 2 and nothing written.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "common/error.hpp"
#include "common/statistics.hpp"
#include "io/case.hpp"
#include "mesh/mesh.hpp"
#include "solver/ensemble.hpp"
#include "test_files.hpp"

namespace {

namespace fs = std::filesystem;
using fdem::test::slurp;
using json = nlohmann::json;

TEST(Ensemble, StudentTQuantilesMatchTables) {
  // Two-sided 95 % values of Student's t (any statistics table); at 1e7 degrees of freedom the
  // normal's 1.959963985 plus the first term of its expansion, (z^3 + z) / (4 nu) = 2.372e-7.
  const std::map<double, double> table = {{1, 12.706204736}, {2, 4.302652730}, {4, 2.776445105},
                                          {15, 2.131449546}, {29, 2.045229642}, {1e7, 1.959964222}};
  for (const auto& [nu, t] : table) EXPECT_NEAR(fdem::stats::student_t_quantile(0.975, nu), t, 2e-8 * t) << nu;
  EXPECT_NEAR(fdem::stats::student_t_cdf(0, 3), 0.5, 1e-15);
  EXPECT_NEAR(fdem::stats::student_t_cdf(-2.776445105, 4), 0.025, 1e-9);
  EXPECT_NEAR(fdem::stats::incomplete_beta(2, 3, 0.4), 0.5248, 1e-12);  // 1 - sum_{k<2} C(4,k) .4^k .6^(4-k)
}

TEST(Ensemble, SummaryOfASample) {
  const auto s = fdem::stats::summarise({1, 2, 3, 4});
  EXPECT_EQ(s.n, 4);
  EXPECT_DOUBLE_EQ(s.mean, 2.5);
  EXPECT_NEAR(s.sd, std::sqrt(5.0 / 3.0), 1e-15);
  EXPECT_NEAR(s.se, std::sqrt(5.0 / 3.0) / 2, 1e-15);
  EXPECT_NEAR(s.ci_high - s.mean, 3.182446305 * s.se, 1e-8);  // t(0.975, 3)
  EXPECT_NEAR(s.mean - s.ci_low, 3.182446305 * s.se, 1e-8);
  EXPECT_EQ(s.min, 1);
  EXPECT_EQ(s.max, 4);
  const auto one = fdem::stats::summarise({7});
  EXPECT_EQ(one.sd, 0);
  EXPECT_EQ(one.ci_low, 7);
  EXPECT_EQ(fdem::stats::summarise({}).n, 0);
}

double edge(const fdem::HostMesh& m, int a, int b) {
  double s = 0;
  for (int k = 0; k < m.dim; ++k) s += std::pow(m.X[a * m.dim + k] - m.X[b * m.dim + k], 2);
  return std::sqrt(s);
}

TEST(Ensemble, RotationKeepsTheShapeAndTurnsIt) {
  fdem::HostMesh box = fdem::generate_box({0, 0, 0}, {2, 1, 1}, 4, 2, 2);
  const fdem::HostMesh before = box;
  fdem::MeshSpec spec;
  spec.rotation_deg = 90;
  spec.rotation_axis = {0, 0, 3};  // normalised by the rotation
  EXPECT_EQ(fdem::transform_mesh(box, spec), 0);  // (no jitter: no node moved by it)
  // About the bounding box's centre (1, 0.5, 0.5): (x, y, z) -> (1 - (y - 0.5), 0.5 + (x - 1), z).
  for (int n = 0; n < box.num_nodes(); ++n) {
    EXPECT_NEAR(box.X[3 * n + 0], 1 - (before.X[3 * n + 1] - 0.5), 1e-14);
    EXPECT_NEAR(box.X[3 * n + 1], 0.5 + (before.X[3 * n + 0] - 1), 1e-14);
    EXPECT_NEAR(box.X[3 * n + 2], before.X[3 * n + 2], 1e-14);
  }
  spec.rotation_deg = 37;
  spec.rotation_axis = {1, -2, 0.5};
  fdem::transform_mesh(box, spec);
  for (int e = 0; e < box.num_elems(); ++e)
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) {
        const int p = box.elems[4 * e + a], q = box.elems[4 * e + b];
        EXPECT_NEAR(edge(box, p, q), edge(before, p, q), 1e-13);
      }
}

TEST(Ensemble, JitterMovesInteriorNodesWithinItsBounds) {
  for (int dim : {2, 3}) {
    fdem::HostMesh m = dim == 2 ? fdem::generate_crossed_rectangle(0, 0, 1, 1, 8, 8)
                                : fdem::generate_box({0, 0, 0}, {1, 1, 1}, 5, 5, 5);
    const fdem::HostMesh before = m;
    fdem::MeshSpec spec;
    spec.jitter = 0.3;
    spec.jitter_seed = 11;
    const long moved = fdem::transform_mesh(m, spec);
    const fdem::MeshQuality q0 = fdem::mesh_quality(before), q1 = fdem::mesh_quality(m);
    std::set<int> boundary;
    for (const auto& [name, nodes] : before.node_sets)
      if (name != "all") boundary.insert(nodes.begin(), nodes.end());
    long interior = 0, changed = 0;
    for (int n = 0; n < m.num_nodes(); ++n) {
      double shortest = 1e300, d = 0;
      for (int k = 0; k < dim; ++k) d += std::pow(m.X[n * dim + k] - before.X[n * dim + k], 2);
      d = std::sqrt(d);
      if (boundary.count(n)) {
        EXPECT_EQ(d, 0) << "boundary node " << n << " moved, dim " << dim;
        continue;
      }
      ++interior;
      changed += d > 0;
      for (int e = 0; e < m.num_elems(); ++e)
        for (int a = 0; a <= dim; ++a)
          if (m.elems[(dim + 1) * e + a] == n)
            for (int b = 0; b <= dim; ++b)
              if (b != a) shortest = std::min(shortest, edge(before, n, m.elems[(dim + 1) * e + b]));
      EXPECT_LE(d, 0.3 * shortest * (1 + 1e-12));
    }
    EXPECT_EQ(changed, moved);
    EXPECT_GT(moved, 0.5 * interior) << dim;  // most moves are kept
    EXPECT_GE(q1.min_size, 0.7 * q0.min_size * (1 - 1e-12)) << dim;
    EXPECT_LT(q1.min_size, q0.min_size) << dim;
    fdem::HostMesh again = before;
    fdem::transform_mesh(again, spec);
    EXPECT_EQ(again.X, m.X);  // the same seed: the same mesh
    spec.jitter_seed = 12;
    again = before;
    fdem::transform_mesh(again, spec);
    EXPECT_NE(again.X, m.X);
  }
}

const std::string kImpact2d = std::string(FDEM_SOURCE_DIR) + "/cases/particle_impact_2d/case.json";

TEST(Ensemble, VelocityFactorAndRotationKeysOfTheCase) {
  const fdem::Case plain = fdem::load_case(kImpact2d);
  const fdem::Case faster = fdem::load_case(kImpact2d, {"boundary.initial_velocity_factor=1.25"});
  ASSERT_EQ(faster.initial_velocities.size(), 1u);
  EXPECT_DOUBLE_EQ(faster.initial_velocities[0].velocity[1], 1.25 * plain.initial_velocities[0].velocity[1]);
  EXPECT_FALSE(plain.resolved["boundary"].contains("initial_velocity_factor"));  // (the same case hash)
  EXPECT_THROW(fdem::load_case(kImpact2d, {"boundary.initial_velocity_factor=3"}), fdem::InputError);
  const fdem::Case turned = fdem::load_case(kImpact2d, {R"(mesh.rotation={"angle_deg": 30})"});
  EXPECT_EQ(turned.mesh.rotation_deg, 30);
  EXPECT_FALSE(turned.mesh.has_rotation_center);
  EXPECT_TRUE(turned.resolved["mesh"].contains("rotation"));
  EXPECT_THROW(fdem::load_case(kImpact2d, {R"(mesh.rotation={"angle_deg": 30, "axis": [0, 0, 1]})"}),
               fdem::InputError);  // (2D: about z only)
  EXPECT_THROW(fdem::load_case(kImpact2d, {R"(mesh.jitter={"amplitude": 0.6})"}), fdem::InputError);
}

TEST(Ensemble, SeedsAndDrawsOfTheRealisations) {
  fdem::EnsembleOptions o;
  o.vary = {"strength", "orientation", "mesh", "velocity"};
  o.seed = 7;
  o.velocity_size = 1e-3;
  std::set<std::uint64_t> seen;
  double sum = 0, sum2 = 0, zsum = 0;
  const long n = 4000;
  for (long i = 0; i < n; ++i) {
    const fdem::Realisation r = fdem::plan_realisation(o, i, 3);
    ASSERT_EQ(r.seeds.size(), 4u);
    ASSERT_EQ(r.sets.size(), 4u);
    for (const auto& [src, s] : r.seeds) seen.insert(s);
    std::map<std::string, double> v(r.values.begin(), r.values.end());
    const double f = v.at("velocity_factor");
    sum += f - 1;
    sum2 += (f - 1) * (f - 1);
    // the rotated z axis of a uniform random rotation has mean zero in each component
    const json rot = json::parse(r.sets[1].substr(r.sets[1].find('=') + 1));
    const double a = rot["angle_deg"].get<double>() * M_PI / 180, uz = rot["axis"][2].get<double>();
    zsum += std::cos(a) + uz * uz * (1 - std::cos(a));  // the z component of R e_z
    EXPECT_EQ(fdem::plan_realisation(o, i, 3).sets, r.sets);  // a pure function of (options, i)
  }
  EXPECT_EQ(seen.size(), 4u * n);  // no two seeds alike
  EXPECT_NEAR(sum / n, 0, 4 * 1e-3 / std::sqrt(n));
  EXPECT_NEAR(std::sqrt(sum2 / n), 1e-3, 0.05e-3);
  EXPECT_NEAR(zsum / n, 0, 4 / std::sqrt(3.0 * n));  // (its standard deviation: 1 / sqrt(3))
  o.seed = 8;
  EXPECT_NE(fdem::plan_realisation(o, 0, 3).sets, fdem::plan_realisation({}, 0, 3).sets);
}

// ---- end to end ----

int run(const std::string& cmd) { return fdem::test::system_status(cmd); }

std::string ensemble_cmd(const std::string& out, const std::string& extra = "", int jobs = 2) {
  return std::string(FDEM_BINARY) + " ensemble " + kImpact2d + " -n 3 --out " + out +
         " --threads 1 --jobs " + std::to_string(jobs) + " --quiet --set parameters.h=0.008 --set parameters.duration=2e-4 " + extra;
}

std::vector<std::map<std::string, std::string>> read_csv(const std::string& path) {
  std::ifstream f(path);
  std::string line, cell;
  std::getline(f, line);
  std::vector<std::string> head;
  std::stringstream hs(line);
  while (std::getline(hs, cell, ',')) head.push_back(cell);
  std::vector<std::map<std::string, std::string>> rows;
  while (std::getline(f, line)) {
    std::stringstream ls(line);
    std::map<std::string, std::string> row;
    for (size_t k = 0; k < head.size() && std::getline(ls, cell, ','); ++k) row[head[k]] = cell;
    rows.push_back(row);
  }
  return rows;
}

TEST(Ensemble, CommandWritesRealisationsTableAndStatistics) {
  const std::string out = fdem::test::scratch_dir("ensemble", "a");
  const std::string vary = "--vary velocity,orientation,mesh";
  ASSERT_EQ(run(ensemble_cmd(out, vary) + " > " + out + ".log 2>&1"), 0) << slurp(out + ".log");
  for (const char* r : {"r0000", "r0001", "r0002"})
    for (const char* f : {"case.json", "summary.json", "history.csv", "realisation.json"})
      EXPECT_TRUE(fs::exists(out + "/" + r + "/" + f)) << r << "/" << f;
  const auto rows = read_csv(out + "/ensemble.csv");
  ASSERT_EQ(rows.size(), 3u);
  const json rep = json::parse(slurp(out + "/ensemble.json"));
  EXPECT_EQ(rep["done"], 3);
  // Each statistic recomputed from the table (t(0.975, 2) = 4.302652730 from tables).
  for (const char* key : {"fragments.largest_fraction", "energy.fracture_J", "interfaces_failed", "steps"}) {
    std::vector<double> x;
    for (const auto& r : rows) x.push_back(std::stod(r.at(key)));
    const double mean = (x[0] + x[1] + x[2]) / 3;
    double ss = 0;
    for (double v : x) ss += (v - mean) * (v - mean);
    const double sd = std::sqrt(ss / 2), se = sd / std::sqrt(3.0);
    const json& s = rep["results"][key];
    EXPECT_NEAR(s["mean"].get<double>(), mean, 1e-12 * std::fabs(mean)) << key;
    EXPECT_NEAR(s["sd"].get<double>(), sd, 1e-9 * sd + 1e-300) << key;
    EXPECT_NEAR(s["ci95"][1].get<double>() - mean, 4.302652730 * se, 1e-8 * se + 1e-300) << key;
    EXPECT_EQ(s["min"].get<double>(), *std::min_element(x.begin(), x.end())) << key;
  }
  // The realisations differ (the sources act), and each row's seeds are those of its record.
  EXPECT_NE(rows[0].at("energy.fracture_J"), rows[1].at("energy.fracture_J"));
  const json rec = json::parse(slurp(out + "/r0001/realisation.json"));
  EXPECT_EQ(std::to_string(rec["seeds"]["mesh"].get<std::uint64_t>()), rows[1].at("seed_mesh"));
  // The mean cumulative mass curve: from 1 (or below) at the largest size to 1 at the smallest.
  const json& d = rep["fragment_mass_distribution"];
  EXPECT_EQ(d["realisations"], 3);
  EXPECT_NEAR(d["mean_mass_fraction"].back().get<double>(), 1.0, 1e-12);

  // The same command: the same ensemble.json, bit for bit.
  const std::string again = fdem::test::scratch_dir("ensemble", "b");
  ASSERT_EQ(run(ensemble_cmd(again, vary) + " > " + again + ".log 2>&1"), 0) << slurp(again + ".log");
  EXPECT_EQ(slurp(again + "/ensemble.json"), slurp(out + "/ensemble.json"));

  // Stopped after its first realisation and started again: the same ensemble.json.
  const std::string stopped = fdem::test::scratch_dir("ensemble", "c");
  const pid_t pid = fork();
  if (pid == 0) {
    execl("/bin/sh", "sh", "-c", ("exec " + ensemble_cmd(stopped, vary, 1)).c_str(), nullptr);
    _exit(127);
  }
  for (int k = 0; k < 600 && !fs::exists(stopped + "/r0000/realisation.json"); ++k)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  kill(pid, SIGTERM);
  int st = 0;
  waitpid(pid, &st, 0);
  EXPECT_TRUE(WIFEXITED(st) && (WEXITSTATUS(st) == 143 || WEXITSTATUS(st) == 0)) << st;
  EXPECT_FALSE(fs::exists(stopped + "/r0002/realisation.json"));
  ASSERT_EQ(run(ensemble_cmd(stopped, vary, 1) + " > " + stopped + ".log 2>&1"), 0)
      << slurp(stopped + ".log");
  EXPECT_EQ(slurp(stopped + "/ensemble.json"), slurp(out + "/ensemble.json"));

  // The folder of another command is refused, and left as it was.
  const std::string before = slurp(out + "/ensemble.json");
  EXPECT_EQ(run(ensemble_cmd(out, "--vary velocity") + " > " + out + ".log2 2>&1"), 2);
  EXPECT_NE(slurp(out + ".log2").find("another command"), std::string::npos) << slurp(out + ".log2");
  EXPECT_EQ(slurp(out + "/ensemble.json"), before);
}

TEST(Ensemble, BadInputIsRefusedAndNothingWritten) {
  const std::string bin = FDEM_BINARY;
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"-n 0", "--realisations"},
      {"-n 2 --vary strength,colour", "unknown source 'colour'"},
      {"-n 2 --vary strength", "needs a strength scatter"},
      {"-n 2 --vary velocity,velocity", "named twice"},
      {"-n 2 --jobs 0", "--jobs"},
      {"-n 2 --velocity-size 0.5", "--velocity-size"},
      {"-n 2 --set parameters.h=-1", "case.json"},
  };
  for (const auto& [args, says] : bad) {
    const std::string out = fdem::test::scratch_dir("ensemble", "bad");
    const std::string cmd = bin + " ensemble " + kImpact2d + " --out " + out + " " + args + " > " + out + ".log 2>&1";
    EXPECT_EQ(run(cmd), 2) << args << ": " << slurp(out + ".log");
    EXPECT_NE(slurp(out + ".log").find(says), std::string::npos) << args << ": " << slurp(out + ".log");
    EXPECT_FALSE(fs::exists(out)) << args;
  }
}

}  // namespace
