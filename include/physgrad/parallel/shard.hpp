// Shard — this process's part of every mini-batch and data set when the ranks of a Communicator
// share the work (contiguous shares, share_of()), with the collectives they combine results by.
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

#include "physgrad/parallel/communicator.hpp"
#include "physgrad/types.hpp"

namespace physgrad {

// Columns [begin, begin + count) of a batch.
struct ColumnRange {
  Index begin = 0;
  Index count = 0;
};

// Default-constructed, or with a communicator of one rank, it is this process alone: the share
// is everything and the collectives return their input, so one code path serves both. Copies
// share the traffic counters.
class Shard {
 public:
  Shard() = default;
  explicit Shard(std::shared_ptr<Communicator> communicator);

  // True with more than one rank.
  bool active() const { return communicator_ != nullptr && communicator_->size() > 1; }
  int rank() const { return active() ? communicator_->rank() : 0; }
  int size() const { return active() ? communicator_->size() : 1; }
  const std::shared_ptr<Communicator>& communicator() const { return communicator_; }

  // This rank's columns of a batch of `count`.
  ColumnRange columns(Index count) const;

  // data[i] ← Σ over ranks (the same bits on every rank).
  void sum(double* data, std::size_t count) const;
  void sum(Vector& data) const { sum(data.data(), static_cast<std::size_t>(data.size())); }
  double sum(double value) const;
  // Every rank's rows × columns(batch).count block of each matrix in `local`, assembled into
  // rows × batch matrices in the one-process column order.
  std::vector<Matrix> gather_columns(const std::vector<Matrix>& local, Index rows,
                                     Index batch) const;
  // Throws Error unless every rank holds bit-identical `theta`.
  void check_identical(const Vector& theta) const;

  // Doubles this rank sent and received in collectives, and the seconds they took, so far.
  double exchanged_doubles() const { return traffic_->doubles; }
  double exchange_seconds() const { return traffic_->seconds; }

 private:
  struct Traffic {
    double doubles = 0;
    double seconds = 0;
  };
  std::shared_ptr<Communicator> communicator_;
  std::shared_ptr<Traffic> traffic_ = std::make_shared<Traffic>();
};

}  // namespace physgrad
