// Run under mpiexec on 2 ranks by Mpi.MpiRanks.*: rank 1 joins the barrier that opens rank 0's
// collective and then never takes part in the collective itself, as a rank stopped inside it
// would; rank 0's watch must end rank 0 once the blocking part has lasted the time limit
// (argv[1] seconds): exit code 2 and one line on stderr. The collective is a large sum, or with
// argv[2] = "eigensolve" the distributed eigensolve (ScaLAPACK's own exchanges). Exit code 1
// means the collective returned, which it cannot; 3, that the build has no distributed solver.
#include <mpi.h>

#include <chrono>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include "physgrad/parallel/distributed_eigen.hpp"
#include "physgrad/parallel/mpi_communicator.hpp"

int main(int argc, char** argv) {
  const double limit = argc > 1 ? std::atof(argv[1]) : 2.0;
  const bool eigensolve = argc > 2 && std::string(argv[2]) == "eigensolve";
  const auto communicator = physgrad::mpi_world_communicator(&argc, &argv, limit);
  if (communicator->rank() == 0) {
    if (eigensolve) {
      physgrad::DistributedEigensolver* solver = communicator->eigensolver();
      if (solver == nullptr) return 3;
      const physgrad::Index n = 256;
      const auto columns = physgrad::block_cyclic_columns(n, solver->block(), 0, 2);
      physgrad::Matrix local =
          physgrad::Matrix::Zero(n, static_cast<physgrad::Index>(columns.size()));
      for (std::size_t j = 0; j < columns.size(); ++j) {
        local(columns[j], static_cast<physgrad::Index>(j)) = 1.0 + static_cast<double>(columns[j]);
      }
      physgrad::DistributedPowerInfo info;
      solver->truncated_power(local, n, physgrad::Vector::Ones(n), {.kappa = 0.5, .rcond = 1e-6}, &info);
      return 1;
    }
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
