// Run under mpiexec on 2 ranks by Mpi.MpiRanks.*: rank 1 joins the barrier that opens rank 0's
// large sum and then never takes part in the sum itself, as a rank stopped inside it would; rank
// 0's watch must end rank 0 once the blocking sum has lasted the time limit (argv[1] seconds):
// exit code 2 and one line on stderr. Exit code 1 means the sum returned, which it cannot.
#include <mpi.h>

#include <chrono>
#include <cstdlib>
#include <thread>
#include <vector>

#include "physgrad/parallel/mpi_communicator.hpp"

int main(int argc, char** argv) {
  const double limit = argc > 1 ? std::atof(argv[1]) : 2.0;
  const auto communicator = physgrad::mpi_world_communicator(&argc, &argv, limit);
  if (communicator->rank() == 0) {
    std::vector<double> data(std::size_t{1} << 20, 1.0);
    communicator->allreduce_sum(data.data(), data.size());
    return 1;
  }
  MPI_Request request = MPI_REQUEST_NULL;
  MPI_Ibarrier(MPI_COMM_WORLD, &request);
  MPI_Wait(&request, MPI_STATUS_IGNORE);
  std::this_thread::sleep_for(std::chrono::seconds(120));  // ended with the job before that
  return 1;
}
