// The structured rules on ConvNetwork: its Kronecker factors (KFC) against a sum over every
// sample and output position written out cell by cell, kfac/kfac-hig against the exact step where
// the factorisation is exact (one output position, identity physics), Lanczos against the exact
// step with as many products as J has rows, and both kinds of rule lowering a small U-net's loss.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "physgrad/catalogue.hpp"
#include "physgrad/error.hpp"
#include "physgrad/nn/conv_net.hpp"
#include "physgrad/physics/diagonal_scale.hpp"
#include "physgrad/train/trainer.hpp"

namespace physgrad {
namespace {

Matrix factor_test_uniform(Index rows, Index cols, std::uint64_t seed) {
  std::mt19937_64 engine(seed);
  Matrix m(rows, cols);
  for (double& v : m.reshaped()) v = 2 * static_cast<double>(engine() >> 11) * 0x1p-53 - 1;
  return m;
}

double factor_test_difference(const Matrix& a, const Matrix& b) {
  return (a - b).norm() / b.norm();
}

// 2-D grid of n × n cells, 3×3 taps with zero padding, stride 1: the input cell that output cell
// (oi, oj) reads at tap t = ti + 3·tj, or −1 outside the grid.
Index factor_test_read(Index n, Index oi, Index oj, Index t) {
  const Index i = oi + t % 3 - 1, j = oj + t / 3 - 1;
  return (i < 0 || j < 0 || i >= n || j >= n) ? -1 : i + n * j;
}

// Σ_b Σ_p ā ā ᵀ of a 3×3 conv on `values` (channels·n² × B), ā = [patch; 1], patch entry c·9 + t.
Matrix brute_input_gram(const Matrix& values, Index channels, Index n) {
  const Index fan_in = 9 * channels;
  Matrix gram = Matrix::Zero(fan_in + 1, fan_in + 1);
  for (Index b = 0; b < values.cols(); ++b) {
    for (Index o = 0; o < n * n; ++o) {
      Vector a = Vector::Zero(fan_in + 1);
      for (Index c = 0; c < channels; ++c) {
        for (Index t = 0; t < 9; ++t) {
          const Index cell = factor_test_read(n, o % n, o / n, t);
          if (cell >= 0) a(c * 9 + t) = values(c * n * n + cell, b);
        }
      }
      a(fan_in) = 1;
      gram += a * a.transpose();
    }
  }
  return gram;
}

// (1/P) Σ_b Σ_p δ δᵀ of the cotangents (channels·n² × B, channel c at row c·n² + cell).
Matrix brute_cotangent_gram(const Matrix& deltas, Index channels, Index n) {
  Matrix gram = Matrix::Zero(channels, channels);
  for (Index b = 0; b < deltas.cols(); ++b) {
    for (Index o = 0; o < n * n; ++o) {
      Vector d(channels);
      for (Index c = 0; c < channels; ++c) d(c) = deltas(c * n * n + o, b);
      gram += d * d.transpose();
    }
  }
  return gram / static_cast<double>(n * n);
}

// The cotangent at the first conv's output z₁ of conv₂(tanh(z₁)) for the cotangent gy at the
// output: the adjoint of conv₂ written out tap by tap, times tanh′(z₁).
Matrix brute_first_deltas(const Matrix& z1, const Matrix& w2, const Matrix& gy, Index hidden,
                          Index outputs, Index n) {
  const Index cells = n * n;
  Matrix d = Matrix::Zero(hidden * cells, gy.cols());
  for (Index b = 0; b < gy.cols(); ++b) {
    for (Index o = 0; o < cells; ++o) {
      for (Index t = 0; t < 9; ++t) {
        const Index cell = factor_test_read(n, o % n, o / n, t);
        if (cell < 0) continue;
        for (Index c = 0; c < hidden; ++c) {
          for (Index k = 0; k < outputs; ++k) {
            d(c * cells + cell, b) += w2(c * 9 + t, k) * gy(k * cells + o, b);
          }
        }
      }
    }
  }
  return d.array() * (1 - z1.array().tanh().square());
}

TEST(ConvFactors, EqualASumOverEveryPositionOfEverySample) {
  constexpr Index kN = 4, kIn = 2, kHidden = 3, kOut = 2, kBatch = 3;
  auto net = ConvNetwork::conv_stack(2, kN, {kIn, kHidden, kOut}, 3, Activation::kTanh);
  net.initialize(5);
  const Matrix x = factor_test_uniform(net.input_dim(), kBatch, 1);
  const std::vector<Matrix> cotangents = {factor_test_uniform(net.output_dim(), kBatch, 2),
                                          factor_test_uniform(net.output_dim(), kBatch, 3)};
  auto cache = net.new_cache();
  net.forward(x, *cache);
  const auto& values = dynamic_cast<const ConvNetworkCache&>(*cache).values;
  const std::vector<DenseLayerFactors> factors = net.dense_layer_factors(*cache, cotangents);
  ASSERT_EQ(factors.size(), 2u);
  const std::vector<ConvOp>& ops = net.ops();  // conv, tanh, conv
  const Matrix w2 = Eigen::Map<const Matrix>(net.parameters().data() + ops[2].offset,
                                             9 * kHidden, kOut);
  Matrix s1 = Matrix::Zero(kHidden, kHidden), s2 = Matrix::Zero(kOut, kOut);
  for (const Matrix& gy : cotangents) {
    s1 += brute_cotangent_gram(brute_first_deltas(values[1], w2, gy, kHidden, kOut, kN),
                               kHidden, kN);
    s2 += brute_cotangent_gram(gy, kOut, kN);
  }
  const Matrix a1 = brute_input_gram(values[0], kIn, kN);
  const Matrix a2 = brute_input_gram(values[2], kHidden, kN);
  const Index layer_in[2] = {9 * kIn, 9 * kHidden}, layer_out[2] = {kHidden, kOut};
  const Index offsets[2] = {ops[0].offset, ops[2].offset};
  for (std::size_t l = 0; l < 2; ++l) {
    EXPECT_EQ(factors[l].offset, offsets[l]);
    EXPECT_EQ(factors[l].inputs, layer_in[l]);
    EXPECT_EQ(factors[l].outputs, layer_out[l]);
    EXPECT_TRUE(factors[l].transposed);
  }
  EXPECT_LT(factor_test_difference(factors[0].input_gram, a1), 1e-13);
  EXPECT_LT(factor_test_difference(factors[1].input_gram, a2), 1e-13);
  EXPECT_LT(factor_test_difference(factors[0].cotangent_gram, s1), 1e-12);
  EXPECT_LT(factor_test_difference(factors[1].cotangent_gram, s2), 1e-13);
  // Split over two threads the sums only change order.
  set_conv_threads(2);
  const std::vector<DenseLayerFactors> split = net.dense_layer_factors(*cache, cotangents);
  set_conv_threads(1);
  EXPECT_LT(factor_test_difference(split[0].input_gram, a1), 1e-13);
  EXPECT_LT(factor_test_difference(split[0].cotangent_gram, s1), 1e-12);
  // A cotangent of the wrong shape is named.
  EXPECT_THROW(net.dense_layer_factors(*cache, {Matrix::Zero(net.output_dim(), kBatch + 1)}),
               Error);
}

// One 3-tap conv (4 → 3 channels) with identity physics on a line of `n` cells. With n = 1 there
// is one output position, so the layer is a dense layer of the 12 patch entries (8 of them the
// zero padding). With more cells the cotangent of output (p, c) is e_c at position p alone, so
// JᵀJ = Σ_{i,p} ā_ip ā_ipᵀ ⊗ I = A ⊗ S with KFC's A = (1/B) Σ_{i,p} āāᵀ and S = (1/P)·B·P·I:
// the factorisation is exact too, and the 1/P of S is what makes it so.
struct SingleConvLayer {
  DiagonalScale physics;
  L2Loss loss{1.0};
  LearningProblem problem{&physics, &loss};
  ConvNetwork network;
  Dataset data;

  SingleConvLayer(Index n, Index batch)
      : physics(Vector::Ones(3 * n)),
        network(ConvNetwork::conv_stack(1, n, {4, 3}, 3, Activation::kIdentity)) {
    network.initialize(2);
    data.inputs = factor_test_uniform(4 * n, batch, 5);
    data.targets = factor_test_uniform(3 * n, batch, 6);
  }
};

TEST(ConvFactors, KfacIsTheExactStepOnOneConvLayerWithIdentityPhysics) {
  for (const auto& [n, batch] : std::vector<std::pair<Index, Index>>{{1, 3}, {1, 8}, {5, 2}}) {
    const SingleConvLayer s(n, batch);
    auto cache = s.network.new_cache();
    const BatchState state =
        evaluate_batch(s.network, s.problem, s.data, UpdateNeed::kStackedJacobian, *cache);
    for (const double kappa : {0.5, 1.0}) {
      HigUpdate exact({.lr = 0.7, .cut = {.kappa = kappa, .rcond = 1e-6}});
      KroneckerHigUpdate kronecker({.lr = 0.7, .cut = {.kappa = kappa, .rcond = 1e-6, .damping = 0}});
      const Vector expected = exact.step(state).delta;
      EXPECT_LT(factor_test_difference(kronecker.step(state).delta, expected), 1e-10)
          << "n " << n << ", batch " << batch << ", κ " << kappa;
      KroneckerHigUpdate damped({.lr = 0.7, .cut = {.kappa = kappa, .rcond = 1e-6, .damping = 0.1}});
      EXPECT_GT(factor_test_difference(damped.step(state).delta, expected), 1e-3);
    }
  }
}

// The checkpoint state keeps each conv layer's layout: a rule restored from it makes the same
// next step (between refreshes, from the saved factors) as the one that saved it.
TEST(ConvFactors, KfacStateKeepsTheConvLayerLayout) {
  const SingleConvLayer s(5, 3);
  auto cache = s.network.new_cache();
  const BatchState jacobian =
      evaluate_batch(s.network, s.problem, s.data, UpdateNeed::kStackedJacobian, *cache);
  KroneckerHigUpdate first({.lr = 0.5, .refresh = 4});
  first.step(jacobian);
  const nlohmann::json state = first.state();
  EXPECT_TRUE(state.at("layers").at(0).at("transposed").get<bool>());
  KroneckerHigUpdate second({.lr = 0.5, .refresh = 4});
  second.restore(state, s.network.num_parameters());
  const BatchState gradient =
      evaluate_batch(s.network, s.problem, s.data, UpdateNeed::kGradient, *cache);
  EXPECT_EQ(second.need(), UpdateNeed::kGradient);
  EXPECT_EQ(second.step(gradient).delta, first.step(gradient).delta);
  nlohmann::json bad = state;
  bad["layers"][0]["transposed"] = "yes";
  EXPECT_THROW(second.restore(bad, s.network.num_parameters()), Error);
}

// A 1-D conv stack through identity physics with 2 samples of 4 outputs: 8 rows of J, so 8
// Lanczos products span J Jᵀ's Krylov space and give the exact step on its Gram path.
TEST(ConvFactors, LanczosWithAsManyProductsAsRowsIsTheExactStep) {
  DiagonalScale physics{Vector::Ones(4)};
  L2Loss loss{1.0};
  const LearningProblem problem{&physics, &loss};
  auto net = ConvNetwork::conv_stack(1, 4, {1, 2, 1}, 3, Activation::kTanh);
  net.initialize(3);
  const Dataset data{factor_test_uniform(4, 2, 7), factor_test_uniform(4, 2, 8), Matrix()};
  auto cache = net.new_cache();
  const BatchState state =
      evaluate_batch(net, problem, data, UpdateNeed::kStackedJacobian, *cache);
  ASSERT_EQ(state.jacobian->rows(), 8);
  for (const double kappa : {0.5, 1.0}) {
    const Vector expected =
        HigUpdate({.lr = 0.3, .cut = {.kappa = kappa, .rcond = 1e-3}, .backend = PinvBackend::kGram})
            .step(state)
            .delta;
    LanczosHigUpdate full({.lr = 0.3, .cut = {.kappa = kappa, .rcond = 1e-3}, .products = 8});
    EXPECT_LT(factor_test_difference(full.step(state).delta, expected), 1e-10) << "κ " << kappa;
  }
}

// A U-net of 2 levels (8×8 cells, 4 filters, no batch norm) fitted to fixed targets through
// identity physics: five updates of kfac-hig (factors refreshed every step) and of lanczos-hig at
// η = 0.1 lower the loss. Here the Kronecker step is far from the exact one (cosine ~0.03 at the
// start), and with factors kept for several steps (refresh 10) or at κ = 1 it diverges.
TEST(ConvFactors, StructuredRulesLowerTheLossOfASmallUNet) {
  UNetOptions o;
  o.n = 8;
  o.levels = 2;
  o.filters = 4;
  const Index cells = o.n * o.n;
  DiagonalScale physics{Vector::Ones(cells)};
  L2Loss loss{1.0};
  const LearningProblem problem{&physics, &loss};
  const Dataset data{factor_test_uniform(cells, 4, 9), 0.5 * factor_test_uniform(cells, 4, 10),
                     Matrix()};
  for (const std::string id : {"kfac-hig", "lanczos-hig"}) {
    auto net = ConvNetwork::unet(o);
    net.initialize(4);
    RuleSettings settings{{"lr", 0.1}};
    if (id == "kfac-hig") settings["refresh"] = 1;
    auto rule = make_learning_update(id, settings);
    auto cache = net.new_cache();
    double first = 0, last = 0;
    for (int step = 0; step < 5; ++step) {
      const BatchState state = evaluate_batch(net, problem, data, rule->need(), *cache);
      if (step == 0) first = state.loss;
      net.parameters() += rule->step(state).delta;
    }
    last = evaluate_batch(net, problem, data, UpdateNeed::kGradient, *cache).loss;
    EXPECT_LT(last, 0.9 * first) << id;
    EXPECT_TRUE(std::isfinite(last)) << id;
  }
}

}  // namespace
}  // namespace physgrad
