#pragma once
// A case: everything a run needs, read from a JSON case file (docs/case-format.md) and validated.
// All quantities in SI units; angles are given in degrees in the file and stored in radians.
#include <array>
#include <map>
#include <utility>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/work_model.hpp"
#include "mesh/mesh.hpp"

namespace fdem {

using Vec3 = std::array<double, 3>;

struct BulkMaterial {
  std::string name;
  double density = 0;  // kg/m^3
  double E = 0;        // Pa
  double nu = 0;       // -
};

struct InterfaceMaterial {
  std::string name;
  double kn = 0, ks = 0;    // Pa/m
  double ft = 0, c = 0;     // Pa
  double phi = 0;           // rad (file: phi_deg)
  double Gnc = 0, Gsc = 0;  // N/m
  double eta = 2.0;         // Benzeggagh-Kenane exponent
  // The law while a point softens and once it has failed (file: law): "residual_friction", a
  // point that has begun to soften keeps a Coulomb friction that takes up what the softening
  // cohesion no longer carries, up to the residual sigma_n tan(phi_r) (phi_r: file phi_r_deg,
  // default phi_deg), or "paper", the paper's law (no friction while a point softens, none once it
  // has failed), the default until the shipped cases have been compared under both
  // (docs/validation.md). The contact faces such an interface leaves take tan(phi_r) too (with
  // "paper", the contact law's friction).
  bool residual_friction = false;
  double phi_r = 0;  // rad
  // No tension and no cohesion: a purely frictional joint. Its interfaces are failed and handed
  // over to contact from the start; contacts on their faces take the friction tan(phi).
  bool frictional() const { return ft == 0 && c == 0; }
};

// Random strength of the interfaces (docs/case-format.md, "fracture.scatter"): interface q's
// f_t and c (strength) and, if `energy`, its Gnc and Gsc are its material's times a factor w_q
// drawn once per interface from the distribution, mean 1: "weibull" (modulus m) or "normal"
// (coefficient of variation cov, truncated to [lower, upper], then rescaled to mean 1).
struct StrengthScatter {
  std::string distribution;  // "" (none), "weibull" or "normal"
  double modulus = 0;        // weibull
  double cov = 0;            // normal
  double lower = 0.1, upper = 10;  // normal: truncation of w before the mean is restored
  unsigned long long seed = 1;
  bool energy = false;  // scale the fracture energies with the strength
  // > 0: a spatially correlated field (Gaussian correlation exp(-r^2 / l^2) of the underlying
  // normal field, this l in m) instead of independent draws; 0: independent
  double correlation_length = 0;
};

// Fixed or prescribed-velocity components of a node set. Fixed is velocity 0.
struct VelocityBC {
  std::string set;
  std::array<bool, 3> active{false, false, false};
  Vec3 velocity{0, 0, 0};
  double ramp_time = 0;  // velocity rises linearly from 0 over this time (0: at once)
};

// Distinct ramp times > 0 the point loads of a case may have (the node update keeps a force per
// node for each: kLoadRampSlots in kernels/nodes.hpp).
constexpr int kMaxLoadRamps = 8;

struct PointLoad {
  std::string set;
  Vec3 force{0, 0, 0};  // total force, shared equally by the nodes of the set
  double ramp_time = 0;  // force rises linearly from 0 over this time (0: at once)
};

struct InitialVelocity {
  std::string region;   // region name, or "all"
  Vec3 velocity{0, 0, 0};
};

// Rigid plane (2D: line) with prescribed motion, pushing on the body's boundary nodes through
// penalty springs with Coulomb friction and cohesion (docs/theory.md section 6b).
struct PlatenSpec {
  std::string name;
  Vec3 point{0, 0, 0};     // a point of the plane at t = 0
  Vec3 normal{0, 0, 0};    // unit normal pointing into the body side
  Vec3 velocity{0, 0, 0};  // prescribed velocity of the plane
  bool has_change = false;        // "change": from change_time on it moves at change_velocity
  double change_time = 0;         // s
  Vec3 change_velocity{0, 0, 0};  // m/s
  double kn = 0, ks = 0;   // Pa/m (per unit contact area); 0: derive (resolve_defaults)
  double friction = 0;     // Coulomb coefficient
  double cohesion = 0;     // Pa
  // kg (2D: of the body's thickness); > 0: the platen moves along its normal under the body's
  // force and gravity from `velocity` on (a guided drop weight); 0: its motion is prescribed
  double mass = 0;
};

// Contact between deformable bodies (docs/theory.md section 6b): the outer boundaries of the bodies
// and the faces of failed interfaces. See docs/case-format.md, "contact".
struct ContactSpec {
  int enabled = -1;        // -1: auto (on when the mesh has interfaces or more than one body); 0: off; 1: on
  double kn = 0, ks = 0;   // Pa/m per unit contact area; 0: derive (resolve_defaults)
  double friction = -1;    // Coulomb coefficient; < 0: derive (default_contact_friction)
  double cohesion = 0;     // Pa
  double skin = 0;         // m, Verlet skin of the broad phase; 0: derive (0.02 mean element size)
  // m, over several processes: how far beyond the search distance each process holds the faces
  // its contacts may touch (docs/parallel.md "Contact"); 0: derive (1 mean element size)
  double zone = 0;
};

struct Case {
  std::string file;     // path of the case file
  std::string name;
  int dim = 2;
  MeshSpec mesh;
  bool plane_stress = false;  // 2D only
  // precision "mixed": the host force pass's strains, stresses and tractions in floats
  // (Model::mixed_precision; docs/case-format.md, top level)
  bool mixed_precision = false;
  double thickness = 1.0;     // 2D only, m

  std::vector<BulkMaterial> materials;
  std::map<std::string, int> region_material;   // region name -> index into materials
  std::vector<InterfaceMaterial> interface_materials;
  std::vector<std::string> fracturable_regions;  // region names that get interfaces
  int fracture_material = -1;                    // index into interface_materials
  // Interface materials by place (docs/case-format.md, "fracture"): an interface with both sides
  // in region R takes region_iface_material[R]; one between regions R1 and R2 takes the material
  // of that pair (pair_iface_material, keys ordered R1 < R2; it wins over the region rule); the
  // rest take fracture_material. Indices into interface_materials.
  std::map<std::string, int> region_iface_material;
  std::map<std::pair<std::string, std::string>, int> pair_iface_material;
  // Interfaces on named surfaces (face sets of the mesh: physical curves in 2D, surfaces in 3D):
  // inserted there even between elements of regions that are not fracturable, and of that
  // material (wins over the region and pair rules). Face set name -> index into interface_materials.
  std::map<std::string, int> surface_iface_material;
  StrengthScatter scatter;
  // Strength reduction of the interfaces (slope stability): f_t, c and tan(phi) are divided by
  // SRF(t) = srf_initial for t < srf_start, srf_initial + srf_rate (t - srf_start) after.
  double srf_initial = 1.0, srf_start = 0.0, srf_rate = 0.0;

  std::vector<VelocityBC> velocity_bcs;
  std::vector<PointLoad> point_loads;
  Vec3 gravity{0, 0, 0};
  std::vector<InitialVelocity> initial_velocities;
  std::vector<PlatenSpec> platens;
  ContactSpec contact;
  // Over several processes with contact: the parts are cut anew when the most loaded process's
  // modelled work per step exceeds the mean by more than this fraction (and by more than twice
  // what it exceeded it by right after the last cut); docs/parallel.md "Rebalancing".
  double rebalance_above = 0.2;
  WorkModel work_model;  // its ns per item (parallel.work_model; defaults: one host thread's)

  double local_damping = 0;      // alpha, [0, 1)
  double mass_damping = 0;       // c, 1/s
  // From damping_change_time on (< 0: never) the damping is these instead (e.g. settle under
  // gravity quasi-statically, then let a failing slope move).
  double damping_change_time = -1, damping_change_local = 0, damping_change_mass = 0;

  double safety_factor = 0.5;    // on the computed stable time step
  double dt = 0;                 // > 0: user time step, used only if below the stable one
  double end_time = 0;           // s
  long max_steps = 0;            // 0: unlimited
  // Stop when the named platen's force magnitude has fallen below (1 - drop_fraction) of its peak
  // (after a peak was reached). Empty: no such stop.
  std::string stop_platen;
  double stop_drop_fraction = 0;

  double history_interval = 0;   // s; 0: 200 rows over the run
  double snapshot_interval = 0;  // s; 0: no snapshots
  double checkpoint_every = 0;   // s of simulated time between checkpoints; 0: none
  int check_interval = 100;      // steps between stability checks (energy balance, finiteness)
  std::vector<std::string> monitors;  // node sets whose mean displacement goes into history.csv
  bool output_fragments = true;  // fragments.csv and the snapshot field (runs with interfaces only)

  // The case after --set overrides and defaults, written to out/ (with the derived values once
  // resolve_defaults has run).
  nlohmann::json resolved;
};

// Reads, applies overrides ("key.path=value", value parsed as JSON when it parses, else a string)
// and validates. Throws InputError naming the file, the key path and the allowed range.
Case load_case(const std::string& path, const std::vector<std::string>& overrides = {});

// Same from an in-memory document; `source` names it in messages.
Case parse_case(nlohmann::json doc, const std::string& source,
                const std::vector<std::string>& overrides = {});

// Checks that names used by the case (regions, node sets) exist in the mesh. Throws InputError.
void check_case_against_mesh(const Case& c, const HostMesh& mesh);

// Fills the values the case leaves to be derived from its materials and mesh (the mesh as the
// solver gets it), in the Case and in `resolved`; values already set are kept, so a second call
// changes nothing. Platen kn and ks; contact kn, ks, friction and skin (docs/case-format.md,
// "platens" and "contact"). Defined in src/io/case_defaults.cpp.
void resolve_defaults(Case& c, const HostMesh& mesh);
// The same from the mesh's mean element size (mesh_quality(mesh).mean_size) alone: what the
// processes of a run over several that do not hold the whole mesh use (the same values).
void resolve_defaults(Case& c, double mean_element_size);

// Contact friction when not given: tan(phi) of the fracture interface material, else 0.
double default_contact_friction(const Case& c);

}  // namespace fdem
