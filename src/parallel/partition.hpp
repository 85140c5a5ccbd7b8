#pragma once
// Partition of the elements of a host mesh into parts (later: MPI processes; docs/parallel.md).
// Host only. Every element of a fracturable region owns its nodes after interface insertion, so a
// cut runs through interfaces (and, in continuous regions, through faces whose nodes two elements
// share); its cost is the number of those it cuts: each needs a ghost element and an exchange per
// step. The work of a part: its elements plus the interfaces whose side A it owns.
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/work_model.hpp"

namespace fdem {

struct HostMesh;

enum class PartitionMethod {
  Metis,  // METIS_PartGraphKway on the element graph (edges: interfaces and shared faces)
  Rcb,    // recursive coordinate bisection of the element centroids (a plain baseline, home-made)
  Block,  // contiguous ranges of element indices: Morton order after reorder_for_locality
  // Zoltan's geometric partitioners of the element centroids (builds with -DFDEM_ENABLE_MPI=ON only):
  ZoltanRcb,   // recursive coordinate bisection
  ZoltanRib,   // recursive inertial bisection
  ZoltanHsfc,  // Hilbert space-filling curve
};

// "metis", "rcb", "block", "zoltan-rcb", "zoltan-rib", "zoltan-hsfc"; anything else, or a method
// this build lacks (METIS not found; Zoltan without FDEM_ENABLE_MPI): InputError naming --method
// and the allowed names.
PartitionMethod parse_partition_method(const std::string& name);
const char* partition_method_name(PartitionMethod m);
// Whether this build links METIS (CMake found it) and Zoltan (FDEM_ENABLE_MPI).
bool partition_has_metis();
bool partition_has_zoltan();

// The element graph in compressed rows: xadj[e]..xadj[e+1] index adj (neighbour elements) and
// kind (0: an interface joins them, 1: a continuous face: they share its nodes). Each edge
// appears in both rows. Elements joined by several interfaces (never for simplices) appear once
// per interface.
struct ElementGraph {
  std::vector<int> xadj, adj;
  std::vector<unsigned char> kind;
  std::vector<int> weight;  // per element: 1 + interfaces whose side A it is (the work model)
};
ElementGraph element_graph(const HostMesh& mesh);

// A part id in [0, parts) per element. Throws InputError for parts < 1 or parts > elements
// (naming --parts and the allowed range) and for metis in a build without METIS.
// Deterministic: the same mesh and arguments give the same result.
// group > 1 (metis): the elements come in groups of `group` consecutive ones that stay together
// (a refined mesh's children of one coarse element, src/mesh/refine.hpp): METIS partitions the
// groups' graph (the coarse mesh's), 1/group of the work; ignored where the element count is not a
// multiple of it or the parts would get fewer than 8 groups each.
std::vector<int> partition_elements(const HostMesh& mesh, int parts, PartitionMethod method, int group = 1);

// The partition of a mesh refined from `coarse` (src/mesh/refine.hpp) computed from the coarse mesh
// alone, one part id per coarse element (its children go with it): what a run over processes
// partitions before any process refines (docs/parallel.md, "The local set-up"), the same on every
// process and whether the whole fine mesh exists or not. Each coarse element weighs its children
// and the interfaces whose side A they are (the work model, as element_graph's weights), from
// iface_offsets (refined_interface_offsets); METIS joins facet neighbours by the fine interfaces
// between them (neighbours ascending), the other methods cut the coarse centroids with those
// weights. Throws InputError as partition_elements, with the coarse element count as the limit.
struct CoarseTopology;
std::vector<int> partition_coarse(const HostMesh& coarse, const CoarseTopology& topo,
                                  const std::vector<std::int64_t>& iface_offsets, int parts, PartitionMethod method);

// Recursive coordinate bisection with the given work per element (positive and finite): the cut
// of the parts during a run (solver/run.cpp), weighted by what each element's step costs. Zoltan's
// RCB (largest part within 1 % of the mean) in a build with Zoltan (the MPI build), else the
// baseline `rcb` (weighted medians). With `graph`: METIS k-way on the mesh's element graph instead
// (the weights scaled to integers up to 1000; the measurement of docs/parallel.md, "Rebalancing").
// Throws InputError for parts out of [1, elements], a weight count or value that does not fit, or
// `graph` in a build without METIS.
std::vector<int> partition_elements_weighted(const HostMesh& mesh, int parts, const std::vector<double>& work,
                                             bool graph = false);
// Each element's work in `model`'s terms (ns a step): its own (bulk, nodes, the interfaces whose side A it
// is, less those whose `handed` flag is set: handed over to contact, they cost about nothing) and
// an equal share of each of its nodes' `node_work` (the contact work of the surface nodes). Empty
// `node_work` or `handed`: none.
std::vector<double> element_work(const HostMesh& mesh, const std::vector<double>& node_work,
                                 const std::vector<long long>& handed = {}, const WorkModel& model = {});

// Starts what the method needs once per process (MPI and Zoltan for the zoltan methods; nothing
// for the others), so that the partition's time excludes it. partition_elements calls it too.
void partition_init(PartitionMethod method);

struct PartitionStats {
  int parts = 0;
  long elements = 0, interfaces = 0, shared_faces = 0;
  std::vector<long> elements_per_part, load_per_part, ghosts_per_part, ghost_nodes_per_part;
  // load + the cut interfaces whose side B the part owns: a cut interface is computed by both
  // parts (docs/parallel.md), so this is the work of a step
  std::vector<long> work_per_part;
  double imbalance = 0;          // max / mean - 1 of load_per_part (elements + side-A interfaces)
  double element_imbalance = 0;  // max / mean - 1 of elements_per_part
  double work_imbalance = 0;     // max of work_per_part / mean of load_per_part - 1
  long interfaces_cut = 0;       // interfaces whose two elements lie in different parts
  long shared_faces_cut = 0;     // continuous faces (shared nodes) between different parts
  long ghosts = 0;               // sum of ghosts_per_part
  long ghost_nodes = 0;          // sum of ghost_nodes_per_part
  double seconds = 0;            // wall time of the partition (set by the caller)
};
// Ghost elements of part p: elements of other parts that share an interface or a face with p.
// Ghost nodes of p: the other side's nodes of p's cut interfaces (distinct): the positions p needs
// from other parts each step to compute those interfaces (dim doubles each).
PartitionStats partition_stats(const HostMesh& mesh, const std::vector<int>& part, int parts);
nlohmann::json partition_stats_json(const PartitionStats& s);
// A few lines for a person: the totals, then elements, load and ghosts per part.
std::string partition_report_text(const nlohmann::json& report);

// Elements that change part from `before` to `after` once the part ids of `after` are renamed to
// match those of `before` (greedily, largest overlap first): what a rebalance would move.
long migrated_elements(const std::vector<int>& before, const std::vector<int>& after, int parts);

// The mesh as a rebalance during a run would see it: node positions `x` (num_nodes * 3, z ignored
// in 2D: a snapshot's coordinates) and without the interfaces whose damage is 1 (failed: handed to
// contact, no longer an edge of the graph nor an exchange).
HostMesh moved_mesh(const HostMesh& mesh, const std::vector<double>& x, const std::vector<double>& damage);

// Legacy VTK (binary) of the mesh with the cell fields "part" and "region", for ParaView.
void write_partition_vtk(const std::string& path, const HostMesh& mesh, const std::vector<int>& part);

// `fdem partition`: loads the case (with --set overrides), prepares its mesh as a run does,
// partitions it, writes out_dir/partition.json (stats) and out_dir/partition.vtk, and returns
// the stats. out_dir empty: out/<case name>. With a snapshot file (snapshots.h5 of a run of the
// same case and --set options): also the rebalance at its last frame (moved_mesh): the partition
// of the moved mesh, its stats, and the elements it moves (migrated_elements) under "rebalance".
nlohmann::json partition_case(const std::string& case_path, const std::vector<std::string>& overrides,
                              int parts, const std::string& method, const std::string& out_dir,
                              const std::string& snapshot = "");

}  // namespace fdem
