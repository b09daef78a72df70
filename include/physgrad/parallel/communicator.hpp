// Communicator — the K processes ("ranks") of a data-parallel run and the collective operations
// they use: sum over ranks, concatenation of per-rank blocks, broadcast from one rank.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "physgrad/stop.hpp"

namespace physgrad {

class DistributedEigensolver;  // distributed_eigen.hpp

// Thrown by a collective that the other ranks did not all join within the communicator's time
// limit (a rank stopped, hung or gone). It is a StopRequested, so that training that meets it
// inside a step drops that step and saves its checkpoint as on a stop request. The
// communicator is broken from then on (Communicator::failure()): every later collective throws
// it again, and the process ends by abort(), since MPI_Finalize would wait for the missing rank.
class RanksNotAnswering : public StopRequested {
 public:
  using StopRequested::StopRequested;
};

// Every rank calls each collective in the same order with matching sizes. Results are the same
// bits on every rank (the sum is reduced on rank 0 and broadcast, so no reduction order can make
// ranks drift apart).
class Communicator {
 public:
  virtual ~Communicator() = default;
  virtual int rank() const = 0;  // 0 … size() − 1
  virtual int size() const = 0;  // K ≥ 1
  virtual std::string name() const = 0;  // "serial", "mpi", …

  // data[i] ← Σ_ranks data[i], for i < count (count equal on every rank).
  virtual void allreduce_sum(double* data, std::size_t count) = 0;
  // The blocks of all ranks concatenated in rank order; each rank's block may have any size
  // (also 0). `counts`, if given, receives the size of every rank's block.
  virtual std::vector<double> allgather(const double* data, std::size_t count,
                                        std::vector<std::size_t>* counts = nullptr) = 0;
  // data[i] ← data[i] of rank `root`, for i < count.
  virtual void broadcast(double* data, std::size_t count, int root) = 0;
  // Ends every rank after an unrecoverable error on this one (so none waits forever in a
  // collective); the serial communicator has nothing to end and returns.
  virtual void abort(int exit_code) = 0;
  // The ranks' solver for symmetric eigenproblems held by columns (distributed_eigen.hpp), or
  // null when they have none (then every rank solves the whole problem itself).
  virtual DistributedEigensolver* eigensolver() { return nullptr; }
  // Why this rank can exchange no more (the message of the RanksNotAnswering it threw); empty
  // while it can.
  virtual std::string failure() const { return {}; }

  // Convenience forms on vectors.
  void allreduce_sum(std::vector<double>& data) { allreduce_sum(data.data(), data.size()); }
  double allreduce_sum(double value) {
    allreduce_sum(&value, 1);
    return value;
  }
};

// One process: sums and concatenations return the local data.
class SerialCommunicator final : public Communicator {
 public:
  int rank() const override { return 0; }
  int size() const override { return 1; }
  std::string name() const override { return "serial"; }
  void allreduce_sum(double* /*data*/, std::size_t /*count*/) override {}
  std::vector<double> allgather(const double* data, std::size_t count,
                                std::vector<std::size_t>* counts = nullptr) override;
  void broadcast(double* data, std::size_t count, int root) override;
  void abort(int /*exit_code*/) override {}
  using Communicator::allreduce_sum;
};

// The contiguous share of `count` items (batch columns, data-set samples) that rank `rank` of
// `size` owns: [begin, begin + length). Shares differ by at most one item, the larger ones on
// the lower ranks, and are empty when count < size for the ranks beyond count.
struct Share {
  std::size_t begin = 0;
  std::size_t length = 0;
};
Share share_of(std::size_t count, int rank, int size);

// True when this process was started by an MPI launcher (mpirun/mpiexec of Open MPI or of an
// MPICH-style process manager), judged from the environment the launcher sets.
bool launched_by_mpi();
// The number of processes the launcher started (OMPI_COMM_WORLD_SIZE or PMI_SIZE), 1 when not
// launched or unknown.
int launcher_size();

// A 64-bit FNV-1a hash of the bytes of `count` doubles; ranks compare it to check that their
// parameters are bit-identical.
std::uint64_t hash_doubles(const double* data, std::size_t count);

// True when every rank passed the same hash (one allgather).
bool same_on_all_ranks(Communicator& communicator, std::uint64_t hash);

// What one rank was started to do, as (name, value) pairs in a fixed order: the command, then
// its settings.
using RankCommand = std::vector<std::pair<std::string, std::string>>;
// Checks, in one allgather of every rank's `command`, that all ranks were started alike; throws
// Error on every rank naming the first entry that differs: "the ranks were not started alike:
// --iters is '100' on rank 0 but '300' on rank 1; start every rank with the same command and
// settings". RanksNotAnswering when a rank does not take part within the time limit.
void require_same_command(Communicator& communicator, const RankCommand& command);

// Returns once every rank has called it (one sum); RanksNotAnswering after the time limit.
void wait_for_all_ranks(Communicator& communicator);

// The seconds a collective of the MPI communicator waits for the other ranks before it throws
// RanksNotAnswering: PHYSGRAD_RANK_TIMEOUT, a decimal number of seconds > 0 (up to 10⁶), or
// kDefaultRankTimeout when it is unset; throws Error naming the variable for any other value.
inline constexpr double kDefaultRankTimeout = 300;
double rank_timeout_seconds();

}  // namespace physgrad
