#pragma once
// The scenes of perf/bench_step.cpp (meshes with interfaces everywhere, the case, the options its
// skip scenes change), its model of the bytes each kernel moves (the rule is at the top of
// perf/bench_step.cpp) and the skip scenes (each skip with and without it).
#include <Kokkos_Core.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "io/case.hpp"
#include "mesh/mesh.hpp"
#include "solver/simulation.hpp"
#include "tests/scenes.hpp"

namespace fdem_bench {

using fdem::Case;
using fdem::ExecSpace;
using fdem::HostMesh;
using fdem::Model;
using fdem::Simulation;

inline int threads() { return ExecSpace().concurrency(); }

// ---------------------------------------------------------------------------------------------
// scenes

template <int D>
HostMesh make_mesh(double target, int& cells) {
  HostMesh m;
  if constexpr (D == 2) {
    cells = std::max(1, static_cast<int>(std::ceil(std::sqrt(target / 4.0) - 1e-9)));
    m = fdem::generate_crossed_rectangle(0, 0, 1.0, 1.0, cells, cells, "body");
  } else {
    cells = std::max(1, static_cast<int>(std::ceil(std::cbrt(target / 6.0) - 1e-9)));
    m = fdem::generate_box({0, 0, 0}, {1.0, 1.0, 1.0}, cells, cells, cells, "body");
  }
  fdem::reorder_for_locality(m);
  fdem::insert_interfaces(m, {true});
  return m;
}

struct SceneOptions {
  double damping = 0.7;
  int contact = -1;  // case rule: -1 auto, 0 off, 1 on
  bool fix_face = true;
  double friction = -1;  // contact friction (< 0: derived, tan phi)
  bool contact_step_now = false;  // contact's stable step from the start (the skip forced off)
  // 1: one interface material (no per-interface table); 2: the same material named again for the
  // region (every interface through the per-interface table); 3: as 2 with a Weibull scatter.
  int iface_table = 1;
};

inline Case make_case(int dim, double h, const SceneOptions& so) {
  Case c;
  c.file = "bench_step";
  c.name = "bench_step";
  c.dim = dim;
  c.materials = {fdem::BulkMaterial{"rock", 2700, 30e9, 0.25}};
  c.region_material = {{"body", 0}};
  const double kn = 30e9 / (0.1 * h);
  // nothing initiates: every interface takes the undamaged path
  c.interface_materials = {fdem_test::strong_interface(kn, kn / 2.5)};
  c.fracturable_regions = {"body"};
  c.fracture_material = 0;
  if (so.iface_table >= 2) {
    c.interface_materials.push_back(c.interface_materials[0]);
    c.interface_materials[1].name = "if_region";
    c.region_iface_material = {{"body", 1}};
  }
  if (so.iface_table >= 3) {
    c.scatter.distribution = "weibull";
    c.scatter.modulus = 5;
  }
  c.contact.enabled = so.contact;
  c.contact.friction = so.friction;
  if (so.fix_face) {
    fdem::VelocityBC fix;
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
  double T = 0;                      // scatter copies (host backends: one per thread but the first)
  bool dup = false;                  // copies to reset and contribute (host backends, 2 threads or more)
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
  c.T = fdem::kHostScatter ? threads() - 1 : 0;  // (kernels/fdem_kokkos.hpp, HostForceScatter)
  c.dup = c.T > 0;
  c.handover = sim.m.icontact.extent(0) > 0;
  c.fext = sim.m.fext.extent(0) > 0;
  return c;
}

// Compulsory bytes per call of each kernel (the rule at the top of perf/bench_step.cpp).
struct Traffic {
  double bulk = 0, iface = 0, reset = 0, contribute = 0, nodes = 0, nodes_sampled = 0, strain = 0,
         istate = 0;
};

inline Traffic traffic(const Counts& c, int D) {
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

// ---------------------------------------------------------------------------------------------
// skip scenes: one scene with and without each skip

struct Variant {
  std::string skip, variant, applies;  // applies: "skip", "no skip (forced)", "not applicable"
  std::function<void()> fn;
  double dt = 0;  // the scene's time step
};

// The scenes of the skip study, all on one mesh; owns its simulations (their addresses are stable:
// the variants keep pointers to them).
template <int D>
struct SkipScenes {
  const HostMesh& mesh;
  double h;
  std::vector<std::unique_ptr<Simulation<D>>> sims;

  // A scene shaken and stepped a few times.
  Simulation<D>& make(const SceneOptions& so) {
    sims.push_back(std::make_unique<Simulation<D>>(make_case(D, h, so), mesh));
    Simulation<D>& s = *sims.back();
    if (so.contact_step_now) s.use_contact_step_now();
    fdem_test::shake(s, 1e-3);
    for (int k = 0; k < 5; ++k) s.step(k == 0);
    return s;
  }
  // A block cracked into single elements, fragments touching each other.
  Simulation<D>& make_cracked(const SceneOptions& so) {
    sims.push_back(std::make_unique<Simulation<D>>(make_case(D, h, so), mesh));
    Simulation<D>& s = *sims.back();
    fdem_test::fail_all_interfaces(s);
    fdem_test::shake(s, 1e-2);
    for (int i = 0; i < 5; ++i) s.step(i == 0);
    return s;
  }
};

// contact: nothing can meet (one intact body) -> no search, and the step without contact springs
template <int D>
void contact_variants(SkipScenes<D>& sc, std::vector<Variant>& vs) {
  SceneOptions on, off, forced;
  off.contact = 0;
  forced.contact_step_now = true;
  Simulation<D>* a = &sc.make(off);
  Simulation<D>* b = &sc.make(on);
  Simulation<D>* b2 = &sc.make(forced);
  vs.push_back({"contact", "contact off", "reference", [a]() { a->step(false); }, a->dt});
  vs.push_back({"contact", "contact on, nothing can meet", "skip", [b]() { b->step(false); }, b->dt});
  vs.push_back({"contact", "contact on, nothing can meet, contact step from the start", "no skip (forced)",
                [b2]() { b2->step(false); }, b2->dt});
}

template <int D>
void damping_variants(SkipScenes<D>& sc, std::vector<Variant>& vs) {
  SceneOptions z, zfull, d;
  z.damping = zfull.damping = 0.0;
  z.fix_face = zfull.fix_face = d.fix_face = false;
  z.contact = zfull.contact = d.contact = 0;
  Simulation<D>* a = &sc.make(z);
  Simulation<D>* b = &sc.make(zfull);
  b->skips.damping = false;
  Simulation<D>* c = &sc.make(d);
  vs.push_back({"damping", "damping 0", "skip", [a]() { a->step(false); }, a->dt});
  vs.push_back({"damping", "damping 0, skip off", "no skip (forced)", [b]() { b->step(false); }, b->dt});
  vs.push_back({"damping", "damping 0.7", "not applicable", [c]() { c->step(false); }, c->dt});
  vs.push_back({"damping", "node update, damping 0", "skip", [a]() { a->update_nodes_now(false); }, a->dt});
  vs.push_back({"damping", "node update, damping 0, skip off", "no skip (forced)",
                [b]() { b->update_nodes_now(false); }, b->dt});
  vs.push_back({"damping", "node update, damping 0.7", "not applicable",
                [c]() { c->update_nodes_now(false); }, c->dt});
}

template <int D>
void sampling_variants(SkipScenes<D>& sc, std::vector<Variant>& vs) {
  SceneOptions so;
  Simulation<D>* a = &sc.make(so);
  vs.push_back({"sampling", "unsampled step", "skip", [a]() { a->step(false); }, a->dt});
  vs.push_back({"sampling", "sampled step", "not applicable", [a]() { a->step(true); }, a->dt});
}

// interface materials: one material reads no per-interface index or table (the one-material
// force kernel); the same material through the table, and with a strength scatter
template <int D>
void iface_table_variants(SkipScenes<D>& sc, std::vector<Variant>& vs) {
  SceneOptions one, table, scatter;
  one.contact = table.contact = scatter.contact = 0;
  table.iface_table = 2;
  scatter.iface_table = 3;
  Simulation<D>* a = &sc.make(one);
  Simulation<D>* b = &sc.make(table);
  Simulation<D>* c = &sc.make(scatter);
  vs.push_back({"iface_table", "one interface material", "skip", [a]() { a->step(false); }, a->dt});
  vs.push_back({"iface_table", "one material through the per-interface table", "no skip (forced)",
                [b]() { b->step(false); }, b->dt});
  vs.push_back({"iface_table", "per-interface table and Weibull scatter", "not applicable",
                [c]() { c->step(false); }, c->dt});
}

// friction: a block cracked into single elements, fragments touching each other
template <int D>
void friction_variants(SkipScenes<D>& sc, std::vector<Variant>& vs) {
  SceneOptions fz, ff;
  fz.contact = ff.contact = 1;
  fz.friction = 0.0;
  ff.friction = 0.5;
  fz.damping = ff.damping = 0.0;
  fz.fix_face = ff.fix_face = false;
  Simulation<D>* a = &sc.make_cracked(fz);
  Simulation<D>* b = &sc.make_cracked(fz);
  Simulation<D>* c = &sc.make_cracked(ff);
  b->contact()->skip_frictionless = false;
  // Only the contact update is timed here, on the fixed shaken state: stepping the undamped,
  // fully fragmented block thousands of times (min-time x reps) let it blow up (the corner
  // contacts of issue 4), after which the grid held every node in a few cells and one build
  // took minutes and 15 GB.
  auto update = [](Simulation<D>* s) {
    return [s]() { s->contact()->update(s->m, s->dt, s->force_scatter()); };
  };
  vs.push_back({"friction", "contact update, friction 0", "skip", update(a), a->dt});
  vs.push_back({"friction", "contact update, friction 0, skip off", "no skip (forced)", update(b), b->dt});
  vs.push_back({"friction", "contact update, friction 0.5", "not applicable", update(c), c->dt});
}

}  // namespace fdem_bench
