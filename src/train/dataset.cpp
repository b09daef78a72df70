#include "physgrad/train/dataset.hpp"

#include <numeric>
#include <random>
#include <sstream>
#include <string>

#include "physgrad/error.hpp"

namespace physgrad {

void Dataset::validate(const char* name) const {
  std::ostringstream msg;
  msg << name << ": ";
  if (inputs.cols() == 0) {
    msg << "has no samples";
  } else if (targets.cols() != inputs.cols()) {
    msg << inputs.cols() << " inputs but " << targets.cols() << " targets";
  } else if (context.size() != 0 && context.cols() != inputs.cols()) {
    msg << inputs.cols() << " inputs but " << context.cols() << " context columns";
  } else if (!all_finite(inputs) || !all_finite(targets) || !all_finite(context)) {
    msg << "contains NaN or Inf";
  } else {
    return;
  }
  throw Error(msg.str());
}

Dataset Dataset::select(const std::vector<Index>& indices) const {
  const auto pick = [&](const Matrix& m) {
    if (m.size() == 0) return Matrix();
    Matrix out(m.rows(), static_cast<Index>(indices.size()));
    for (std::size_t j = 0; j < indices.size(); ++j) out.col(static_cast<Index>(j)) = m.col(indices[j]);
    return out;
  };
  return {pick(inputs), pick(targets), pick(context)};
}

Dataset Dataset::columns(Index begin, Index count) const {
  if (begin < 0 || count < 0 || begin + count > size()) {
    throw Error("Dataset::columns: samples [" + std::to_string(begin) + ", " +
                std::to_string(begin + count) + ") of " + std::to_string(size()));
  }
  const auto part = [&](const Matrix& m) {
    return m.size() == 0 ? Matrix() : Matrix(m.middleCols(begin, count));
  };
  return {part(inputs), part(targets), part(context)};
}

std::vector<Index> shuffled_indices(Index n, std::uint64_t seed) {
  std::vector<Index> order(static_cast<std::size_t>(n));
  std::iota(order.begin(), order.end(), Index{0});
  std::mt19937_64 engine(seed);
  for (Index i = n - 1; i > 0; --i) {
    const auto j = static_cast<Index>(engine() % static_cast<std::uint64_t>(i + 1));
    std::swap(order[static_cast<std::size_t>(i)], order[static_cast<std::size_t>(j)]);
  }
  return order;
}

}  // namespace physgrad
