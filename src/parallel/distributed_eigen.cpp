#include "physgrad/parallel/distributed_eigen.hpp"

#include <atomic>
#include <string>

#include "physgrad/error.hpp"

namespace physgrad {

namespace {

std::atomic<Index> gram_rows{kDefaultDistributedGramRows};

}  // namespace

std::vector<Index> block_cyclic_columns(Index n, Index block, int rank, int size) {
  if (block < 1 || size < 1 || rank < 0 || rank >= size) {
    throw Error("block_cyclic_columns: block " + std::to_string(block) + ", rank " +
                std::to_string(rank) + " of " + std::to_string(size));
  }
  std::vector<Index> columns;
  for (Index start = block * rank; start < n; start += block * size) {
    for (Index c = start; c < std::min(start + block, n); ++c) columns.push_back(c);
  }
  return columns;
}

Vector distributed_truncated_power(DistributedEigensolver& solver, Matrix local, Index n,
                                   const Vector& g, const SpectralCut& cut,
                                   DistributedPowerInfo* info) {
  const auto columns =
      static_cast<Index>(block_cyclic_columns(n, solver.block(), solver.rank(), solver.size()).size());
  if (local.rows() != n || local.cols() != columns || g.size() != n) {
    throw Error("distributed truncated power: rank " + std::to_string(solver.rank()) + " holds " +
                std::to_string(local.rows()) + "×" + std::to_string(local.cols()) +
                " of an n = " + std::to_string(n) + " matrix (expected " + std::to_string(n) +
                "×" + std::to_string(columns) + ") and a vector of " + std::to_string(g.size()));
  }
  if (!all_finite(local) || !all_finite(g)) {
    throw NumericalError("distributed truncated power: non-finite entry in the matrix or the vector");
  }
  DistributedPowerInfo out;
  Vector x = solver.truncated_power(std::move(local), n, g, cut, &out);
  if (info != nullptr) *info = out;
  return x;
}

void set_distributed_gram_rows(Index rows) {
  if (rows < 0) {
    throw Error("distributed Gram rows must be ≥ 0 (0: never), got " + std::to_string(rows));
  }
  gram_rows = rows;
}

Index distributed_gram_rows() { return gram_rows; }

}  // namespace physgrad
