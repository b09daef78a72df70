// The processes of one CLI run: under mpirun (in a build with MPI) the ranks of MPI_COMM_WORLD,
// otherwise this process alone. Rank 0 prints and writes the run folder; the others only compute.
#pragma once

#include <memory>
#include <string>

#include "physgrad/parallel/communicator.hpp"

namespace physgrad::cli {

// Made once at the start of main(): initializes MPI only when the build has it and a launcher
// started this process; finalizes it when destroyed.
class Ranks {
 public:
  Ranks(int* argc, char*** argv);
  ~Ranks();
  Ranks(const Ranks&) = delete;
  Ranks& operator=(const Ranks&) = delete;
};

// The communicator of this run (serial before Ranks is made or without MPI).
const std::shared_ptr<Communicator>& communicator();
// True on the rank that prints and writes (rank 0).
bool is_writer();
// "rank R of K: " in a run of several ranks, empty otherwise.
std::string rank_prefix();
// After an error on this rank: in a run of several ranks ends all of them with `exit_code`
// (MPI_Abort), so none waits forever; otherwise returns `exit_code`.
int end_run(int exit_code);

}  // namespace physgrad::cli
