// Throughput of the explicit step and of each of its kernels, against the machine's memory
// bandwidth measured in the same binary (issue 7). See perf/README.md for how to run it and
// docs/performance.md for results.
//
//   bench_step [--dims 2,3] [--sizes 1e4,1e5,1e6] [--reps 5] [--min-time 0.25]
//              [--triad-doubles 3.2e7] [--skips SIZE | --no-skips] [--no-kernels]
//              [--json FILE] [--csv FILE]
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
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <functional>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "mesh/mesh.hpp"
#include "solver/simulation.hpp"
#include "tests/scenes.hpp"

namespace {

using namespace fdem;
using fdem_test::shake;
using Clock = std::chrono::steady_clock;
using nlohmann::json;

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
  std::string json_file, csv_file;
  std::string command;
};

std::vector<double> parse_list(const std::string& s) {
  std::vector<double> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ','))
    if (!item.empty()) out.push_back(std::stod(item));
  return out;
}

[[noreturn]] void usage(const char* msg) {
  std::fprintf(stderr,
               "bench_step: %s\nusage: bench_step [--dims 2,3] [--sizes 1e4,1e5,1e6] [--reps 5] "
               "[--min-time 0.25] [--triad-doubles 3.2e7] [--skips SIZE | --no-skips] [--no-kernels] "
               "[--json FILE] [--csv FILE]\n",
               msg);
  std::exit(2);
}

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 0; i < argc; ++i) o.command += (i ? " " : "") + std::string(argv[i]);
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto val = [&]() -> std::string {
      if (i + 1 >= argc) usage(("missing value after " + a).c_str());
      return argv[++i];
    };
    if (a == "-h" || a == "--help") {
      std::printf("bench_step [--dims 2,3] [--sizes 1e4,1e5,1e6] [--reps 5] [--min-time 0.25] "
                  "[--triad-doubles 3.2e7] [--skips SIZE | --no-skips] [--no-kernels] [--json FILE] [--csv FILE]\n"
                  "  --sizes: target element counts; --skips: element count of the skip scenes (default: the "
                  "smallest size)\n  --no-kernels: the full step only; see the comment at the top of "
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
// timing: every function in turn, `reps` rounds, each call repeated to last `min_time`

struct Stat {
  double median = 0, min = 0, max = 0;  // ns per call
  long calls = 0;                       // per round
};

// after[k] (optional, not timed) runs after each batch of calls of fns[k].
std::vector<Stat> measure(const std::vector<std::function<void()>>& fns, int reps, double min_time,
                          const std::vector<std::function<void()>>& after = {},
                          const std::vector<std::function<void()>>& before = {}) {
  const size_t n = fns.size();
  auto post = [&](size_t k) {
    if (k < after.size() && after[k]) after[k]();
  };
  auto pre = [&](size_t k) {
    if (k < before.size() && before[k]) before[k]();
  };
  std::vector<long> calls(n, 1);
  for (size_t k = 0; k < n; ++k) {  // warm-up and calibration
    pre(k);
    fns[k]();
    Kokkos::fence();
    const auto t0 = Clock::now();
    fns[k]();
    Kokkos::fence();
    const double t = std::chrono::duration<double>(Clock::now() - t0).count();
    post(k);
    calls[k] = std::max<long>(1, std::min<long>(1000000, static_cast<long>(std::ceil(min_time / std::max(t, 1e-9)))));
  }
  std::vector<std::vector<double>> samples(n);
  for (int r = 0; r < reps; ++r)
    for (size_t k = 0; k < n; ++k) {
      pre(k);
      Kokkos::fence();
      const auto t0 = Clock::now();
      for (long c = 0; c < calls[k]; ++c) fns[k]();
      Kokkos::fence();
      samples[k].push_back(std::chrono::duration<double, std::nano>(Clock::now() - t0).count() / calls[k]);
      post(k);
    }
  std::vector<Stat> out(n);
  for (size_t k = 0; k < n; ++k) {
    auto s = samples[k];
    std::sort(s.begin(), s.end());
    const size_t m = s.size();
    out[k].median = m % 2 ? s[m / 2] : 0.5 * (s[m / 2 - 1] + s[m / 2]);
    out[k].min = s.front();
    out[k].max = s.back();
    out[k].calls = calls[k];
  }
  return out;
}

json stat_json(const Stat& s) {
  return {{"ns_median", s.median}, {"ns_min", s.min}, {"ns_max", s.max}, {"calls_per_round", s.calls}};
}

// ---------------------------------------------------------------------------------------------
// machine

std::string cpu_model() {
  std::ifstream f("/proc/cpuinfo");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("model name", 0) == 0) {
      const auto p = line.find(':');
      return p == std::string::npos ? line : line.substr(p + 2);
    }
  return "unknown";
}

std::string env(const char* name) {
  const char* v = std::getenv(name);
  return v ? v : "";
}

std::string utc_now() {
  const std::time_t t = std::time(nullptr);
  char buf[64];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}

int threads() { return ExecSpace().concurrency(); }

// The force scatter duplicates the force array per thread on host backends (Kokkos' default for
// OpenMP), and uses atomics on GPUs.
bool scatter_duplicated() {
#ifdef KOKKOS_ENABLE_OPENMP
  return std::is_same<ExecSpace, Kokkos::OpenMP>::value;
#else
  return false;
#endif
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

// ---------------------------------------------------------------------------------------------
// scenes

template <int D>
HostMesh make_mesh(double target, int& cells) {
  HostMesh m;
  if constexpr (D == 2) {
    cells = std::max(1, static_cast<int>(std::ceil(std::sqrt(target / 4.0) - 1e-9)));
    m = generate_crossed_rectangle(0, 0, 1.0, 1.0, cells, cells, "body");
  } else {
    cells = std::max(1, static_cast<int>(std::ceil(std::cbrt(target / 6.0) - 1e-9)));
    m = generate_box({0, 0, 0}, {1.0, 1.0, 1.0}, cells, cells, cells, "body");
  }
  reorder_for_locality(m);
  insert_interfaces(m, {true});
  return m;
}

struct SceneOptions {
  double damping = 0.7;
  int contact = -1;  // case rule: -1 auto, 0 off, 1 on
  bool fix_face = true;
  double friction = -1;  // contact friction (< 0: derived, tan phi)
  bool contact_step_now = false;  // contact's stable step from the start (the skip forced off)
};

Case make_case(int dim, double h, const SceneOptions& so) {
  Case c;
  c.file = "bench_step";
  c.name = "bench_step";
  c.dim = dim;
  c.materials = {BulkMaterial{"rock", 2700, 30e9, 0.25}};
  c.region_material = {{"body", 0}};
  InterfaceMaterial im;
  im.name = "if";
  im.kn = 30e9 / (0.1 * h);
  im.ks = im.kn / 2.5;
  im.ft = 1e30;  // nothing initiates: every interface takes the undamaged path
  im.c = 1e30;
  im.phi = 0.5;
  im.Gnc = 1e30;
  im.Gsc = 1e30;
  c.interface_materials = {im};
  c.fracturable_regions = {"body"};
  c.fracture_material = 0;
  c.contact.enabled = so.contact;
  c.contact.friction = so.friction;
  if (so.fix_face) {
    VelocityBC fix;
    fix.set = "xmin";
    fix.active = {true, true, true};
    c.velocity_bcs = {fix};
  }
  c.local_damping = so.damping;
  c.end_time = 1;
  return c;
}

template <class V>
double view_bytes(const V& v) {
  return static_cast<double>(v.span()) * sizeof(typename V::value_type);
}

template <int D>
double model_bytes(const Model<D>& m) {
  return view_bytes(m.X) + view_bytes(m.x) + view_bytes(m.v) + view_bytes(m.f) + view_bytes(m.mass) +
         view_bytes(m.node_bc) + view_bytes(m.bcs) + view_bytes(m.fext) + view_bytes(m.elem) +
         view_bytes(m.grad) + view_bytes(m.vol0) + view_bytes(m.emat) + view_bytes(m.mat) +
         view_bytes(m.iface) + view_bytes(m.ihist) + view_bytes(m.iarea) + view_bytes(m.icontact) +
         view_bytes(m.icontact_pending) + view_bytes(m.bnode) + view_bytes(m.barea) +
         view_bytes(m.platen_fs) + view_bytes(m.platen_acc);
}

// Counts the traffic model needs.
struct Counts {
  double nn = 0, ne = 0, ni = 0;
  double nn_elem = 0, nn_iface = 0;  // distinct nodes of the elements, of the interfaces
  double nn_iface_only = 0;          // nodes of interfaces that no element has
  bool fused = false;                // one force pass: elements with their interfaces (Model::ichunk)
  double T = 1;                      // scatter copies (duplicated scatter: one per thread)
  bool dup = false;                  // duplicated scatter (reset and contribute passes)
  bool handover = false, fext = false;
};

template <int D>
Counts counts(const HostMesh& mesh, const Simulation<D>& sim) {
  Counts c;
  c.nn = mesh.num_nodes();
  c.ne = mesh.num_elems();
  c.ni = mesh.num_ifaces();
  std::vector<char> a(mesh.num_nodes(), 0), b(mesh.num_nodes(), 0);
  for (int n : mesh.elems) a[n] = 1;
  for (int n : mesh.ifaces) b[n] = 1;
  for (size_t i = 0; i < a.size(); ++i) {
    c.nn_elem += a[i];
    c.nn_iface += b[i];
    c.nn_iface_only += b[i] && !a[i];
  }
  c.fused = sim.m.ichunk.extent(0) > 0;
  c.dup = scatter_duplicated();
  c.T = c.dup ? threads() : 1;
  c.handover = sim.m.icontact.extent(0) > 0;
  c.fext = sim.m.fext.extent(0) > 0;
  return c;
}

// Compulsory bytes per call of each kernel (the rule at the top of this file).
struct Traffic {
  double bulk = 0, iface = 0, reset = 0, contribute = 0, nodes = 0, nodes_sampled = 0, strain = 0,
         istate = 0;
};

Traffic traffic(const Counts& c, int D) {
  const double vec = 8.0 * D;  // one node vector
  Traffic t;
  t.bulk = c.ne * ((D + 1) * 4.0 + D * D * 8.0 + 8.0 + 4.0) + c.nn_elem * vec * (1 + 2);
  t.iface = c.ni * (2 * D * 4.0 + D * 4 * 8.0 * 2 + 8.0 + (c.handover ? 4.0 : 0.0)) +
            (c.fused ? c.nn_iface_only : c.nn_iface) * vec * (1 + 2);
  if (c.dup) {
    t.reset = c.T * c.nn * vec;
    t.contribute = c.T * c.nn * vec + 2 * c.nn * vec;
  }
  t.nodes = c.nn * (vec * 6 + 8.0 + 4.0 + (c.fext ? vec : 0.0));
  t.nodes_sampled = t.nodes + c.nn * vec;
  t.strain = c.ne * ((D + 1) * 4.0 + D * D * 8.0 + 8.0 + 4.0) + c.nn_elem * vec;
  t.istate = c.ni * (2 * D * 4.0 + D * 4 * 8.0 + 8.0 + (c.handover ? 4.0 : 0.0)) + c.nn_iface * vec;
  return t;
}

struct Row {
  std::string kernel;
  Stat s;
  double bytes = 0;  // per call (0: not modelled)
  bool derived = false;
};

template <int D>
json run_size(double target, const Options& o, double triad_gbps) {
  int cells = 0;
  const auto tm0 = Clock::now();
  const HostMesh mesh = make_mesh<D>(target, cells);
  const double h = 1.0 / cells;
  SceneOptions so;
  Simulation<D> sim(make_case(D, h, so), mesh);
  const double setup_s = std::chrono::duration<double>(Clock::now() - tm0).count();
  shake(sim, 1e-3);
  for (int s = 0; s < 20; ++s) sim.step(s % 10 == 0);
  Kokkos::fence();
  const Counts c = counts(mesh, sim);
  const Traffic tr = traffic(c, D);
  std::printf("\n%dD, %d cells per side: %.0f elements, %.0f nodes, %.0f interfaces (setup %.1f s)\n", D, cells,
              c.ne, c.nn, c.ni, setup_s);
  std::fflush(stdout);

  Model<D>& m = sim.m;
  ForceScatter<D> sf(m.f);
  auto f = m.f;
  ContactSystem<D>* ct = sim.contact();
  std::vector<std::string> names = {"step", "step_sampled"};
  std::vector<std::function<void()>> fns = {[&]() { sim.step(false); }, [&]() { sim.step(true); }};
  if (o.kernels) {
    names.insert(names.end(), {"forces", "scatter_reset", "scatter_contribute", "nodes", "nodes_sampled",
                               "strain_energy", "interface_state"});
    fns.push_back([&]() { compute_forces<D>(m, sf); });
    fns.push_back([&]() { sf.reset(); });
    fns.push_back([&]() { Kokkos::Experimental::contribute(f, sf); });
    fns.push_back([&]() { sim.update_nodes_now(false); });
    fns.push_back([&]() { sim.update_nodes_now(true); });
    fns.push_back([&]() { strain_energy<D>(m); });
    fns.push_back([&]() { interface_state<D>(m); });
    if (ct) {
      names.push_back("contact");
      fns.push_back([&]() { ct->update(m, sim.dt, sim.force_scatter()); });
    }
  }
  // The force kernel and the contribution timed on their own add to m.f: zeroed after them (not
  // timed), so that the state stays the one of a normal run.
  // The node update timed on its own advances positions and velocities with the same forces
  // thousands of times: the nodes would accelerate without bound (in 2D at 3e5 elements the
  // interfaces then opened past their final opening, failed, and the contact search of the
  // flying pieces took the benchmark minutes per call). Positions and velocities are saved
  // before and restored after those calls (not timed).
  std::vector<std::function<void()>> after(fns.size()), before(fns.size());
  Kokkos::View<double* [D]> x0("bench_x0", m.nn), v0("bench_v0", m.nn);
  for (size_t k = 0; k < names.size(); ++k) {
    if (names[k] == "forces" || names[k] == "scatter_contribute") after[k] = [&]() { Kokkos::deep_copy(m.f, 0.0); };
    if (names[k] == "nodes" || names[k] == "nodes_sampled") {
      before[k] = [&]() {
        Kokkos::deep_copy(x0, m.x);
        Kokkos::deep_copy(v0, m.v);
      };
      after[k] = [&]() {
        Kokkos::deep_copy(m.x, x0);
        Kokkos::deep_copy(m.v, v0);
      };
    }
  }
  const std::vector<Stat> st = measure(fns, o.reps, o.min_time, after, before);

  std::vector<Row> rows;
  auto stat_of = [&](const std::string& n) {
    for (size_t k = 0; k < names.size(); ++k)
      if (names[k] == n) return st[k];
    return Stat{};
  };
  const double forces_bytes = tr.bulk + tr.iface + tr.reset + tr.contribute;
  rows.push_back({"step", stat_of("step"), forces_bytes + tr.nodes});
  rows.push_back({"step_sampled", stat_of("step_sampled"), forces_bytes + tr.nodes_sampled + tr.strain + tr.istate});
  if (o.kernels) {
    rows.push_back({"forces", stat_of("forces"), forces_bytes});
    const Stat r = stat_of("scatter_reset"), q = stat_of("scatter_contribute"), F = stat_of("forces");
    Stat fk;
    fk.median = F.median - r.median - q.median;
    fk.min = fk.max = fk.median;
    rows.push_back({"forces_compute", fk, tr.bulk + tr.iface, true});
    rows.push_back({"scatter_reset", r, tr.reset});
    rows.push_back({"scatter_contribute", q, tr.contribute});
    if (ct) rows.push_back({"contact", stat_of("contact"), 0.0});
    rows.push_back({"nodes", stat_of("nodes"), tr.nodes});
    rows.push_back({"nodes_sampled", stat_of("nodes_sampled"), tr.nodes_sampled});
    rows.push_back({"strain_energy", stat_of("strain_energy"), tr.strain});
    rows.push_back({"interface_state", stat_of("interface_state"), tr.istate});
    Stat se;
    se.median = stat_of("step_sampled").median - stat_of("step").median;
    se.min = se.max = se.median;
    rows.push_back({"sampling_extra", se, tr.nodes_sampled - tr.nodes + tr.strain + tr.istate, true});
  }

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
  const double mb = model_bytes(m);
  const double sb = scatter_duplicated() ? c.T * c.nn * D * 8.0 : 0.0;
  j["model_bytes"] = mb;
  j["model_bytes_per_element"] = mb / c.ne;
  j["scatter_copies_bytes"] = sb;
  j["scatter_copies_bytes_per_element"] = sb / c.ne;
  j["kernels"] = json::array();
  std::printf("  memory: %.0f B per element in the model's Views, + %.0f B per element in the scatter copies\n",
              mb / c.ne, sb / c.ne);
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
    j["kernels"].push_back(k);
    char frac[32] = "-";
    if (r.bytes > 0) std::snprintf(frac, sizeof frac, "%.0f %%", 100 * gbps / triad_gbps);
    std::printf("  %-20s %12.0f %12.0f %12.0f %10.2f %10.2f %10.0f %8.2f %8s%s\n", r.kernel.c_str(), r.s.median,
                r.s.min, r.s.max, r.s.median / c.ne, c.ni > 0 ? r.s.median / c.ni : 0.0, r.bytes / c.ne, gbps,
                frac, r.derived ? "  (derived)" : "");
  }
  std::fflush(stdout);
  return j;
}

// ---------------------------------------------------------------------------------------------
// skips: one scene with and without each skip

struct Variant {
  std::string skip, variant, applies;  // applies: "skip", "no skip (forced)", "not applicable"
  std::function<void()> fn;
  double dt = 0;  // the scene's time step
};

template <int D>
json run_skips(double target, const Options& o) {
  int cells = 0;
  const HostMesh mesh = make_mesh<D>(target, cells);
  const double h = 1.0 / cells;
  const double ne = mesh.num_elems();
  std::printf("\nskips, %dD, %.0f elements (full step unless named)\n", D, ne);
  std::vector<std::unique_ptr<Simulation<D>>> sims;
  auto make = [&](SceneOptions so) -> Simulation<D>& {
    sims.push_back(std::make_unique<Simulation<D>>(make_case(D, h, so), mesh));
    Simulation<D>& s = *sims.back();
    if (so.contact_step_now) s.use_contact_step_now();
    shake(s, 1e-3);
    for (int k = 0; k < 5; ++k) s.step(k == 0);
    return s;
  };
  std::vector<Variant> vs;
  {  // contact: nothing can meet (one intact body) -> no search, and the step without contact springs
    SceneOptions on, off, forced;
    off.contact = 0;
    forced.contact_step_now = true;
    Simulation<D>& a = make(off);
    Simulation<D>& b = make(on);
    Simulation<D>& b2 = make(forced);
    vs.push_back({"contact", "contact off", "reference", [&a]() { a.step(false); }, a.dt});
    vs.push_back({"contact", "contact on, nothing can meet", "skip", [&b]() { b.step(false); }, b.dt});
    vs.push_back({"contact", "contact on, nothing can meet, contact step from the start", "no skip (forced)",
                  [&b2]() { b2.step(false); }, b2.dt});
  }
  {  // damping
    SceneOptions z, zfull, d;
    z.damping = zfull.damping = 0.0;
    z.fix_face = zfull.fix_face = d.fix_face = false;
    z.contact = zfull.contact = d.contact = 0;
    Simulation<D>& a = make(z);
    Simulation<D>& b = make(zfull);
    b.skips.damping = false;
    Simulation<D>& c = make(d);
    vs.push_back({"damping", "damping 0", "skip", [&a]() { a.step(false); }, a.dt});
    vs.push_back({"damping", "damping 0, skip off", "no skip (forced)", [&b]() { b.step(false); }, b.dt});
    vs.push_back({"damping", "damping 0.7", "not applicable", [&c]() { c.step(false); }, c.dt});
    vs.push_back({"damping", "node update, damping 0", "skip", [&a]() { a.update_nodes_now(false); }, a.dt});
    vs.push_back({"damping", "node update, damping 0, skip off", "no skip (forced)",
                  [&b]() { b.update_nodes_now(false); }, b.dt});
    vs.push_back({"damping", "node update, damping 0.7", "not applicable", [&c]() { c.update_nodes_now(false); }, c.dt});
  }
  {  // sampling
    SceneOptions so;
    Simulation<D>& a = make(so);
    vs.push_back({"sampling", "unsampled step", "skip", [&a]() { a.step(false); }, a.dt});
    vs.push_back({"sampling", "sampled step", "not applicable", [&a]() { a.step(true); }, a.dt});
  }
  {  // friction: a block cracked into single elements, fragments touching each other
    SceneOptions fz, ff;
    fz.contact = ff.contact = 1;
    fz.friction = 0.0;
    ff.friction = 0.5;
    fz.damping = ff.damping = 0.0;
    fz.fix_face = ff.fix_face = false;
    std::vector<Simulation<D>*> s3;
    for (int k = 0; k < 3; ++k) {
      sims.push_back(std::make_unique<Simulation<D>>(make_case(D, h, k == 2 ? ff : fz), mesh));
      Simulation<D>& s = *sims.back();
      fdem_test::fail_all_interfaces(s);
      shake(s, 1e-2);
      for (int i = 0; i < 5; ++i) s.step(i == 0);
      s3.push_back(&s);
    }
    s3[1]->contact()->skip_frictionless = false;
    Simulation<D>* a = s3[0];
    Simulation<D>* b = s3[1];
    Simulation<D>* c = s3[2];
    // Only the contact update is timed here, on the fixed shaken state: stepping the undamped,
    // fully fragmented block thousands of times (min-time x reps) let it blow up (the corner
    // contacts of issue 4), after which the grid held every node in a few cells and one build
    // took minutes and 15 GB.
    vs.push_back({"friction", "contact update, friction 0", "skip", [a]() { a->contact()->update(a->m, a->dt, a->force_scatter()); }, a->dt});
    vs.push_back({"friction", "contact update, friction 0, skip off", "no skip (forced)",
                  [b]() { b->contact()->update(b->m, b->dt, b->force_scatter()); }, b->dt});
    vs.push_back({"friction", "contact update, friction 0.5", "not applicable",
                  [c]() { c->contact()->update(c->m, c->dt, c->force_scatter()); }, c->dt});
  }
  std::vector<std::function<void()>> fns;
  for (const auto& v : vs) fns.push_back(v.fn);
  const std::vector<Stat> st = measure(fns, o.reps, o.min_time);
  json out = json::array();
  std::printf("  %-10s %-40s %-18s %12s %12s %12s %10s %10s\n", "skip", "scene", "", "median ns", "min ns", "max ns",
              "ns/elem", "dt [s]");
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
    std::printf("  %-10s %-40s %-18s %12.0f %12.0f %12.0f %10.2f %10.3g\n", vs[k].skip.c_str(), vs[k].variant.c_str(),
                vs[k].applies.c_str(), st[k].median, st[k].min, st[k].max, st[k].median / ne, vs[k].dt);
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
  json doc;
  doc["benchmark"] = "bench_step";
  doc["command"] = o.command;
  doc["date_utc"] = utc_now();
  doc["machine"] = {{"cpu_model", cpu_model()},
                    {"hardware_threads", std::thread::hardware_concurrency()},
                    {"OMP_NUM_THREADS", env("OMP_NUM_THREADS")},
                    {"OMP_PROC_BIND", env("OMP_PROC_BIND")},
                    {"OMP_PLACES", env("OMP_PLACES")}};
  doc["backend"] = ExecSpace::name();
  doc["kokkos_version"] = KOKKOS_VERSION;
  doc["threads"] = threads();
  doc["scatter"] = scatter_duplicated() ? "duplicated" : "atomic/none";
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
  if (!o.json_file.empty()) {
    std::ofstream f(o.json_file);
    f << doc.dump(1) << "\n";
  }
  if (!o.csv_file.empty()) write_csv(o.csv_file, doc);
  return 0;
}
