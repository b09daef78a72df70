// MeanMatchedNetwork: the output takes the input's mean, and every derivative member equals
// central differences of forward().
#include <gtest/gtest.h>

#include <memory>
#include <random>

#include "physgrad/autodiff/finite_difference.hpp"
#include "physgrad/error.hpp"
#include "physgrad/nn/mean_matched_network.hpp"
#include "physgrad/nn/mlp.hpp"

namespace physgrad {
namespace {

Matrix random_matrix(Index rows, Index cols, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  Matrix m(rows, cols);
  for (Index j = 0; j < cols; ++j) {
    for (Index i = 0; i < rows; ++i) m(i, j) = u(rng);
  }
  return m;
}

double max_relative(const Matrix& a, const Matrix& b) { return (a - b).norm() / b.norm(); }

MeanMatchedNetwork make_network() {
  auto inner = std::make_unique<Mlp>(std::vector<Index>{5, 7, 5}, Activation::kTanh);
  inner->initialize(3);
  return MeanMatchedNetwork(std::move(inner));
}

// θ ↦ vec(f(x; θ)), sample after sample.
Vector outputs_at(const Matrix& x, const Vector& theta) {
  MeanMatchedNetwork copy = make_network();
  copy.set_parameters(theta);
  return copy.forward(x).reshaped();
}

TEST(MeanMatchedNetwork, OutputMeanIsTheInputMean) {
  const MeanMatchedNetwork net = make_network();
  const Matrix x = random_matrix(5, 4, 1);
  const Matrix y = net.forward(x);
  EXPECT_LT((y.colwise().mean() - x.colwise().mean()).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_EQ(net.describe().at("output_mean"), "input");
  EXPECT_EQ(net.describe().at("kind"), "mlp");
}

TEST(MeanMatchedNetwork, DerivativesMatchFiniteDifferences) {
  const MeanMatchedNetwork net = make_network();
  const Matrix x = random_matrix(5, 3, 2);
  const Matrix gy = random_matrix(5, 3, 4);
  const auto cache = net.new_cache();
  net.forward(x, *cache);
  const auto f = [&](const Vector& theta) { return outputs_at(x, theta); };
  const Matrix fd = finite_difference_jacobian(f, net.parameters());  // (3·5) × |θ|

  // ∇θ Σ gy·f, the per-sample rows and J v, each against the same differences.
  const Vector gradient = net.backward(*cache, gy);
  EXPECT_LT(max_relative(gradient, fd.transpose() * gy.reshaped()), 1e-7);
  const Matrix rows = net.per_sample_gradients(*cache, gy);
  for (Index b = 0; b < 3; ++b) {
    const Vector expected = fd.middleRows(5 * b, 5).transpose() * gy.col(b);
    EXPECT_LT(max_relative(rows.row(b).transpose(), expected), 1e-7) << "sample " << b;
  }
  const Vector v = random_matrix(net.num_parameters(), 1, 5);
  EXPECT_LT(max_relative(net.jvp(*cache, 3, v).reshaped(), fd * v), 1e-7);
  // The Gram of the rows as the Jacobian rules form it (the Mlp's factored path, centred).
  const Matrix gram = net.per_sample_gram(*cache, {gy});
  EXPECT_LT(max_relative(gram, rows * rows.transpose()), 1e-12);
}

TEST(MeanMatchedNetwork, RefusesANetworkWhoseFieldsDiffer) {
  EXPECT_THROW(MeanMatchedNetwork(std::make_unique<Mlp>(std::vector<Index>{4, 3})), Error);
  EXPECT_THROW(MeanMatchedNetwork(nullptr), Error);
}

}  // namespace
}  // namespace physgrad
