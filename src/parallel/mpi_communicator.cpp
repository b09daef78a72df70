#include "physgrad/parallel/mpi_communicator.hpp"

#include <mpi.h>

#include <climits>
#include <cstdint>
#include <memory>
#include <string>

#include "physgrad/error.hpp"
#include "physgrad/parallel/scalapack_eigensolver.hpp"

namespace physgrad {

namespace {

void check(int status, const char* call) {
  if (status != MPI_SUCCESS) {
    char text[MPI_MAX_ERROR_STRING];
    int length = 0;
    MPI_Error_string(status, text, &length);
    throw Error(std::string(call) + " failed: " +
                std::string(text, static_cast<std::size_t>(length)));
  }
}

int mpi_count(std::size_t count, const char* what) {
  if (count > static_cast<std::size_t>(INT_MAX)) {
    throw Error(std::string(what) + ": " + std::to_string(count) +
                " doubles exceed one MPI message (INT_MAX)");
  }
  return static_cast<int>(count);
}

class MpiCommunicator final : public Communicator {
 public:
  MpiCommunicator(int* argc, char*** argv) {
    int initialized = 0;
    MPI_Initialized(&initialized);
    if (initialized != 0) throw Error("MPI was initialized before the communicator was made");
    check(MPI_Init(argc, argv), "MPI_Init");
    // Errors come back as codes (turned into Error) instead of ending the process silently.
    MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
    if (size_ > 1) eigensolver_ = scalapack_eigensolver();
  }
  ~MpiCommunicator() override {
    eigensolver_.reset();  // its BLACS grid ends before MPI does
    int finalized = 0;
    MPI_Finalized(&finalized);
    if (finalized == 0) MPI_Finalize();
  }
  MpiCommunicator(const MpiCommunicator&) = delete;
  MpiCommunicator& operator=(const MpiCommunicator&) = delete;

  int rank() const override { return rank_; }
  int size() const override { return size_; }
  std::string name() const override { return "mpi"; }

  void allreduce_sum(double* data, std::size_t count) override {
    if (count == 0) return;
    const int n = mpi_count(count, "allreduce_sum");
    // Reduce + broadcast: every rank gets rank 0's bits, whatever order the reduction used.
    if (rank_ == 0) {
      check(MPI_Reduce(MPI_IN_PLACE, data, n, MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD),
            "MPI_Reduce");
    } else {
      check(MPI_Reduce(data, nullptr, n, MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD), "MPI_Reduce");
    }
    check(MPI_Bcast(data, n, MPI_DOUBLE, 0, MPI_COMM_WORLD), "MPI_Bcast");
  }

  std::vector<double> allgather(const double* data, std::size_t count,
                                std::vector<std::size_t>* counts) override {
    const auto local = static_cast<std::uint64_t>(count);
    std::vector<std::uint64_t> sizes(static_cast<std::size_t>(size_));
    check(MPI_Allgather(&local, 1, MPI_UINT64_T, sizes.data(), 1, MPI_UINT64_T, MPI_COMM_WORLD),
          "MPI_Allgather");
    std::vector<int> lengths(sizes.size()), offsets(sizes.size());
    std::size_t total = 0;
    for (std::size_t r = 0; r < sizes.size(); ++r) {
      lengths[r] = mpi_count(static_cast<std::size_t>(sizes[r]), "allgather");
      offsets[r] = mpi_count(total, "allgather");
      total += static_cast<std::size_t>(sizes[r]);
    }
    mpi_count(total, "allgather");
    std::vector<double> all(total);
    check(MPI_Allgatherv(data, mpi_count(count, "allgather"), MPI_DOUBLE, all.data(),
                         lengths.data(), offsets.data(), MPI_DOUBLE, MPI_COMM_WORLD),
          "MPI_Allgatherv");
    if (counts != nullptr) counts->assign(sizes.begin(), sizes.end());
    return all;
  }

  void broadcast(double* data, std::size_t count, int root) override {
    if (root < 0 || root >= size_) {
      throw Error("broadcast: root " + std::to_string(root) + " of " + std::to_string(size_) +
                  " ranks");
    }
    if (count == 0) return;
    check(MPI_Bcast(data, mpi_count(count, "broadcast"), MPI_DOUBLE, root, MPI_COMM_WORLD),
          "MPI_Bcast");
  }

  void abort(int exit_code) override { MPI_Abort(MPI_COMM_WORLD, exit_code); }
  DistributedEigensolver* eigensolver() override { return eigensolver_.get(); }

 private:
  int rank_ = 0;
  int size_ = 1;
  std::unique_ptr<DistributedEigensolver> eigensolver_;
};

}  // namespace

std::shared_ptr<Communicator> mpi_world_communicator(int* argc, char*** argv) {
  return std::make_shared<MpiCommunicator>(argc, argv);
}

}  // namespace physgrad
