// Case schema, second part: boundary conditions, platens, contact, damping, time and output.
#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "io/case_internal.hpp"

namespace fdem::case_detail {
namespace {

// "boundary.fixed": [{"set", "components"}], velocity 0.
void read_fixed(json& b, Case& c, const Reader& R) {
  const int d = c.dim;
  const std::string P = "boundary";
  json& fixed = R.array(b, P, "fixed", false);
  for (size_t i = 0; i < fixed.size(); ++i) {
    const std::string p = child(child(P, "fixed"), i);
    R.keys(fixed[i], p, {"set", "components"});
    VelocityBC bc;
    bc.set = R.name(fixed[i], p, "set");
    bc.active = R.components(fixed[i], p, d);
    c.velocity_bcs.push_back(bc);
  }
}

// "boundary.velocity": [{"set", "velocity", "components", "ramp_time"}].
void read_velocity(json& b, Case& c, const Reader& R) {
  const int d = c.dim;
  const std::string P = "boundary";
  json& vel = R.array(b, P, "velocity", false);
  for (size_t i = 0; i < vel.size(); ++i) {
    const std::string p = child(child(P, "velocity"), i);
    R.keys(vel[i], p, {"set", "velocity", "components", "ramp_time"});
    VelocityBC bc;
    bc.set = R.name(vel[i], p, "set");
    bc.velocity = R.vec(vel[i], p, "velocity", d);
    bc.active = R.components(vel[i], p, d);
    for (int k = 0; k < d; ++k)
      if (!bc.active[k] && bc.velocity[k] != 0.0)
        R.fail(child(child(p, "velocity"), static_cast<size_t>(k)),
               "component " + std::string(1, "xyz"[k]) + " is " + fmt_num(bc.velocity[k]) +
                   " but is not in components '" + vel[i]["components"].get<std::string>() +
                   "' (allowed: 0, or add it to components)");
    bc.ramp_time = R.number(vel[i], p, "ramp_time", ge(0), 0.0);
    c.velocity_bcs.push_back(bc);
  }
}

// "boundary.point_loads": [{"set", "force", "ramp_time"}].
void read_point_loads(json& b, Case& c, const Reader& R) {
  const int d = c.dim;
  const std::string P = "boundary";
  json& loads = R.array(b, P, "point_loads", false);
  std::set<double> ramps;
  for (size_t i = 0; i < loads.size(); ++i) {
    const std::string p = child(child(P, "point_loads"), i);
    R.keys(loads[i], p, {"set", "force", "ramp_time"});
    PointLoad pl;
    pl.set = R.name(loads[i], p, "set");
    pl.force = R.vec(loads[i], p, "force", d);
    pl.ramp_time = R.number(loads[i], p, "ramp_time", ge(0), 0.0);
    ramps.insert(pl.ramp_time);
    if (ramps.size() - ramps.count(0.0) > static_cast<size_t>(kMaxLoadRamps))
      R.fail(child(p, "ramp_time"), "more than " + std::to_string(kMaxLoadRamps) +
                                        " different ramp times among the point loads (allowed: at most " +
                                        std::to_string(kMaxLoadRamps) + " distinct values > 0)");
    c.point_loads.push_back(pl);
  }
}

// "boundary.initial_velocity": [{"region" (default "all"), "velocity"}].
void read_initial_velocity(json& b, Case& c, const Reader& R) {
  const int d = c.dim;
  const std::string P = "boundary";
  json& iv = R.array(b, P, "initial_velocity", false);
  std::vector<std::string> known;
  for (const auto& kv : c.region_material) known.push_back(kv.first);
  for (size_t i = 0; i < iv.size(); ++i) {
    const std::string p = child(child(P, "initial_velocity"), i);
    R.keys(iv[i], p, {"region", "velocity"});
    InitialVelocity v;
    v.region = R.name(iv[i], p, "region", std::string("all"));
    if (v.region != "all" && !c.region_material.count(v.region))
      R.fail(child(p, "region"), "region '" + v.region + "' has no material in 'regions'" +
                                     did_you_mean(v.region, known) + " (allowed: 'all', " +
                                     quoted_list(known) + ")");
    v.velocity = R.vec(iv[i], p, "velocity", d);
    c.initial_velocities.push_back(v);
  }
  // "boundary.initial_velocity_factor": every initial velocity times this factor (an ensemble's
  // velocity perturbation, src/solver/ensemble.cpp); not written when absent (the same case hash).
  if (b.contains("initial_velocity_factor")) {
    const double f = R.number(b, P, "initial_velocity_factor", between(0.5, false, 2, false));
    for (auto& v : c.initial_velocities)
      for (double& x : v.velocity) x *= f;
  }
}

// The first rule of "fracture" that gives interfaces a frictional joint material (ft = c = 0), as
// {key path, material index}; {"", -1} when none does. fracture.interface_material counts where an
// interface may take it: a fracturable region without a region_materials rule, or a fracturable
// region and another region without a pair_materials rule (the mesh decides whether they touch).
std::pair<std::string, int> frictional_rule(const Case& c) {
  auto frictional = [&c](int m) { return m >= 0 && c.interface_materials[m].frictional(); };
  auto fracturable = [&c](const std::string& r) {
    return std::find(c.fracturable_regions.begin(), c.fracturable_regions.end(), r) !=
           c.fracturable_regions.end();
  };
  if (frictional(c.fracture_material)) {
    bool default_used = false;
    for (const std::string& r : c.fracturable_regions) {
      default_used = default_used || !c.region_iface_material.count(r);
      for (const auto& kv : c.region_material)
        if (kv.first != r)
          default_used = default_used || !c.pair_iface_material.count(std::minmax(r, kv.first));
    }
    if (default_used) return {"fracture.interface_material", c.fracture_material};
  }
  for (const auto& [r, m] : c.region_iface_material)
    if (fracturable(r) && frictional(m)) return {child("fracture.region_materials", r), m};
  for (const auto& [rs, m] : c.pair_iface_material)
    if ((fracturable(rs.first) || fracturable(rs.second)) && frictional(m))
      return {"fracture.pair_materials (regions '" + rs.first + "', '" + rs.second + "')", m};
  for (const auto& [surface, m] : c.surface_iface_material)
    if (frictional(m)) return {child("fracture.surfaces", surface), m};
  return {"", -1};
}

// With contact switched off a frictional joint carries nothing (its interfaces start failed and
// handed over to contact): the bodies on either side would pass through each other.
void check_frictional_joints_have_contact(const Case& c, const Reader& R) {
  if (c.contact.enabled != 0) return;
  const auto [rule, m] = frictional_rule(c);
  if (m < 0) return;
  const std::string& name = c.interface_materials[m].name;
  R.fail("contact.enabled",
         "is false, but interface material '" + name + "' (" + rule +
             ") is a frictional joint (ft = 0 and c = 0): its interfaces start failed and only contact "
             "carries them, so without contact they carry nothing and the bodies on either side pass "
             "through each other; switch contact on (\"enabled\": true or \"auto\") or give " +
             child("interface_materials", name) + " a tensile strength ft > 0 or a cohesion c > 0");
}

}  // namespace

void read_boundary(json& doc, Case& c, const Reader& R) {
  const int d = c.dim;
  json& b = R.object(doc, "", "boundary", false);
  const std::string P = "boundary";
  R.keys(b, P, {"fixed", "velocity", "point_loads", "gravity", "initial_velocity", "initial_velocity_factor"});
  read_fixed(b, c, R);
  read_velocity(b, c, R);
  read_point_loads(b, c, R);
  c.gravity = R.vec(b, P, "gravity", d, Vec3{0, 0, 0});
  read_initial_velocity(b, c, R);
}

void read_platens(json& doc, Case& c, const Reader& R) {
  const int d = c.dim;
  json& pl = R.array(doc, "", "platens", false);
  for (size_t i = 0; i < pl.size(); ++i) {
    const std::string p = child("platens", i);
    R.keys(pl[i], p, {"name", "point", "normal", "velocity", "change", "kn", "ks", "friction", "cohesion",
                        "mass"});
    PlatenSpec s;
    s.name = R.name(pl[i], p, "name");
    for (const auto& o : c.platens)
      if (o.name == s.name) R.fail(child(p, "name"), "platen name '" + s.name + "' is used twice");
    s.point = R.vec(pl[i], p, "point", d);
    Vec3 n = R.vec(pl[i], p, "normal", d);
    double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 0))
      R.fail(child(p, "normal"), "the normal is zero (allowed: any non-zero vector; it is normalised)");
    for (auto& x : n) x /= len;
    s.normal = n;
    s.velocity = R.vec(pl[i], p, "velocity", d, Vec3{0, 0, 0});
    if (pl[i].contains("change")) {  // one change of velocity (e.g. fast approach, slow loading)
      json& ch = R.object(pl[i], p, "change", false);
      const std::string cp = child(p, "change");
      R.keys(ch, cp, {"time", "velocity"});
      s.has_change = true;
      s.change_time = R.number(ch, cp, "time", ge(0));
      s.change_velocity = R.vec(ch, cp, "velocity", d);
    }
    s.kn = R.number(pl[i], p, "kn", ge(0), 0.0);
    s.ks = R.number(pl[i], p, "ks", ge(0), 0.0);
    s.friction = R.number(pl[i], p, "friction", ge(0), 0.0);
    s.cohesion = R.number(pl[i], p, "cohesion", ge(0), 0.0);
    s.mass = R.number(pl[i], p, "mass", ge(0), 0.0);
    if (s.mass > 0 && s.has_change)
      R.fail(child(p, "change"), "a platen with a mass moves as its mass and the forces on it decide: "
                                 "'change' is for a platen without one (allowed: one of 'mass', 'change')");
    c.platens.push_back(s);
  }
}

void read_contact(json& doc, Case& c, const Reader& R) {
  json& ct = R.object(doc, "", "contact", false);
  const std::string P = "contact";
  R.keys(ct, P, {"enabled", "kn", "ks", "friction", "cohesion", "skin", "zone"});
  auto it = ct.find("enabled");
  if (it == ct.end()) {
    ct["enabled"] = "auto";
    c.contact.enabled = -1;
  } else if (it->is_boolean()) {
    c.contact.enabled = it->get<bool>() ? 1 : 0;
  } else if (it->is_string() && it->get<std::string>() == "auto") {
    c.contact.enabled = -1;
  } else {
    R.fail(child(P, "enabled"), "expected true, false or \"auto\", got " + describe(*it));
  }
  c.contact.kn = R.number(ct, P, "kn", ge(0), 0.0);
  c.contact.ks = R.number(ct, P, "ks", ge(0), 0.0);
  c.contact.friction = R.number(ct, P, "friction", ge(0), default_contact_friction(c));
  c.contact.cohesion = R.number(ct, P, "cohesion", ge(0), 0.0);
  c.contact.skin = R.number(ct, P, "skin", ge(0), 0.0);
  c.contact.zone = R.number(ct, P, "zone", ge(0), 0.0);
  check_frictional_joints_have_contact(c, R);
}

// "parallel": what a run over several processes does beyond what one process does
// (docs/parallel.md, "Rebalancing"); a run on one process reads it and does nothing with it.
void read_parallel(json& doc, Case& c, const Reader& R) {
  json& par = R.object(doc, "", "parallel", false);
  R.keys(par, "parallel", {"rebalance_above", "work_model"});
  c.rebalance_above = R.number(par, "parallel", "rebalance_above", between(0.01, false, 1000, false), 0.2);
  // ns a step per item (docs/parallel.md "Rebalancing": how to measure them)
  if (par.contains("work_model")) {
    json& wm = R.object(par, "parallel", "work_model", false);
    const std::string P = "parallel.work_model";
    R.keys(wm, P, {"element_ns", "interface_ns", "node_ns", "contact_unit_ns"});
    WorkModel& w = c.work_model;
    w.element = R.number(wm, P, "element_ns", between(0, true, 100000, false), w.element);
    w.interface = R.number(wm, P, "interface_ns", between(0, true, 100000, false), w.interface);
    w.node = R.number(wm, P, "node_ns", between(0, true, 100000, false), w.node);
    w.contact_unit = R.number(wm, P, "contact_unit_ns", between(0, true, 100000, false), w.contact_unit);
  }
}

void read_damping(json& doc, Case& c, const Reader& R) {
  json& dmp = R.object(doc, "", "damping", false);
  R.keys(dmp, "damping", {"local", "mass_proportional", "change"});
  c.local_damping = R.number(dmp, "damping", "local", between(0, false, 1, true), 0.0);
  c.mass_damping = R.number(dmp, "damping", "mass_proportional", ge(0), 0.0);
  if (dmp.contains("change")) {
    json& ch = R.object(dmp, "damping", "change", false);
    const std::string cp = "damping.change";
    R.keys(ch, cp, {"time", "local", "mass_proportional"});
    c.damping_change_time = R.number(ch, cp, "time", ge(0));
    c.damping_change_local = R.number(ch, cp, "local", between(0, false, 1, true), 0.0);
    c.damping_change_mass = R.number(ch, cp, "mass_proportional", ge(0), 0.0);
  }
}

void read_time(json& doc, Case& c, const Reader& R) {
  json& t = R.object(doc, "", "time", true);
  const std::string P = "time";
  R.keys(t, P, {"safety_factor", "dt", "end_time", "max_steps", "stop", "check_interval"});
  c.safety_factor = R.number(t, P, "safety_factor", between(0, true, 2, false), 0.5);
  c.dt = R.number(t, P, "dt", ge(0), 0.0);
  c.end_time = R.number(t, P, "end_time", gt(0));
  c.max_steps = R.integer(t, P, "max_steps", 0, std::numeric_limits<long>::max(), 0L);
  c.check_interval =
      static_cast<int>(R.integer(t, P, "check_interval", 1, std::numeric_limits<int>::max(), 100L));
  if (t.contains("stop")) {
    json& s = R.object(t, P, "stop", false);
    const std::string sp = "time.stop";
    R.keys(s, sp, {"platen", "drop_fraction"});
    std::string name = R.string(s, sp, "platen");
    std::vector<std::string> names;
    for (const auto& p : c.platens) names.push_back(p.name);
    if (std::find(names.begin(), names.end(), name) == names.end())
      R.fail(child(sp, "platen"), "no platen named '" + name + "'" + did_you_mean(name, names) +
                                      " (platens: " + quoted_list(names, false) + ")");
    c.stop_platen = name;
    c.stop_drop_fraction = R.number(s, sp, "drop_fraction", between(0, true, 1, true));
  }
}

void read_output(json& doc, Case& c, const Reader& R) {
  json& o = R.object(doc, "", "output", false);
  const std::string P = "output";
  R.keys(o, P, {"history_interval", "history_rows", "snapshot_interval", "snapshot_count", "monitors",
                "fragments", "checkpoint_every"});
  if (o.contains("monitors")) {
    json& arr = R.array(o, P, "monitors", false);
    for (size_t i = 0; i < arr.size(); ++i) {
      const std::string p = child(child(P, "monitors"), i);
      const std::string m = R.string_value(arr[i], p);
      const auto first = std::find(c.monitors.begin(), c.monitors.end(), m);
      if (first != c.monitors.end()) {  // its history.csv columns would appear twice
        const size_t j = static_cast<size_t>(first - c.monitors.begin());
        R.fail(p, "monitor '" + m + "' is listed twice (also " + child(child(P, "monitors"), j) +
                      "); each monitor gives its own history.csv columns: list it once");
      }
      c.monitors.push_back(m);
    }
  }
  if (o.contains("history_interval") && o.contains("history_rows"))
    R.fail(P, "give either 'history_interval' or 'history_rows', not both");
  if (o.contains("snapshot_interval") && o.contains("snapshot_count"))
    R.fail(P, "give either 'snapshot_interval' or 'snapshot_count', not both");
  if (o.contains("history_interval")) {
    c.history_interval = R.number(o, P, "history_interval", gt(0));
  } else {
    long rows = R.integer(o, P, "history_rows", 1, 100000000L, 200L);
    c.history_interval = c.end_time / static_cast<double>(rows);
  }
  if (o.contains("snapshot_interval")) {
    c.snapshot_interval = R.number(o, P, "snapshot_interval", ge(0));
  } else {
    long n = R.integer(o, P, "snapshot_count", 0, 1000000L, 0L);
    c.snapshot_interval = n > 0 ? c.end_time / static_cast<double>(n) : 0.0;
  }
  if (o.contains("fragments")) {
    if (!o["fragments"].is_boolean())
      R.fail(child(P, "fragments"), "expected true or false, got " + describe(o["fragments"]));
    c.output_fragments = o["fragments"].get<bool>();
  } else {
    o["fragments"] = true;
  }
  if (o.contains("checkpoint_every")) c.checkpoint_every = R.number(o, P, "checkpoint_every", ge(0));
}


}  // namespace fdem::case_detail
