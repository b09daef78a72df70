// The derivatives the structured HIG rules use, against finite differences: the network's jvp
// (∂f/∂θ·v, Mlp's forward mode and the default through the gradient rows), J w of the stacked
// Jacobian, and the Kronecker factors Σ āāᵀ, Σ δδᵀ of each dense layer (δ = ∂y/∂b by differences).
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "learning_fixture.hpp"
#include "physgrad/autodiff/finite_difference.hpp"
#include "physgrad/error.hpp"
#include "physgrad/learn/mapped_jacobian.hpp"
#include "physgrad/nn/checked_network.hpp"

namespace physgrad {
namespace {

using testing::NetworkThroughPhysics;

// A 3 → 5 → 4 → 2 network with smooth activations and nonzero biases.
Mlp curvature_network(Activation hidden) {
  Mlp network({3, 5, 4, 2}, hidden, Activation::kSoftplus);
  network.initialize(11);
  network.parameters() += 0.1 * Vector::LinSpaced(network.num_parameters(), -1.0, 1.0);
  return network;
}

Matrix curvature_inputs() {
  Matrix x(3, 6);
  for (Index j = 0; j < x.cols(); ++j) {
    const auto t = static_cast<double>(j);
    x.col(j) << std::sin(t), std::cos(1.7 * t), 0.3 * t - 0.8;
  }
  return x;
}

// An Mlp seen only through the members a Network must have: jvp is the Network default
// (gradient rows per output), and it has no layer factors.
class RowsOnlyNetwork : public Network {
 public:
  explicit RowsOnlyNetwork(Mlp inner) : inner_(std::move(inner)) {}
  Index input_dim() const override { return inner_.input_dim(); }
  Index output_dim() const override { return inner_.output_dim(); }
  Index num_parameters() const override { return inner_.num_parameters(); }
  const Vector& parameters() const override { return inner_.parameters(); }
  Vector& parameters() override { return inner_.parameters(); }
  std::unique_ptr<NetworkCache> new_cache() const override { return inner_.new_cache(); }
  Matrix forward(const Matrix& x, NetworkCache& cache) const override {
    return inner_.forward(x, cache);
  }
  Vector backward(const NetworkCache& cache, const Matrix& gy) const override {
    return inner_.backward(cache, gy);
  }
  void per_sample_gradients(const NetworkCache& cache, const Matrix& gy,
                            StridedMatrixRef out) const override {
    inner_.per_sample_gradients(cache, gy, out);
  }

 protected:
  Mlp inner_;
};

TEST(NetworkJvp, MatchesFiniteDifferencesOfTheForwardPass) {
  for (const Activation hidden : {Activation::kTanh, Activation::kSigmoid}) {
    const Mlp network = curvature_network(hidden);
    const Matrix x = curvature_inputs();
    MlpCache cache;
    network.forward(x, cache);
    const Vector v = Vector::LinSpaced(network.num_parameters(), 0.5, -1.5);
    const Matrix tangent = network.jvp(cache, x.cols(), v);
    // f(θ + hv) by central differences in h.
    const Matrix expected =
        finite_difference_jacobian(
            [&](const Vector& h) {
              Mlp moved = network;
              moved.parameters() += h(0) * v;
              return Vector(moved.forward(x).reshaped());
            },
            Vector::Zero(1))
            .reshaped(network.output_dim(), x.cols());
    EXPECT_LT((tangent - expected).cwiseAbs().maxCoeff(), 1e-8) << to_string(hidden);
    // The default through the gradient rows gives the same numbers.
    const RowsOnlyNetwork rows(network);
    EXPECT_LT((rows.jvp(cache, x.cols(), v) - tangent).cwiseAbs().maxCoeff(),
              1e-14 * tangent.cwiseAbs().maxCoeff());
  }
}

TEST(NetworkJvp, WrongSizesAreErrors) {
  const Mlp network = curvature_network(Activation::kTanh);
  MlpCache cache;
  network.forward(curvature_inputs(), cache);
  EXPECT_THROW(network.jvp(cache, 6, Vector::Zero(3)), Error);
  EXPECT_THROW(network.jvp(cache, 5, Vector::Zero(network.num_parameters())), Error);
  const RowsOnlyNetwork rows(network);
  EXPECT_THROW(rows.jvp(cache, 6, Vector::Zero(3)), Error);
  // Only a network that knows its layers gives their factors.
  EXPECT_THROW(rows.dense_layer_factors(cache, {}), Error);
}

// J w of the stacked Jacobian: central differences of the stacked outputs along w, the formed J
// times w, and ⟨J w, c⟩ = ⟨w, Jᵀc⟩.
TEST(StackedJacobianApply, MatchesFiniteDifferencesAndTheTranspose) {
  const NetworkThroughPhysics s(7);
  MlpCache cache;
  const BatchState state = s.evaluate(UpdateNeed::kStackedJacobian, cache);
  const StackedJacobian& j = *state.jacobian;
  const Vector w = Vector::LinSpaced(j.cols(), -1.0, 0.7);
  const Vector jw = j.apply(w);
  const Vector expected = finite_difference_jacobian(
      [&](const Vector& h) { return s.stacked_outputs(s.network.parameters() + h(0) * w); },
      Vector::Zero(1));
  EXPECT_LT((jw - expected).cwiseAbs().maxCoeff(), 1e-7);
  const Matrix formed = j.materialize();
  EXPECT_LT((jw - formed * w).norm(), 1e-13 * jw.norm());
  const Vector c = Vector::LinSpaced(j.rows(), 2.0, -1.0);
  EXPECT_NEAR(jw.dot(c), w.dot(j.apply_transpose(c)), 1e-13 * std::abs(jw.dot(c)));
  EXPECT_THROW(j.apply(Vector::Zero(3)), Error);
  // A formed J applies itself; it knows no layers.
  const Matrix row_major = formed.transpose();  // J stored row after row
  const MappedJacobian mapped(row_major.data(), j.batch(), j.outputs(), j.cols());
  EXPECT_LT((mapped.apply(w) - jw).norm(), 1e-13 * jw.norm());
  EXPECT_THROW(mapped.dense_layer_factors(), Error);
  EXPECT_LT((DenseJacobian(formed).apply(w) - jw).norm(), 1e-13 * jw.norm());
}

// Each layer's factors: Σ ā āᵀ from its inputs, and Σ over the rows of J of δ δᵀ with δ = ∂y/∂b
// (the bias gradient of the row) by central differences in the layer's biases.
TEST(DenseLayerFactors, AreTheInputsGramAndTheBiasDerivativesGram) {
  const NetworkThroughPhysics s(5);
  MlpCache cache;
  const BatchState state = s.evaluate(UpdateNeed::kStackedJacobian, cache);
  const std::vector<DenseLayerFactors> factors = state.jacobian->dense_layer_factors();
  ASSERT_EQ(factors.size(), 2U);
  Index next = 0;
  for (std::size_t l = 0; l < factors.size(); ++l) {
    const DenseLayerFactors& f = factors[l];
    const auto layer = static_cast<Index>(l);
    EXPECT_EQ(f.offset, next);
    EXPECT_EQ(f.outputs, s.network.widths()[l + 1]);
    EXPECT_EQ(f.inputs, s.network.widths()[l]);
    next += f.outputs * (f.inputs + 1);
    // ā = [a; 1] of every sample.
    Matrix extended = Matrix::Ones(f.inputs + 1, s.data.size());
    extended.topRows(f.inputs) = cache.activations[l];
    const Matrix a = extended * extended.transpose();
    EXPECT_LT((f.input_gram - a).cwiseAbs().maxCoeff(), 1e-13 * a.cwiseAbs().maxCoeff());
    // δ of every row: ∂y_r/∂b by differences; the bias sits after vec(W).
    const Index bias = f.offset + f.outputs * f.inputs;
    const Matrix deltas = finite_difference_jacobian(
        [&](const Vector& b) {
          Vector theta = s.network.parameters();
          theta.segment(bias, f.outputs) += b;
          return s.stacked_outputs(theta);
        },
        Vector::Zero(f.outputs));  // rows × outputs
    const Matrix expected = deltas.transpose() * deltas;
    EXPECT_LT((f.cotangent_gram - expected).cwiseAbs().maxCoeff(),
              1e-7 * expected.cwiseAbs().maxCoeff())
        << "layer " << layer;
  }
  EXPECT_EQ(next, s.network.num_parameters());
}

// A network whose layers lie outside θ, or whose jvp has the wrong shape, is named.
class MisplacedLayers final : public RowsOnlyNetwork {
 public:
  using RowsOnlyNetwork::RowsOnlyNetwork;
  Matrix jvp(const NetworkCache& cache, Index batch, const Vector& v) const override {
    return inner_.jvp(cache, batch, v).leftCols(batch - 1);
  }
  std::vector<DenseLayerFactors> dense_layer_factors(
      const NetworkCache& cache, const std::vector<Matrix>& cotangents) const override {
    std::vector<DenseLayerFactors> layers = inner_.dense_layer_factors(cache, cotangents);
    layers.back().offset += 1;
    return layers;
  }
};

TEST(CheckedNetwork, NamesAWrongJvpAndLayersOutsideTheParameters) {
  const MisplacedLayers lying(curvature_network(Activation::kTanh));
  const CheckedNetwork checked(lying);
  const Matrix x = curvature_inputs();
  MlpCache cache;
  checked.forward(x, cache);
  try {
    checked.jvp(cache, x.cols(), Vector::Zero(checked.num_parameters()));
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("jvp returned 2×5"), std::string::npos) << e.what();
  }
  try {
    checked.dense_layer_factors(cache, {Matrix::Ones(2, x.cols())});
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("outside the"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace physgrad
