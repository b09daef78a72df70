// The stacked Jacobian of network + physics: J, J Jᵀ, Jᵀc and JᵀJ from evaluate_batch() against
// finite differences and each other, the Gram matrix of a network from its layer factors
// (DenseLayerGram) against the formed gradient rows, and the physics VJPs on several threads.
#include <gtest/gtest.h>

#include <cmath>
#include <utility>

#include "learning_fixture.hpp"
#include "physgrad/autodiff/dual.hpp"
#include "physgrad/autodiff/finite_difference.hpp"
#include "physgrad/physics/checked_simulator.hpp"
#include "physgrad/error.hpp"
#include "physgrad/nn/dense_layer_gram.hpp"
#include "physgrad/parallel/distributed_eigen.hpp"
#include "physgrad/threads.hpp"

namespace physgrad {
namespace {

using testing::NetworkThroughPhysics;

TEST(StackedJacobian, MatchesFiniteDifferences) {
  const NetworkThroughPhysics s;
  MlpCache cache;
  const BatchState state = s.evaluate(UpdateNeed::kStackedJacobian, cache);
  const Matrix expected = finite_difference_jacobian(
      [&](const Vector& theta) { return s.stacked_outputs(theta); }, s.network.parameters());
  const Matrix j = state.jacobian->materialize();
  ASSERT_EQ(j.rows(), 2 * s.data.size());
  ASSERT_EQ(state.jacobian->rows(), j.rows());
  EXPECT_LT((j - expected).cwiseAbs().maxCoeff(), 1e-7);
}

// J Jᵀ from the layer factors, Jᵀc by one backward and JᵀJ, Jᵀg agree with the formed J.
TEST(StackedJacobian, EveryFormAgreesWithTheFormedJacobian) {
  const NetworkThroughPhysics s(7);
  MlpCache cache;
  const BatchState state = s.evaluate(UpdateNeed::kStackedJacobian, cache);
  const StackedJacobian& jacobian = *state.jacobian;
  const Matrix j = jacobian.materialize();
  const Matrix gram = j * j.transpose();
  EXPECT_LT((jacobian.gram() - gram).cwiseAbs().maxCoeff(), 1e-13 * gram.cwiseAbs().maxCoeff());
  const Vector c = Vector::LinSpaced(j.rows(), -1.0, 2.0);
  EXPECT_LT((jacobian.apply_transpose(c) - j.transpose() * c).norm(),
            1e-13 * (j.transpose() * c).norm());
  const StackedJacobian::Normal normal = jacobian.normal(c);
  const Matrix expected = j.transpose() * j;
  EXPECT_LT((Matrix(normal.matrix.triangularView<Eigen::Lower>()) -
             Matrix(expected.triangularView<Eigen::Lower>()))
                .cwiseAbs()
                .maxCoeff(),
            1e-13 * expected.cwiseAbs().maxCoeff());
  EXPECT_LT((normal.rhs - j.transpose() * c).norm(), 1e-13 * normal.rhs.norm());
}

// The physics VJPs on several threads give bit-identical results: each output's VJP is
// computed by one thread into its own matrix.
TEST(StackedJacobian, IsTheSameOnAnyNumberOfThreads) {
  const NetworkThroughPhysics s(9);
  const auto gram_and_transpose = [&](int threads) {
    set_jacobian_threads(threads);
    MlpCache cache;
    const BatchState state = s.evaluate(UpdateNeed::kStackedJacobian, cache);
    const Vector c = Vector::LinSpaced(state.jacobian->rows(), -1.0, 2.0);
    return std::make_pair(state.jacobian->gram(), state.jacobian->apply_transpose(c));
  };
  const auto one = gram_and_transpose(1);
  for (const int threads : {2, 3}) {
    const auto many = gram_and_transpose(threads);
    EXPECT_TRUE(many.first == one.first) << threads << " threads";
    EXPECT_TRUE(many.second == one.second) << threads << " threads";
  }
  set_jacobian_threads(1);
  EXPECT_GT(one.first.norm(), 0.0);
}

// x ↦ (x₀x₁, sin x₀ + x₁², e^{x₁}): a simulator whose jacobian() is its own (forward duals).
struct ThreeOutputs {
  template <typename T>
  Eigen::Matrix<T, Eigen::Dynamic, 1> operator()(const Eigen::Matrix<T, Eigen::Dynamic, 1>& x,
                                                 const Vector& /*context*/) const {
    using std::exp;
    using std::sin;
    Eigen::Matrix<T, Eigen::Dynamic, 1> y(3);
    y << x(0) * x(1), sin(x(0)) + x(1) * x(1), exp(x(1));
    return y;
  }
};

// The same simulator without has_jacobian(): the stacked Jacobian then makes m VJPs.
class ThroughVjps final : public AutoDiffSimulator<ThreeOutputs> {
 public:
  using AutoDiffSimulator::AutoDiffSimulator;
  bool has_jacobian() const override { return false; }
};

// With has_jacobian() the stacked Jacobian asks jacobian() once per sample and makes no VJP at
// all (Jᵀc comes from the stored cotangents); J, J Jᵀ and Jᵀc equal those through the m VJPs
// and J matches finite differences of the stacked outputs.
TEST(StackedJacobian, ThroughTheSimulatorsJacobianEqualsTheOneThroughVjps) {
  const AutoDiffSimulator<ThreeOutputs> own(ThreeOutputs{}, "three_outputs", 2, 3);
  const ThroughVjps vjps(ThreeOutputs{}, "three_outputs", 2, 3);
  ASSERT_TRUE(own.has_jacobian());
  ASSERT_FALSE(vjps.has_jacobian());
  Mlp network({2, 5, 2}, Activation::kTanh);
  network.initialize(4);
  const Matrix inputs{{0.3, -0.2, 0.5, 0.1}, {0.7, 0.4, -0.6, -0.1}};
  MlpCache cache;
  const Matrix x = network.forward(inputs, cache);
  const CheckedSimulator checked(own);
  const LocalJacobian through_jacobian(network, cache, checked, x, Matrix());
  const SimulatorCounts counts = checked.counts();
  EXPECT_EQ(counts.jacobians, inputs.cols());
  EXPECT_EQ(counts.vjp, 0);
  const LocalJacobian through_vjps(network, cache, vjps, x, Matrix());

  const Matrix j = through_jacobian.materialize();
  const Matrix reference = through_vjps.materialize();
  ASSERT_EQ(j.rows(), 3 * inputs.cols());
  EXPECT_LT((j - reference).cwiseAbs().maxCoeff(), 1e-12 * reference.cwiseAbs().maxCoeff());
  EXPECT_LT((through_jacobian.gram() - through_vjps.gram()).cwiseAbs().maxCoeff(),
            1e-12 * through_vjps.gram().cwiseAbs().maxCoeff());
  const Vector c = Vector::LinSpaced(j.rows(), -1.0, 2.0);
  EXPECT_LT((through_jacobian.apply_transpose(c) - through_vjps.apply_transpose(c)).norm(),
            1e-12 * through_vjps.apply_transpose(c).norm());
  EXPECT_EQ(checked.counts(), counts);  // Jᵀc made no simulator call

  const Matrix expected = finite_difference_jacobian(
      [&](const Vector& theta) {
        Mlp copy = network;
        copy.set_parameters(theta);
        return Vector(own.forward_batch(copy.forward(inputs), Matrix()).transpose().reshaped());
      },
      network.parameters());
  EXPECT_LT((j - expected).cwiseAbs().maxCoeff(), 1e-7);
  EXPECT_LT((reference - expected).cwiseAbs().maxCoeff(), 1e-7);
}

// A LocalJacobian given the output cotangents (as data-parallel runs gather them) is the one
// that computes them, bit for bit.
TEST(StackedJacobian, FromGivenCotangentsIsTheComputedOne) {
  const NetworkThroughPhysics s(12);
  MlpCache cache;
  const Matrix x = s.network.forward(s.data.inputs, cache);
  const LocalJacobian computed(s.network, cache, s.physics, x, Matrix());
  const std::vector<Matrix> cotangents = output_cotangents(s.physics, x, Matrix());
  const LocalJacobian given(s.network, cache, s.physics, x, cotangents);
  EXPECT_EQ(given.materialize(), computed.materialize());
  EXPECT_EQ(given.gram(), computed.gram());
  EXPECT_THROW(LocalJacobian(s.network, cache, s.physics, x, std::vector<Matrix>{cotangents[0]}),
               Error);
  EXPECT_THROW(LocalJacobian(s.network, cache, s.physics, x,
                             std::vector<Matrix>{cotangents[0], Matrix::Zero(2, 3)}),
               Error);
}

TEST(EvaluateBatch, GradientMatchesFiniteDifferencesAndTheJacobianPath) {
  const NetworkThroughPhysics s;
  MlpCache cache;
  const BatchState with_gradient = s.evaluate(UpdateNeed::kGradient, cache);
  const auto mean = [&](const Vector& theta) {
    Mlp copy = s.network;
    copy.set_parameters(theta);
    return Vector::Constant(1, mean_loss(copy, s.problem, s.data));
  };
  const Matrix expected = finite_difference_jacobian(mean, s.network.parameters());
  EXPECT_LT((with_gradient.gradient - expected.row(0).transpose()).cwiseAbs().maxCoeff(), 1e-8);
  EXPECT_NEAR(with_gradient.loss, mean(s.network.parameters())(0), 1e-14);
  // Jᵀ ∂(mean L)/∂y is the same gradient.
  const BatchState with_jacobian = s.evaluate(UpdateNeed::kStackedJacobian, cache);
  EXPECT_LT((with_jacobian.jacobian->materialize().transpose() * with_jacobian.loss_gradient_y -
             with_gradient.gradient)
                .norm(),
            1e-12);
}

// A 3-5-4-2 tanh network on 6 samples with 3 random cotangents per sample (18 Gram columns).
struct SmallGram {
  explicit SmallGram(unsigned seed) : network({3, 5, 4, 2}, Activation::kTanh) {
    network.initialize(seed);
    network.forward(Matrix::Random(3, 6), cache);
    cotangents = {Matrix::Random(2, 6), Matrix::Random(2, 6), Matrix::Random(2, 6)};
  }
  Mlp network;
  MlpCache cache;
  std::vector<Matrix> cotangents;
};

// Mlp's per_sample_gram() (layer factors, DenseLayerGram) equals the Network default, which forms
// the gradient rows, for several cotangents per sample.
TEST(DenseLayerGram, MlpGramFromLayerFactorsEqualsTheFormedRows) {
  SmallGram s(11);
  const Mlp& network = s.network;
  const MlpCache& cache = s.cache;
  const std::vector<Matrix>& cotangents = s.cotangents;
  const Matrix factored = network.per_sample_gram(cache, cotangents);
  const Matrix formed = network.Network::per_sample_gram(cache, cotangents);
  ASSERT_EQ(factored.rows(), 18);
  EXPECT_LT((factored - formed).cwiseAbs().maxCoeff(), 1e-13 * formed.cwiseAbs().maxCoeff());
  EXPECT_TRUE(factored.isApprox(factored.transpose(), 0.0));  // exactly symmetric
  EXPECT_THROW(network.per_sample_gram(cache, {Matrix::Random(2, 5)}), Error);
  EXPECT_EQ(network.per_sample_gram(cache, {}).size(), 0);
}

// Selected columns of the Gram matrix (a rank's block-cyclic share) equal those columns of the
// whole one, for Mlp's layer factors and for the Network default.
TEST(DenseLayerGram, SelectedColumnsEqualThoseOfTheWholeMatrix) {
  SmallGram s(12);
  const Matrix whole = s.network.per_sample_gram(s.cache, s.cotangents);
  for (int rank = 0; rank < 3; ++rank) {
    const std::vector<Index> columns = block_cyclic_columns(18, 4, rank, 3);
    const Matrix factored = s.network.per_sample_gram_columns(s.cache, s.cotangents, columns);
    const Matrix formed =
        s.network.Network::per_sample_gram_columns(s.cache, s.cotangents, columns);
    ASSERT_EQ(factored.cols(), static_cast<Index>(columns.size()));
    for (std::size_t i = 0; i < columns.size(); ++i) {
      EXPECT_LT((factored.col(Index(i)) - whole.col(columns[i])).cwiseAbs().maxCoeff(), 1e-13);
      EXPECT_LT((formed.col(Index(i)) - whole.col(columns[i])).cwiseAbs().maxCoeff(), 1e-13);
    }
  }
  EXPECT_THROW(s.network.per_sample_gram_columns(s.cache, s.cotangents, {18}), Error);
  EXPECT_THROW(s.network.Network::per_sample_gram_columns(s.cache, s.cotangents, {-1}), Error);
}

// 1 × K block-cyclic layout: blocks of b columns dealt to the ranks in turn, every column once.
TEST(DenseLayerGram, BlockCyclicColumnsDealBlocksInTurn) {
  EXPECT_EQ(block_cyclic_columns(10, 2, 0, 3), (std::vector<Index>{0, 1, 6, 7}));
  EXPECT_EQ(block_cyclic_columns(10, 2, 1, 3), (std::vector<Index>{2, 3, 8, 9}));
  EXPECT_EQ(block_cyclic_columns(10, 2, 2, 3), (std::vector<Index>{4, 5}));
  EXPECT_TRUE(block_cyclic_columns(3, 4, 1, 2).empty());
  EXPECT_THROW(block_cyclic_columns(3, 0, 0, 1), Error);
  EXPECT_THROW(block_cyclic_columns(3, 1, 2, 2), Error);
}

TEST(DenseLayerGram, RejectsShapesThatDoNotFitAndASecondFinish) {
  EXPECT_THROW(DenseLayerGram(7, 3), Error);
  DenseLayerGram gram(6, 3);
  EXPECT_THROW(gram.add(Matrix::Zero(2, 5), Matrix::Zero(4, 3)), Error);
  EXPECT_THROW(gram.add(Matrix::Zero(2, 6), Matrix::Zero(4, 2)), Error);
  gram.add(Matrix::Ones(2, 6), Matrix::Zero(4, 3), false);
  EXPECT_EQ(gram.finish(), Matrix::Zero(6, 6));  // inputs 0 and no bias: nothing
  EXPECT_THROW(gram.finish(), Error);
}

}  // namespace
}  // namespace physgrad
