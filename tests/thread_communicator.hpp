// Test helper: a Communicator whose "ranks" are threads of one process, so data-parallel
// training is tested without MPI. Sums add the ranks' values in rank order on every thread.
#pragma once

#include <condition_variable>
#include <mutex>
#include <vector>

#include "physgrad/error.hpp"
#include "physgrad/parallel/communicator.hpp"

namespace physgrad::testing {

// The meeting point of the threads of one group.
class ThreadHub {
 public:
  explicit ThreadHub(int size) : size_(size), slots_(static_cast<std::size_t>(size)) {}
  int size() const { return size_; }
  std::vector<double>& slot(int rank) { return slots_[static_cast<std::size_t>(rank)]; }
  // Returns when every thread of the group has arrived.
  void barrier() {
    std::unique_lock<std::mutex> lock(mutex_);
    const long generation = generation_;
    if (++arrived_ == size_) {
      arrived_ = 0;
      ++generation_;
      ready_.notify_all();
    } else {
      ready_.wait(lock, [&] { return generation_ != generation; });
    }
  }

 private:
  int size_;
  std::vector<std::vector<double>> slots_;
  std::mutex mutex_;
  std::condition_variable ready_;
  int arrived_ = 0;
  long generation_ = 0;
};

class ThreadCommunicator final : public Communicator {
 public:
  ThreadCommunicator(ThreadHub& hub, int rank) : hub_(hub), rank_(rank) {}
  int rank() const override { return rank_; }
  int size() const override { return hub_.size(); }
  std::string name() const override { return "threads"; }

  void allreduce_sum(double* data, std::size_t count) override {
    hub_.slot(rank_).assign(data, data + count);
    hub_.barrier();
    for (std::size_t i = 0; i < count; ++i) {
      double total = hub_.slot(0)[i];
      for (int r = 1; r < size(); ++r) total += hub_.slot(r)[i];
      data[i] = total;
    }
    hub_.barrier();
  }
  std::vector<double> allgather(const double* data, std::size_t count,
                                std::vector<std::size_t>* counts = nullptr) override {
    hub_.slot(rank_).assign(data, data + count);
    hub_.barrier();
    std::vector<double> all;
    if (counts != nullptr) counts->clear();
    for (int r = 0; r < size(); ++r) {
      all.insert(all.end(), hub_.slot(r).begin(), hub_.slot(r).end());
      if (counts != nullptr) counts->push_back(hub_.slot(r).size());
    }
    hub_.barrier();
    return all;
  }
  void broadcast(double* data, std::size_t count, int root) override {
    if (rank_ == root) hub_.slot(root).assign(data, data + count);
    hub_.barrier();
    std::copy(hub_.slot(root).begin(), hub_.slot(root).begin() + static_cast<long>(count), data);
    hub_.barrier();
  }
  void abort(int /*exit_code*/) override { throw Error("ThreadCommunicator: abort"); }
  using Communicator::allreduce_sum;

 private:
  ThreadHub& hub_;
  int rank_;
};

}  // namespace physgrad::testing
