// Throughput of the explicit step and of each of its kernels, against the machine's memory
// bandwidth measured in the same binary (issue 7). See perf/README.md for how to run it and
// docs/performance.md for results.
//
//   bench_step [--dims 2,3] [--sizes 1e4,1e5,1e6] [--reps 5] [--min-time 0.25]
//              [--triad-doubles 3.2e7] [--skips SIZE | --no-skips] [--no-kernels]
//              [--mixed] [--json FILE] [--csv FILE]
//
// Meshes: 2D crossed rectangle (4 triangles per cell), 3D box (6 tetrahedra per cell), the cell
// count chosen so that the element count is at least the requested size; renumbered for locality
// and given interfaces on every internal face, as `fdem run` does.
//
// Throughput scene: rock (E 30 GPa), interfaces with a stiff penalty (E / (0.1 h)) and strengths
// so high that none initiates (every interface takes the undamaged path of the cohesive law, as
// most interfaces of a run do), local damping 0.7, the xmin face fixed (velocity BC), small random
// initial velocities, contact as `fdem run` decides it ("auto": on, but nothing can meet yet), no
// platens (they act on boundary nodes only). After 20 warm-up steps each kernel is timed on its
// own on that state: `reps` rounds, each timing every kernel in turn over enough calls to last
// `min-time` seconds; the median, minimum and maximum of the rounds are reported.
//
// Bytes moved per step: the compulsory traffic. Each array element a pass touches counts once per
// pass (read: once, written: once, read and written: twice), gathered node data once per pass
// (perfect reuse within the pass, which the locality ordering approaches); the force kernel is one
// pass over the nodes where it does each element chunk with its interfaces (Model::ichunk, host
// backends), else the bulk and interface parts are separate passes. The duplicated scatter (OpenMP):
// the reset writes T copies of the force array, each pass read-modify-writes one copy's worth, the
// contribution reads T copies and read-modify-writes the force array. Write-allocate traffic is
// not counted (as in STREAM), so the achieved bandwidth is a lower bound. Triad: a = b + 3 c over
// `triad-doubles` doubles per array, 24 bytes per index (STREAM's rule).
#include <Kokkos_Core.hpp>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "mesh/mesh.hpp"
#include "perf/bench_common.hpp"
#include "perf/bench_step_scene.hpp"
#include "solver/simulation.hpp"
#include "perf/yardstick.hpp"
#include "tests/scenes.hpp"

namespace {

using namespace fdem;
using namespace fdem_bench;
using fdem_test::shake;

// ---------------------------------------------------------------------------------------------
// options

struct Options {
  std::vector<int> dims{2, 3};
  std::vector<double> sizes{1e4, 1e5, 1e6};
  int reps = 5;
  double min_time = 0.25;
  double triad_doubles = 3.2e7;
  double skip_size = -1;  // < 0: the smallest size; 0: no skip scenes
  bool kernels = true;
  bool mixed = false;  // also time the full step with precision "mixed" (step_mixed)
  std::string json_file, csv_file;
  std::string command;
};

[[noreturn]] void usage(const char* msg) {
  std::fprintf(stderr,
               "bench_step: %s\nusage: bench_step [--dims 2,3] [--sizes 1e4,1e5,1e6] [--reps 5] "
               "[--min-time 0.25] [--triad-doubles 3.2e7] [--skips SIZE | --no-skips] [--no-kernels] "
               "[--mixed] [--json FILE] [--csv FILE]\n",
               msg);
  std::exit(2);
}

Options parse(int argc, char** argv) {
  Options o;
  o.command = command_line(argc, argv);
  Args args(argc, argv, [](const std::string& msg) { usage(msg.c_str()); });
  while (args.next()) {
    const std::string& a = args.arg();
    auto val = [&]() { return args.value(); };
    if (a == "-h" || a == "--help") {
      std::printf("bench_step [--dims 2,3] [--sizes 1e4,1e5,1e6] [--reps 5] [--min-time 0.25] "
                  "[--triad-doubles 3.2e7] [--skips SIZE | --no-skips] [--no-kernels] [--mixed] [--json FILE] [--csv FILE]\n"
                  "  --sizes: target element counts; --skips: element count of the skip scenes (default: the "
                  "smallest size)\n  --no-kernels: the full step only; --mixed: also the full step with precision "
                  "\"mixed\" (step_mixed),\n  timed in the same rounds; see the comment at the top of "
                  "perf/bench_step.cpp\n");
      std::exit(0);
    } else if (a == "--dims") {
      o.dims.clear();
      for (double d : parse_list(val())) o.dims.push_back(static_cast<int>(d));
    } else if (a == "--sizes") {
      o.sizes = parse_list(val());
    } else if (a == "--reps") {
      o.reps = std::stoi(val());
    } else if (a == "--min-time") {
      o.min_time = std::stod(val());
    } else if (a == "--triad-doubles") {
      o.triad_doubles = std::stod(val());
    } else if (a == "--skips") {
      o.skip_size = std::stod(val());
    } else if (a == "--no-skips") {
      o.skip_size = 0;
    } else if (a == "--no-kernels") {
      o.kernels = false;
    } else if (a == "--mixed") {
      o.mixed = true;
    } else if (a == "--json") {
      o.json_file = val();
    } else if (a == "--csv") {
      o.csv_file = val();
    } else if (a.rfind("--kokkos", 0) == 0) {
      // Kokkos' own arguments (consumed by the ScopeGuard)
    } else {
      usage(("unknown argument " + a).c_str());
    }
  }
  for (int d : o.dims)
    if (d != 2 && d != 3) usage("--dims takes 2 and/or 3");
  if (o.sizes.empty()) usage("--sizes is empty");
  if (o.reps < 1) usage("--reps must be >= 1");
  std::sort(o.sizes.begin(), o.sizes.end());
  if (o.skip_size < 0) o.skip_size = o.sizes.front();
  return o;
}

// ---------------------------------------------------------------------------------------------
// triad

void triad_once(const Kokkos::View<double*>& a, const Kokkos::View<double*>& b, const Kokkos::View<double*>& c) {
  Kokkos::parallel_for(
      "triad", Kokkos::RangePolicy<ExecSpace>(0, a.extent(0)),
      KOKKOS_LAMBDA(const size_t i) { a(i) = b(i) + 3.0 * c(i); });
}

json triad(double ndoubles, int reps, double min_time) {
  const size_t n = static_cast<size_t>(ndoubles);
  Kokkos::View<double*> a("triad::a", n), b("triad::b", n), c("triad::c", n);
  Kokkos::parallel_for(
      "triad::init", Kokkos::RangePolicy<ExecSpace>(0, n), KOKKOS_LAMBDA(const size_t i) {
        a(i) = 0.0;
        b(i) = 1.0 + 1e-9 * static_cast<double>(i % 1000);
        c(i) = 2.0;
      });
  const std::vector<std::function<void()>> fns = {[=]() { triad_once(a, b, c); }};
  const Stat s = measure(fns, std::max(reps, 5), min_time)[0];
  const double bytes = 24.0 * static_cast<double>(n);
  json j = stat_json(s);
  j["doubles_per_array"] = n;
  j["bytes_per_call"] = bytes;
  j["GBps_median"] = bytes / s.median;
  j["GBps_best"] = bytes / s.min;
  j["GBps_worst"] = bytes / s.max;
  return j;
}

struct Row {
  std::string kernel;
  Stat s;
  double bytes = 0;  // per call (0: not modelled)
  bool derived = false;
};

// The functions timed on the throughput scene: the full step (unsampled, sampled) and, with
// o.kernels, each kernel on its own; before/after (not timed) keep the state the one of a run.
template <int D>
struct KernelSet {
  std::vector<std::string> names;
  std::vector<std::function<void()>> fns, before, after;
  ForceScatter<D> sf;
  Kokkos::View<double* [D]> x0, v0;
  Yardstick<D> ys;

  KernelSet(Simulation<D>& sim, bool kernels, bool mixed)
      : sf(sim.m.f), x0("bench_x0", sim.m.nn), v0("bench_v0", sim.m.nn), ys(sim.m, sim.dt) {
    Simulation<D>* s = &sim;
    Model<D>* m = &sim.m;
    ContactSystem<D>* ct = sim.contact();
    Yardstick<D>* y = &ys;
    // the yardstick (perf/yardstick.hpp) is timed interleaved with the full step, in every round
    names = {"step", "step_sampled", "yardstick"};
    fns = {[s]() { s->step(false); }, [s]() { s->step(true); }, [y]() { y->step(); }};
    if (mixed) {  // the full step with precision "mixed" (Model::mixed_precision), interleaved
      names.push_back("step_mixed");
      fns.push_back([s]() {
        s->m.mixed_precision = true;
        s->step(false);
        s->m.mixed_precision = false;
      });
    }
    if (kernels) {
      names.insert(names.end(), {"forces", "forces_one_at_a_time", "forces_mixed", "scatter_reset",
                                 "scatter_contribute", "nodes",
                                 "nodes_sampled", "strain_energy", "interface_state"});
      fns.push_back([this, m]() { compute_forces<D>(*m, sf); });
      // the host's fused pass without its lanes (FusedForceKernel::lanes): their gain, timed
      // interleaved with the pass that has them
      fns.push_back([this, m]() { compute_forces<D>(*m, sf, true, false); });
      // the mixed precision's pass (case key precision = "mixed"), timed interleaved
      fns.push_back([this, m]() {
        const bool was = m->mixed_precision;
        m->mixed_precision = true;
        compute_forces<D>(*m, sf);
        m->mixed_precision = was;
      });
      fns.push_back([this]() { sf.reset(); });
      fns.push_back([this, m]() { fdem::contribute_forces<D>(m->f, sf); });
      fns.push_back([s]() { s->update_nodes_now(false); });
      fns.push_back([s]() { s->update_nodes_now(true); });
      fns.push_back([m]() { strain_energy<D>(*m); });
      fns.push_back([m]() { interface_state<D>(*m); });
      if (ct) {
        names.push_back("contact");
        fns.push_back([ct, s]() { ct->update(s->m, s->dt, s->force_scatter()); });
      }
    }
    // The force kernel and the contribution timed on their own add to m.f: zeroed after them (not
    // timed), so that the state stays the one of a normal run.
    // The node update timed on its own advances positions and velocities with the same forces
    // thousands of times: the nodes would accelerate without bound (in 2D at 3e5 elements the
    // interfaces then opened past their final opening, failed, and the contact search of the
    // flying pieces took the benchmark minutes per call). Positions and velocities are saved
    // before and restored after those calls (not timed).
    before.resize(fns.size());
    after.resize(fns.size());
    for (size_t k = 0; k < names.size(); ++k) {
      if (names[k] == "forces" || names[k] == "forces_one_at_a_time" || names[k] == "forces_mixed" ||
          names[k] == "scatter_contribute")
        after[k] = [m]() { Kokkos::deep_copy(m->f, 0.0); };
      if (names[k] == "nodes" || names[k] == "nodes_sampled") {
        before[k] = [this, m]() {
          Kokkos::deep_copy(x0, m->x);
          Kokkos::deep_copy(v0, m->v);
        };
        after[k] = [this, m]() {
          Kokkos::deep_copy(m->x, x0);
          Kokkos::deep_copy(m->v, v0);
        };
      }
    }
  }
  KernelSet(const KernelSet&) = delete;
  KernelSet& operator=(const KernelSet&) = delete;
};

// The table's rows from the timings: bytes from the traffic model, and the derived rows (the force
// computation without its scatter, the extra cost of sampling).
std::vector<Row> make_rows(const std::vector<std::string>& names, const std::vector<Stat>& st,
                           const Traffic& tr, double yardstick_bytes, bool kernels, bool contact) {
  std::vector<Row> rows;
  auto stat_of = [&](const std::string& n) {
    for (size_t k = 0; k < names.size(); ++k)
      if (names[k] == n) return st[k];
    return Stat{};
  };
  const double forces_bytes = tr.bulk + tr.iface + tr.reset + tr.contribute;
  rows.push_back({"step", stat_of("step"), forces_bytes + tr.nodes});
  rows.push_back({"step_sampled", stat_of("step_sampled"), forces_bytes + tr.nodes_sampled + tr.strain + tr.istate});
  rows.push_back({"yardstick", stat_of("yardstick"), yardstick_bytes});
  if (std::find(names.begin(), names.end(), "step_mixed") != names.end())
    rows.push_back({"step_mixed", stat_of("step_mixed"), forces_bytes + tr.nodes});
  if (!kernels) return rows;
  rows.push_back({"forces", stat_of("forces"), forces_bytes});
  const Stat r = stat_of("scatter_reset"), q = stat_of("scatter_contribute"), F = stat_of("forces");
  Stat fk;
  fk.median = F.median - r.median - q.median;
  fk.min = fk.max = fk.median;
  rows.push_back({"forces_compute", fk, tr.bulk + tr.iface, true});
  rows.push_back({"forces_one_at_a_time", stat_of("forces_one_at_a_time"), forces_bytes});
  rows.push_back({"forces_mixed", stat_of("forces_mixed"), forces_bytes});
  rows.push_back({"scatter_reset", r, tr.reset});
  rows.push_back({"scatter_contribute", q, tr.contribute});
  if (contact) rows.push_back({"contact", stat_of("contact"), 0.0});
  rows.push_back({"nodes", stat_of("nodes"), tr.nodes});
  rows.push_back({"nodes_sampled", stat_of("nodes_sampled"), tr.nodes_sampled});
  rows.push_back({"strain_energy", stat_of("strain_energy"), tr.strain});
  rows.push_back({"interface_state", stat_of("interface_state"), tr.istate});
  Stat se;
  se.median = stat_of("step_sampled").median - stat_of("step").median;
  se.min = se.max = se.median;
  rows.push_back({"sampling_extra", se, tr.nodes_sampled - tr.nodes + tr.strain + tr.istate, true});
  return rows;
}

// Prints the kernel table and returns its JSON records.
json report_rows(const std::vector<Row>& rows, const Counts& c, double triad_gbps) {
  json out = json::array();
  std::printf("  %-20s %12s %12s %12s %10s %10s %10s %8s %8s\n", "kernel", "median ns", "min ns", "max ns",
              "ns/elem", "ns/iface", "B/elem", "GB/s", "triad");
  for (const Row& r : rows) {
    json k = stat_json(r.s);
    k["name"] = r.kernel;
    k["derived"] = r.derived;
    k["ns_per_element_step"] = r.s.median / c.ne;
    k["ns_per_interface_step"] = c.ni > 0 ? r.s.median / c.ni : 0.0;
    k["ns_per_element_step_min"] = r.s.min / c.ne;
    k["ns_per_element_step_max"] = r.s.max / c.ne;
    k["bytes"] = r.bytes;
    k["bytes_per_element"] = r.bytes / c.ne;
    const double gbps = r.bytes > 0 && r.s.median > 0 ? r.bytes / r.s.median : 0.0;
    k["GBps"] = gbps;
    k["fraction_of_triad"] = triad_gbps > 0 ? gbps / triad_gbps : 0.0;
    out.push_back(k);
    char frac[32] = "-";
    if (r.bytes > 0) std::snprintf(frac, sizeof frac, "%.0f %%", 100 * gbps / triad_gbps);
    std::printf("  %-20s %12.0f %12.0f %12.0f %10.2f %10.2f %10.0f %8.2f %8s%s\n", r.kernel.c_str(),
                r.s.median, r.s.min, r.s.max, r.s.median / c.ne, c.ni > 0 ? r.s.median / c.ni : 0.0,
                r.bytes / c.ne, gbps, frac, r.derived ? "  (derived)" : "");
  }
  std::fflush(stdout);
  return out;
}

template <int D>
json run_size(double target, const Options& o, double triad_gbps) {
  int cells = 0;
  const auto tm0 = Clock::now();
  const HostMesh mesh = make_mesh<D>(target, cells);
  const double h = 1.0 / cells;
  SceneOptions so;
  Simulation<D> sim(make_case(D, h, so), mesh);
  const double setup_s = seconds_since(tm0);
  shake(sim, 1e-3);
  for (int s = 0; s < 20; ++s) sim.step(s % 10 == 0);
  Kokkos::fence();
  const Counts c = counts(mesh, sim);
  const Traffic tr = traffic(c, D);
  std::printf("\n%dD, %d cells per side: %.0f elements, %.0f nodes, %.0f interfaces (setup %.1f s)\n", D,
              cells, c.ne, c.nn, c.ni, setup_s);
  std::fflush(stdout);

  ContactSystem<D>* ct = sim.contact();
  KernelSet<D> ks(sim, o.kernels, o.mixed);
  const std::vector<Stat> st = measure(ks.fns, o.reps, o.min_time, ks.after, ks.before);
  const std::vector<Row> rows = make_rows(ks.names, st, tr, ks.ys.bytes(static_cast<int>(c.T)), o.kernels,
                                          ct != nullptr);

  json j;
  j["dim"] = D;
  j["target_elements"] = target;
  j["cells_per_side"] = cells;
  j["elements"] = c.ne;
  j["nodes"] = c.nn;
  j["interfaces"] = c.ni;
  j["nodes_of_elements"] = c.nn_elem;
  j["nodes_of_interfaces"] = c.nn_iface;
  j["contact"] = ct != nullptr;
  j["contact_may_meet"] = ct ? ct->may_meet() : false;
  j["setup_seconds"] = setup_s;
  const double mb = model_bytes(sim.m);
  const double sb = fdem::kHostScatter ? c.T * c.nn * D * 8.0 : 0.0;
  j["model_bytes"] = mb;
  j["model_bytes_per_element"] = mb / c.ne;
  j["scatter_copies_bytes"] = sb;
  j["scatter_copies_bytes_per_element"] = sb / c.ne;
  std::printf("  memory: %.0f B per element in the model's Views, + %.0f B per element in the scatter copies\n",
              mb / c.ne, sb / c.ne);
  j["kernels"] = report_rows(rows, c, triad_gbps);
  // the full step as a multiple of the yardstick, both timed in the same rounds
  const double ys_ns = rows[2].s.median;
  j["step_over_yardstick"] = ys_ns > 0 ? rows[0].s.median / ys_ns : 0.0;
  j["step_sampled_over_yardstick"] = ys_ns > 0 ? rows[1].s.median / ys_ns : 0.0;
  std::printf("  full step / yardstick: %.2f (sampled step: %.2f)\n", j["step_over_yardstick"].get<double>(),
              j["step_sampled_over_yardstick"].get<double>());
  if (rows.size() > 3 && rows[3].kernel == "step_mixed") {
    j["step_mixed_over_yardstick"] = ys_ns > 0 ? rows[3].s.median / ys_ns : 0.0;
    std::printf("  full step with precision \"mixed\" / yardstick: %.2f\n",
                j["step_mixed_over_yardstick"].get<double>());
  }
  std::fflush(stdout);
  return j;
}

// ---------------------------------------------------------------------------------------------
// skips: one scene with and without each skip

template <int D>
json run_skips(double target, const Options& o) {
  int cells = 0;
  const HostMesh mesh = make_mesh<D>(target, cells);
  const double ne = mesh.num_elems();
  std::printf("\nskips, %dD, %.0f elements (full step unless named)\n", D, ne);
  SkipScenes<D> sc{mesh, 1.0 / cells, {}};
  std::vector<Variant> vs;
  contact_variants(sc, vs);
  damping_variants(sc, vs);
  sampling_variants(sc, vs);
  friction_variants(sc, vs);
  iface_table_variants(sc, vs);
  std::vector<std::function<void()>> fns;
  for (const auto& v : vs) fns.push_back(v.fn);
  const std::vector<Stat> st = measure(fns, o.reps, o.min_time);
  json out = json::array();
  std::printf("  %-10s %-40s %-18s %12s %12s %12s %10s %10s\n", "skip", "scene", "", "median ns", "min ns",
              "max ns", "ns/elem", "dt [s]");
  for (size_t k = 0; k < vs.size(); ++k) {
    json j = stat_json(st[k]);
    j["dim"] = D;
    j["elements"] = ne;
    j["skip"] = vs[k].skip;
    j["variant"] = vs[k].variant;
    j["applies"] = vs[k].applies;
    j["ns_per_element_step"] = st[k].median / ne;
    j["dt_s"] = vs[k].dt;
    out.push_back(j);
    std::printf("  %-10s %-40s %-18s %12.0f %12.0f %12.0f %10.2f %10.3g\n", vs[k].skip.c_str(),
                vs[k].variant.c_str(), vs[k].applies.c_str(), st[k].median, st[k].min, st[k].max,
                st[k].median / ne, vs[k].dt);
  }
  std::fflush(stdout);
  return out;
}

void write_csv(const std::string& file, const json& doc) {
  std::ofstream f(file);
  f << "section,dim,elements,interfaces,kernel,ns_median,ns_min,ns_max,ns_per_element_step,"
       "ns_per_interface_step,bytes_per_element,GBps,fraction_of_triad,threads\n";
  const int T = doc["threads"].get<int>();
  for (const auto& r : doc["runs"])
    for (const auto& k : r["kernels"])
      f << "throughput," << r["dim"].get<int>() << "," << r["elements"].get<double>() << ","
        << r["interfaces"].get<double>() << "," << k["name"].get<std::string>() << ","
        << k["ns_median"].get<double>() << "," << k["ns_min"].get<double>() << "," << k["ns_max"].get<double>()
        << "," << k["ns_per_element_step"].get<double>() << "," << k["ns_per_interface_step"].get<double>() << ","
        << k["bytes_per_element"].get<double>() << "," << k["GBps"].get<double>() << ","
        << k["fraction_of_triad"].get<double>() << "," << T << "\n";
  for (const auto& s : doc["skips"])
    f << "skip," << s["dim"].get<int>() << "," << s["elements"].get<double>() << ",,\""
      << s["skip"].get<std::string>() << ": " << s["variant"].get<std::string>() << " ["
      << s["applies"].get<std::string>() << "]\"," << s["ns_median"].get<double>() << ","
      << s["ns_min"].get<double>() << "," << s["ns_max"].get<double>() << ","
      << s["ns_per_element_step"].get<double>() << ",,,,," << T << "\n";
}

}  // namespace

int main(int argc, char** argv) {
  Kokkos::ScopeGuard guard(argc, argv);
  const Options o = parse(argc, argv);
  json doc = record_header("bench_step", o.command);
  doc["machine"]["hardware_threads"] = std::thread::hardware_concurrency();
  doc["machine"]["OMP_NUM_THREADS"] = env("OMP_NUM_THREADS");
  doc["machine"]["OMP_PROC_BIND"] = env("OMP_PROC_BIND");
  doc["machine"]["OMP_PLACES"] = env("OMP_PLACES");
  doc["kokkos_version"] = KOKKOS_VERSION;
  doc["scatter"] = fdem::kHostScatter ? "a copy per thread but the first" : "atomic";
  doc["reps"] = o.reps;
  doc["min_time_s"] = o.min_time;
  std::printf("bench_step: %s backend, %d threads, Kokkos %d, %s\n", ExecSpace::name(), threads(), KOKKOS_VERSION,
              cpu_model().c_str());
  std::printf("triad a = b + 3 c, %.3g doubles per array ... ", o.triad_doubles);
  std::fflush(stdout);
  doc["triad"] = triad(o.triad_doubles, o.reps, o.min_time);
  const double tg = doc["triad"]["GBps_median"].get<double>();
  std::printf("%.1f GB/s median (best %.1f, worst %.1f)\n", tg, doc["triad"]["GBps_best"].get<double>(),
              doc["triad"]["GBps_worst"].get<double>());
  doc["runs"] = json::array();
  for (int d : o.dims)
    for (double s : o.sizes) doc["runs"].push_back(d == 2 ? run_size<2>(s, o, tg) : run_size<3>(s, o, tg));
  doc["skips"] = json::array();
  if (o.skip_size > 0)
    for (int d : o.dims) {
      const json s = d == 2 ? run_skips<2>(o.skip_size, o) : run_skips<3>(o.skip_size, o);
      for (const auto& r : s) doc["skips"].push_back(r);
    }
  write_json(o.json_file, doc);
  if (!o.csv_file.empty()) write_csv(o.csv_file, doc);
  return 0;
}
