#pragma once
// Zoltan's geometric partitioners (Debian's Trilinos, libtrilinos-zoltan-dev), built only with
// -DFDEM_ENABLE_MPI=ON (CMakeLists.txt): partition.cpp calls them for the methods zoltan-rcb,
// zoltan-rib and zoltan-hsfc. Plain arrays in and out, so that this file alone sees MPI and Zoltan.
#include <string>
#include <vector>

namespace fdem {

// MPI_Init (a singleton process: 0.3 s with OpenMPI here) and Zoltan_Initialize, once; also called by
// zoltan_partition. Throws std::runtime_error when Zoltan fails.
void zoltan_init();
// Points (dim coordinates each, the element centroids) with weights into `parts` parts on this one
// process; lb_method is Zoltan's LB_METHOD ("RCB", "RIB", "HSFC"), imbalance_tol Zoltan's
// IMBALANCE_TOL (the largest part's weight over the mean; 1.03 is METIS's default). Initialises MPI
// (a singleton) when it is not yet, and finalises it at exit. Throws std::runtime_error when Zoltan
// fails.
std::vector<int> zoltan_partition(int dim, const std::vector<double>& xyz, const std::vector<float>& weight,
                                  int parts, const std::string& lb_method, double imbalance_tol = 1.03);

}  // namespace fdem
