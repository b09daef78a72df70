// Dataset — N samples of (network input, target y*, optional physics context c), one sample
// per column; the learning problem is min_θ mean_i L(P(f(inᵢ; θ); cᵢ), yᵢ*).
#pragma once

#include <cstdint>
#include <vector>

#include "physgrad/types.hpp"

namespace physgrad {

struct Dataset {
  Matrix inputs;   // d_in × N
  Matrix targets;  // m × N
  Matrix context;  // k × N, or empty when the physics needs none

  Index size() const { return inputs.cols(); }
  // Throws Error naming the mismatch: column counts differ, N = 0, or a non-finite entry.
  void validate(const char* name) const;
  // The samples at `indices`, in that order.
  Dataset select(const std::vector<Index>& indices) const;
  // The samples begin … begin + count − 1.
  Dataset columns(Index begin, Index count) const;
};

// A deterministic permutation of 0..n−1 for a seed (Fisher-Yates on std::mt19937_64, the same
// on every platform).
std::vector<Index> shuffled_indices(Index n, std::uint64_t seed);

}  // namespace physgrad
