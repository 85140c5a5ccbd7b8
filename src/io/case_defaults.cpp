// The values a case leaves to be derived (docs/case-format.md, "platens" and "contact"), filled
// in one place: by the run once its mesh is ready (so that the case.json it writes shows them)
// and by the Simulation constructor on its own copy (for cases built in code).
#include <cmath>

#include "io/case.hpp"

namespace fdem {

namespace {

// Penalty stiffness of platens and contact when not given: the fracture interface material's kn
// and its ks / kn, else 10 E / mean element size (largest E) and 1 / (2 (1 + nu)) of that material.
struct DerivedStiffness {
  double kn = 0, ks_ratio = 0;
};

template <class MeanSize>
DerivedStiffness derived_stiffness(const Case& c, const MeanSize& mean_size) {
  DerivedStiffness s;
  if (c.fracture_material >= 0) {
    const auto& im = c.interface_materials[c.fracture_material];
    s.kn = im.kn;
    s.ks_ratio = im.ks / im.kn;
    return s;
  }
  double emax = 0, nu = 0.25;
  for (const auto& bm : c.materials)
    if (bm.E > emax) {
      emax = bm.E;
      nu = bm.nu;
    }
  s.kn = 10 * emax / mean_size();
  s.ks_ratio = 1.0 / (2 * (1 + nu));
  return s;
}

bool unset(double v) { return !(v > 0); }

// Writes a derived value into the resolved document at section[key] when that object exists.
void show(nlohmann::json* section, const char* key, double v) {
  if (section && section->is_object()) (*section)[key] = v;
}

nlohmann::json* resolved_section(Case& c, const char* name) {
  if (!c.resolved.is_object() || !c.resolved.contains(name)) return nullptr;
  return &c.resolved[name];
}

}  // namespace

double default_contact_friction(const Case& c) {
  return c.fracture_material >= 0 ? std::tan(c.interface_materials[c.fracture_material].phi) : 0.0;
}

namespace {

// mean_size(): the mean element size (asked for only when a value derives from it)
template <class MeanSize>
void resolve_with(Case& c, const MeanSize& mean_size) {
  bool need = unset(c.contact.kn) || unset(c.contact.ks);
  for (const auto& p : c.platens) need = need || unset(p.kn) || unset(p.ks);
  DerivedStiffness d;
  if (need) d = derived_stiffness(c, mean_size);

  nlohmann::json* pl = resolved_section(c, "platens");
  const bool pl_known = pl && pl->is_array() && pl->size() == c.platens.size();
  for (size_t i = 0; i < c.platens.size(); ++i) {
    PlatenSpec& p = c.platens[i];
    nlohmann::json* doc = pl_known ? &(*pl)[i] : nullptr;
    if (unset(p.kn)) show(doc, "kn", p.kn = d.kn);
    if (unset(p.ks)) show(doc, "ks", p.ks = p.kn * d.ks_ratio);
  }

  ContactSpec& ct = c.contact;
  nlohmann::json* doc = resolved_section(c, "contact");
  if (unset(ct.kn)) show(doc, "kn", ct.kn = d.kn);
  if (unset(ct.ks)) show(doc, "ks", ct.ks = ct.kn * d.ks_ratio);
  if (ct.friction < 0) show(doc, "friction", ct.friction = default_contact_friction(c));
  // skin: 2 % of the mean element size (docs/performance-impact.md, "Skin"): the narrow phase costs
  // in proportion to the candidates, which grow with the search distance dpen + skin, and a
  // rebuild costs about ten narrow-phase passes; the results do not depend on it
  if (unset(ct.skin)) show(doc, "skin", ct.skin = 0.02 * mean_size());
  // zone (runs over several processes): the room nodes have to move before a process could need a
  // face it does not hold (docs/parallel.md "Contact"); more room, more ghosts, fewer cuts. One
  // mean size: on the default 3D impact over 2 processes 6-17 % faster than 3 sizes and half the
  // bytes a step for two more cuts (docs/parallel.md "Rebalancing"); the speed that would fill it
  // within the 25 steps between two checks is far above an impact's (50 v dt = h: v of about
  // 750 m/s at the bulk's dt there, 8.8 km/s at the contact step)
  if (unset(ct.zone)) show(doc, "zone", ct.zone = 1.0 * mean_size());
}

}  // namespace

void resolve_defaults(Case& c, const HostMesh& mesh) {
  resolve_with(c, [&] { return mesh_sizes(mesh).mean_size; });
}

void resolve_defaults(Case& c, double mean_element_size) {
  resolve_with(c, [=] { return mean_element_size; });
}

}  // namespace fdem
