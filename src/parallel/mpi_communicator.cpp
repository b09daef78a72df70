#include "physgrad/parallel/mpi_communicator.hpp"

#include <mpi.h>

#include <atomic>
#include <chrono>
#include <climits>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>

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

// The backstop of the blocking part of a collective: a rank that stops in the middle of one
// (after it joined) would hold the others for ever, so a thread ends this process when a
// blocking call lasts longer than the limit (mpiexec then ends the others).
class BlockingWatch {
 public:
  BlockingWatch(double limit, int rank, int size)
      : limit_(limit), prefix_("rank " + std::to_string(rank) + " of " + std::to_string(size)) {
    thread_ = std::thread([this] { watch(); });
  }
  ~BlockingWatch() {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      done_ = true;
    }
    wake_.notify_all();
    thread_.join();
  }
  BlockingWatch(const BlockingWatch&) = delete;
  BlockingWatch& operator=(const BlockingWatch&) = delete;

  // Runs `call` under the watch and returns what it returns (also when it throws, the watch
  // stops watching).
  template <class Call>
  auto run(const Call& call, std::size_t count) {
    count_.store(count);
    since_.store(Clock::now().time_since_epoch().count());
    struct Unwatch {
      std::atomic<Clock::rep>& since;
      ~Unwatch() { since.store(0); }
    } unwatch{since_};
    return call();
  }

 private:
  using Clock = std::chrono::steady_clock;
  void watch() {
    std::unique_lock<std::mutex> lock(mutex_);
    while (!wake_.wait_for(lock, std::chrono::milliseconds(250), [this] { return done_; })) {
      const auto since = since_.load();
      if (since == 0) continue;
      const double waited = std::chrono::duration<double>(
          Clock::now().time_since_epoch() - Clock::duration(since)).count();
      if (waited <= limit_) continue;
      std::fprintf(stderr,
                   "physgrad: error: %s: a blocking exchange of %zu numbers from this rank did "
                   "not end within %g s: a rank stopped in it (PHYSGRAD_RANK_TIMEOUT sets the "
                   "limit); ended without saving this state\n",
                   prefix_.c_str(), count_.load(), limit_);
      std::fflush(stderr);
      std::_Exit(2);
    }
  }

  const double limit_;
  const std::string prefix_;
  std::atomic<Clock::rep> since_{0};  // when the running call began; 0: none runs
  std::atomic<std::size_t> count_{0};
  std::mutex mutex_;
  std::condition_variable wake_;
  bool done_ = false;
  std::thread thread_;
};

// Collectives of this many doubles or more move their data by the blocking MPI call, once a
// polled non-blocking barrier (or gather of the sizes) has seen every rank join: Open MPI's
// non-blocking forms were up to 13× slower from about here on (2 ranks on shared memory: a sum
// of 2048 doubles 0.33 against 0.19 ms, a gather of 49152 doubles 2.4 against 0.2 ms, a sum of
// 10⁶ doubles 0.1 against 0.016 s), while below it they cost microseconds more (sums of 1 to 30
// doubles, as a step makes: 0.3 to 2 µs).
constexpr std::size_t kBlockingFrom = 1024;

// The distributed eigensolve under the bounds of a large collective: the ranks first all join a
// polled exchange (`join`, which throws RanksNotAnswering after the limit), then the solve, whose
// own exchanges ScaLAPACK makes, runs under the watch: a rank that stops inside it ends the job
// within the limit instead of holding the others for ever.
class WatchedEigensolver final : public DistributedEigensolver {
 public:
  WatchedEigensolver(std::unique_ptr<DistributedEigensolver> inner,
                     std::function<void(std::size_t)> join, BlockingWatch& watch)
      : inner_(std::move(inner)), join_(std::move(join)), watch_(watch) {}
  std::string name() const override { return inner_->name(); }
  Index block() const override { return inner_->block(); }
  int rank() const override { return inner_->rank(); }
  int size() const override { return inner_->size(); }
  Vector truncated_power(Matrix local, Index n, const Vector& g, const SpectralCut& cut,
                         DistributedPowerInfo* info) override {
    const auto count = static_cast<std::size_t>(local.size());
    join_(count);
    return watch_.run(
        [&] { return inner_->truncated_power(std::move(local), n, g, cut, info); },
        count);
  }

 private:
  std::unique_ptr<DistributedEigensolver> inner_;
  std::function<void(std::size_t)> join_;
  BlockingWatch& watch_;
};

// Every collective waits for the other ranks at most `timeout` seconds: a small one is started
// non-blocking and polled against the limit; a large one opens with such a polled exchange that
// every rank must join, and then runs blocking under the watch. A rank that never comes
// (stopped, hung, gone) thus ends the wait instead of holding it for ever.
class MpiCommunicator final : public Communicator {
 public:
  MpiCommunicator(int* argc, char*** argv, double timeout) : timeout_(timeout) {
    if (!(timeout > 0)) throw Error("the MPI communicator's time limit must be > 0 seconds");
    int initialized = 0;
    MPI_Initialized(&initialized);
    if (initialized != 0) throw Error("MPI was initialized before the communicator was made");
    check(MPI_Init(argc, argv), "MPI_Init");
    // Errors come back as codes (turned into Error) instead of ending the process silently.
    MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
    if (size_ > 1) {
      watch_ = std::make_unique<BlockingWatch>(timeout_, rank_, size_);
      if (auto scalapack = scalapack_eigensolver()) {
        eigensolver_ = std::make_unique<WatchedEigensolver>(
            std::move(scalapack),
            [this](std::size_t count) {
              usable();
              join_all("the distributed eigensolve", count);
            },
            *watch_);
      }
    }
  }
  ~MpiCommunicator() override {
    eigensolver_.reset();  // its BLACS grid ends before MPI does; it watches with watch_
    watch_.reset();
    int finalized = 0;
    MPI_Finalized(&finalized);
    if (finalized != 0) return;
    // A collective left waiting: MPI_Finalize would wait for the rank that never joined it.
    if (!failure_.empty()) MPI_Abort(MPI_COMM_WORLD, 1);
    MPI_Finalize();
  }
  MpiCommunicator(const MpiCommunicator&) = delete;
  MpiCommunicator& operator=(const MpiCommunicator&) = delete;

  int rank() const override { return rank_; }
  int size() const override { return size_; }
  std::string name() const override { return "mpi"; }
  std::string failure() const override { return failure_; }

  void allreduce_sum(double* data, std::size_t count) override {
    if (count == 0) return;
    const int n = mpi_count(count, "allreduce_sum");
    usable();
    // Reduce + broadcast: every rank gets rank 0's bits, whatever order the reduction used.
    void* send = rank_ == 0 ? MPI_IN_PLACE : data;
    void* receive = rank_ == 0 ? data : nullptr;
    if (count >= kBlockingFrom) {
      join_all("a sum", count);
      check(blocking(
                [&] {
                  const int reduced =
                      MPI_Reduce(send, receive, n, MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD);
                  return reduced != MPI_SUCCESS ? reduced
                                                : MPI_Bcast(data, n, MPI_DOUBLE, 0, MPI_COMM_WORLD);
                },
                count),
            "MPI_Reduce/MPI_Bcast");
      return;
    }
    MPI_Request request = MPI_REQUEST_NULL;
    check(MPI_Ireduce(send, receive, n, MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD, &request),
          "MPI_Ireduce");
    wait(request, "a sum", count);
    check(MPI_Ibcast(data, n, MPI_DOUBLE, 0, MPI_COMM_WORLD, &request), "MPI_Ibcast");
    wait(request, "a sum", count);
  }

  std::vector<double> allgather(const double* data, std::size_t count,
                                std::vector<std::size_t>* counts) override {
    usable();
    const auto local = static_cast<std::uint64_t>(count);
    std::vector<std::uint64_t> sizes(static_cast<std::size_t>(size_));
    MPI_Request request = MPI_REQUEST_NULL;
    check(MPI_Iallgather(&local, 1, MPI_UINT64_T, sizes.data(), 1, MPI_UINT64_T, MPI_COMM_WORLD,
                         &request),
          "MPI_Iallgather");
    wait(request, "a gather", count);  // every rank has joined
    std::vector<int> lengths(sizes.size()), offsets(sizes.size());
    std::size_t total = 0;
    for (std::size_t r = 0; r < sizes.size(); ++r) {
      lengths[r] = mpi_count(static_cast<std::size_t>(sizes[r]), "allgather");
      offsets[r] = mpi_count(total, "allgather");
      total += static_cast<std::size_t>(sizes[r]);
    }
    mpi_count(total, "allgather");
    std::vector<double> all(total);
    const int n = mpi_count(count, "allgather");
    if (total >= kBlockingFrom) {
      check(blocking(
                [&] {
                  return MPI_Allgatherv(data, n, MPI_DOUBLE, all.data(), lengths.data(),
                                        offsets.data(), MPI_DOUBLE, MPI_COMM_WORLD);
                },
                count),
            "MPI_Allgatherv");
    } else {
      check(MPI_Iallgatherv(data, n, MPI_DOUBLE, all.data(), lengths.data(), offsets.data(),
                            MPI_DOUBLE, MPI_COMM_WORLD, &request),
            "MPI_Iallgatherv");
      wait(request, "a gather", count);
    }
    if (counts != nullptr) counts->assign(sizes.begin(), sizes.end());
    return all;
  }

  void broadcast(double* data, std::size_t count, int root) override {
    if (root < 0 || root >= size_) {
      throw Error("broadcast: root " + std::to_string(root) + " of " + std::to_string(size_) +
                  " ranks");
    }
    if (count == 0) return;
    const int n = mpi_count(count, "broadcast");
    usable();
    if (count >= kBlockingFrom) {
      join_all("a broadcast", count);
      check(blocking([&] { return MPI_Bcast(data, n, MPI_DOUBLE, root, MPI_COMM_WORLD); }, count),
            "MPI_Bcast");
      return;
    }
    MPI_Request request = MPI_REQUEST_NULL;
    check(MPI_Ibcast(data, n, MPI_DOUBLE, root, MPI_COMM_WORLD, &request), "MPI_Ibcast");
    wait(request, "a broadcast", count);
  }

  void abort(int exit_code) override { MPI_Abort(MPI_COMM_WORLD, exit_code); }
  DistributedEigensolver* eigensolver() override { return eigensolver_.get(); }

 private:
  // Throws the RanksNotAnswering of an earlier collective again: this rank is out of step.
  void usable() const {
    if (!failure_.empty()) throw RanksNotAnswering(failure_);
  }

  template <class Call>
  int blocking(const Call& call, std::size_t count) {
    return watch_ ? watch_->run(call, count) : call();
  }

  // Returns once every rank has entered the collective `what` (a non-blocking barrier).
  void join_all(const char* what, std::size_t count) {
    MPI_Request request = MPI_REQUEST_NULL;
    check(MPI_Ibarrier(MPI_COMM_WORLD, &request), "MPI_Ibarrier");
    wait(request, what, count);
  }

  // Polls `request` until it completes; after timeout_ seconds the communicator is broken and
  // RanksNotAnswering names the exchange (`what` of `count` doubles from this rank).
  void wait(MPI_Request& request, const char* what, std::size_t count) {
    using Clock = std::chrono::steady_clock;
    int done = 0;
    check(MPI_Test(&request, &done, MPI_STATUS_IGNORE), "MPI_Test");
    if (done != 0) return;
    const auto start = Clock::now();
    for (unsigned polls = 1;; ++polls) {
      check(MPI_Test(&request, &done, MPI_STATUS_IGNORE), "MPI_Test");
      if (done != 0) return;
      if (polls % 64 != 0 ||
          std::chrono::duration<double>(Clock::now() - start).count() <= timeout_) {
        continue;
      }
      std::ostringstream text;
      text << "no answer from " << (size_ == 2 ? "rank " + std::to_string(1 - rank_) : "a rank")
           << " within " << timeout_ << " s in " << what << " (" << count
           << (count == 1 ? " number" : " numbers")
           << " from this rank): a rank is stopped, hung, gone or slower than that "
              "(PHYSGRAD_RANK_TIMEOUT sets the limit)";
      failure_ = text.str();
      throw RanksNotAnswering(failure_);
    }
  }

  int rank_ = 0;
  int size_ = 1;
  double timeout_;
  std::string failure_;
  std::unique_ptr<DistributedEigensolver> eigensolver_;
  std::unique_ptr<BlockingWatch> watch_;
};

}  // namespace

std::shared_ptr<Communicator> mpi_world_communicator(int* argc, char*** argv,
                                                     double timeout_seconds) {
  return std::make_shared<MpiCommunicator>(argc, argv, timeout_seconds);
}

}  // namespace physgrad
