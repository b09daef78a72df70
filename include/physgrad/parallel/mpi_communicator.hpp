// MpiCommunicator — the Communicator over MPI_COMM_WORLD (library physgrad_mpi, built when CMake
// finds MPI): Σ by MPI_Reduce to rank 0 + MPI_Bcast, blocks by MPI_Allgatherv.
#pragma once

#include <memory>

#include "physgrad/parallel/communicator.hpp"

namespace physgrad {

// Initializes MPI (MPI_Init) and finalizes it (MPI_Finalize) when the last reference goes away;
// one per process. Throws Error when MPI was initialized before by someone else.
std::shared_ptr<Communicator> mpi_world_communicator(int* argc, char*** argv);

}  // namespace physgrad
