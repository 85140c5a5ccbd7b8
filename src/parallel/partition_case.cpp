// `fdem partition` (partition.hpp: partition_case): the case's mesh as a run prepares it, its
// partition, the statistics, and the files partition.json and partition.vtk.
#include <chrono>

#include "common/error.hpp"
#include "io/case.hpp"
#include "io/output.hpp"
#include "mesh/mesh.hpp"
#include "parallel/partition.hpp"
#include "solver/run.hpp"

namespace fdem {

nlohmann::json partition_case(const std::string& case_path, const std::vector<std::string>& overrides,
                              int parts, const std::string& method_name, const std::string& out_dir) {
  const PartitionMethod method = parse_partition_method(method_name);  // before the mesh: fails fast
  if (parts < 1)
    throw InputError("--parts " + std::to_string(parts) +
                     " is out of range: give an integer in [1, number of elements]");
  Case c = load_case(case_path, overrides);
  const std::string out = out_dir.empty() ? "out/" + c.name : out_dir;
  const HostMesh mesh = prepare_mesh(c);
  partition_init(method);  // MPI_Init for Zoltan: not part of the partition's time
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<int> part = partition_elements(mesh, parts, method);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  PartitionStats s = partition_stats(mesh, part, parts);
  s.seconds = seconds;
  nlohmann::json report = {{"case", c.name}, {"dimension", c.dim}, {"method", partition_method_name(method)}};
  report.update(partition_stats_json(s));
  ensure_output_dir(out);
  write_file_atomic(out + "/partition.json", report.dump(2) + "\n");
  write_partition_vtk(out + "/partition.vtk", mesh, part);
  report["files"] = {out + "/partition.json", out + "/partition.vtk (cell fields part, region)"};
  return report;
}

}  // namespace fdem
