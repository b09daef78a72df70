// Cost of the collectives of data-parallel training on this machine: run under mpiexec with K
// ranks; prints, per message size, the mean seconds of one sum over ranks (reduce to rank 0 +
// broadcast) and of one gather of every rank's block, for the latency/bandwidth model of
// docs/distributed.md.
#include <chrono>
#include <cstdio>
#include <vector>

#include "physgrad/parallel/mpi_communicator.hpp"

int main(int argc, char** argv) {
  using Clock = std::chrono::steady_clock;
  const auto communicator = physgrad::mpi_world_communicator(&argc, &argv);
  physgrad::Communicator& comm = *communicator;
  if (comm.rank() == 0) {
    std::printf("ranks %d\n%12s %14s %14s\n", comm.size(), "doubles", "sum_seconds",
                "gather_seconds");
  }
  for (std::size_t n = 1; n <= (std::size_t{1} << 22); n *= 4) {
    std::vector<double> data(n, 1.0 + comm.rank());
    const int repeats = n < 4096 ? 2000 : n < (1 << 18) ? 100 : 10;
    double seconds[2] = {0, 0};
    for (int kind = 0; kind < 2; ++kind) {
      for (int warm = 0; warm < 2; ++warm) {
        const auto start = Clock::now();
        for (int r = 0; r < repeats; ++r) {
          if (kind == 0) {
            comm.allreduce_sum(data.data(), n);
          } else {
            // Each rank contributes n / K doubles, as a batch split over K ranks would.
            const std::size_t share = n / static_cast<std::size_t>(comm.size());
            const std::vector<double> all = comm.allgather(data.data(), share);
            data[0] += all.empty() ? 0.0 : all[0] * 0.0;
          }
        }
        seconds[kind] = std::chrono::duration<double>(Clock::now() - start).count() / repeats;
      }
    }
    if (comm.rank() == 0) std::printf("%12zu %14.3e %14.3e\n", n, seconds[0], seconds[1]);
  }
  return 0;
}
