#include "physgrad/parallel/distributed_eigen.hpp"

#include <atomic>
#include <cmath>
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

Vector distributed_power_part(DistributedEigensolver& solver, Matrix local, Index n,
                              const Vector& g, double kappa, double rcond,
                              DistributedPowerInfo* info) {
  if (!all_finite(local) || !all_finite(g)) {
    throw NumericalError("distributed_power_part: non-finite entry in the matrix or the vector");
  }
  const Vector lambda = solver.decompose(local, n);
  const Vector sigma = lambda.cwiseMax(0.0).cwiseSqrt();  // rounding can leave λ slightly < 0
  DistributedPowerInfo out;
  out.sigma_max = n > 0 ? sigma(n - 1) : 0.0;
  out.kept = (sigma.array() > rcond * out.sigma_max).count();
  out.sigma_min_kept = out.kept > 0 ? sigma(n - out.kept) : 0.0;
  // Kept pairs are the trailing indices (ascending eigenvalues).
  const std::vector<Index> columns =
      block_cyclic_columns(n, solver.block(), solver.rank(), solver.size());
  Vector part = Vector::Zero(n);
  for (std::size_t s = 0; s < columns.size(); ++s) {
    const Index i = columns[s];
    if (i < n - out.kept) continue;
    const auto u = local.col(static_cast<Index>(s));
    part += u * (u.dot(g) * std::pow(sigma(i), -1 - kappa));
  }
  if (info != nullptr) *info = out;
  return part;
}

void set_distributed_gram_rows(Index rows) {
  if (rows < 0) {
    throw Error("distributed Gram rows must be ≥ 0 (0: never), got " + std::to_string(rows));
  }
  gram_rows = rows;
}

Index distributed_gram_rows() { return gram_rows; }

}  // namespace physgrad
