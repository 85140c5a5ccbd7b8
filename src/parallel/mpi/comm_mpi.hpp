#pragma once
// MPI for fdem's main in an MPI build (-DFDEM_ENABLE_MPI=ON; the library fdem_mpi, the only code
// that sees MPI besides Zoltan's partitioners): starts and ends MPI and implements Comm
// (src/parallel/comm.hpp) on MPI_COMM_WORLD.
#include <memory>
#include <string>

#include "parallel/comm.hpp"

namespace fdem {

// MPI_Init (before Kokkos starts); the world's Comm.
std::shared_ptr<Comm> mpi_start(int* argc, char*** argv);
// MPI_Finalize (after Kokkos has ended), unless MPI was not started or is finalized already.
void mpi_finish();
// One line for `fdem info`: the MPI library's version, the process count and GPU-awareness.
std::string mpi_description(const Comm& comm);

}  // namespace fdem
