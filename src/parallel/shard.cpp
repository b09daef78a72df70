#include "physgrad/parallel/shard.hpp"

#include <chrono>

#include "physgrad/error.hpp"
#include "physgrad/timing.hpp"

namespace physgrad {

namespace {

using Clock = std::chrono::steady_clock;

ColumnRange range_of(Index count, int rank, int size) {
  const Share share = share_of(static_cast<std::size_t>(count), rank, size);
  return {static_cast<Index>(share.begin), static_cast<Index>(share.length)};
}

}  // namespace

Shard::Shard(std::shared_ptr<Communicator> communicator)
    : communicator_(std::move(communicator)) {}

ColumnRange Shard::columns(Index count) const { return range_of(count, rank(), size()); }

void Shard::sum(double* data, std::size_t count) const {
  if (!active()) return;
  const auto start = Clock::now();
  communicator_->allreduce_sum(data, count);
  traffic_->seconds += seconds_since(start);
  traffic_->doubles += static_cast<double>(count);
}

double Shard::sum(double value) const {
  sum(&value, 1);
  return value;
}

std::vector<Matrix> Shard::gather_columns(const std::vector<Matrix>& local, Index rows,
                                          Index batch) const {
  if (!active()) return local;
  std::vector<double> packed;
  for (const Matrix& m : local) packed.insert(packed.end(), m.data(), m.data() + m.size());
  const auto start = Clock::now();
  const std::vector<double> all = communicator_->allgather(packed.data(), packed.size());
  traffic_->seconds += seconds_since(start);
  traffic_->doubles += static_cast<double>(all.size());
  std::vector<Matrix> full(local.size(), Matrix(rows, batch));
  std::size_t at = 0;
  for (int r = 0; r < size(); ++r) {
    const ColumnRange part = range_of(batch, r, size());
    for (Matrix& m : full) {
      m.middleCols(part.begin, part.count) =
          Eigen::Map<const Matrix>(all.data() + at, rows, part.count);
      at += static_cast<std::size_t>(rows * part.count);
    }
  }
  return full;
}

void Shard::check_identical(const Vector& theta) const {
  if (!active()) return;
  const std::uint64_t hash = hash_doubles(theta.data(), static_cast<std::size_t>(theta.size()));
  if (!same_on_all_ranks(*communicator_, hash)) {
    throw Error("data-parallel training: the parameters differ between ranks");
  }
}

}  // namespace physgrad
