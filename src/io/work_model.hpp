#pragma once
// The work model of a run over processes (docs/parallel.md "Rebalancing"): nanoseconds of one
// step per bulk element, per interface not handed over to contact, per node (its update) and per
// unit of the contact's work (a surface point counts 2 units, each of its candidate faces 1). Only
// the ratios matter. The defaults were measured on one host thread on the default 3D impact's late
// stage (docs/parallel.md): the contact kernels 4.63 ms a step for 107 503 candidates and 20 101
// surface points (31 ns a unit), the force pass 2.6 ms for 12 577 tetrahedra and 23 898
// interfaces, 3 134 of them handed over (the model: 2.62 ms); the node update about 11 ns a node on
// large meshes (docs/performance.md). Another machine or backend (a GPU) sets its own in the case
// (parallel.work_model, docs/case-format.md). A case setting (Case::work_model, io/case.hpp), read
// by the balance and the weighted cut (parallel/partition.hpp: element_work).

namespace fdem {

struct WorkModel {
  double element = 60, interface = 90, node = 11, contact_unit = 31;
};

}  // namespace fdem
