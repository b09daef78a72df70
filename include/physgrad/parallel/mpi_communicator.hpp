// MpiCommunicator — the Communicator over MPI_COMM_WORLD (library physgrad_mpi, built when CMake
// finds MPI): Σ by a reduce to rank 0 + a broadcast, blocks by an allgatherv; each waits for the
// other ranks at most a time limit (non-blocking forms, polled).
#pragma once

#include <memory>

#include "physgrad/parallel/communicator.hpp"

namespace physgrad {

// Initializes MPI (MPI_Init) and finalizes it (MPI_Finalize) when the last reference goes away;
// one per process. Throws Error when MPI was initialized before by someone else. A collective
// that the other ranks have not all joined after `timeout_seconds` throws RanksNotAnswering
// (communicator.hpp) and breaks the communicator; destroyed broken, it ends the job
// (MPI_Abort, exit code 1) instead of waiting in MPI_Finalize for the missing rank. A large
// collective (1024 doubles or more) moves its data by the blocking call once every rank has
// joined it; should that still last longer than the limit (a rank stopped inside it), a watch
// thread ends the process (exit code 2, one line on stderr).
std::shared_ptr<Communicator> mpi_world_communicator(int* argc, char*** argv,
                                                     double timeout_seconds = kDefaultRankTimeout);

}  // namespace physgrad
