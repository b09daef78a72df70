// HeatDiffusion: kernel values, mean conservation, derivatives vs finite differences, and the
// regularised inverse diffusion — exact on clear signal, identity or damping below the noise.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <utility>

#include "physgrad/autodiff/finite_difference.hpp"
#include "physgrad/error.hpp"
#include "physgrad/physics/heat_diffusion.hpp"
#include "test_problems.hpp"

namespace physgrad {
namespace {

constexpr double kTwoPi = 2 * std::numbers::pi;

// A cos(2π(m_i·i + m_j·j)/n) on the grid of `c` (j = 0 in 1-D).
Vector cosine_mode(const HeatConfig& c, Index m_i, Index m_j, double amplitude) {
  const Index cols = c.dims == 2 ? c.n : 1;
  Vector field(c.n * cols);
  for (Index j = 0; j < cols; ++j) {
    for (Index i = 0; i < c.n; ++i) {
      field(i + c.n * j) = amplitude * std::cos(kTwoPi * static_cast<double>(m_i * i + m_j * j) /
                                                static_cast<double>(c.n));
    }
  }
  return field;
}

// exp(−4π²|k|²·amount) for the mode (m_i, m_j), 0 < m < n/2.
double kernel_of(const HeatConfig& c, Index m_i, Index m_j) {
  const double k2 = static_cast<double>(m_i * m_i + m_j * m_j) / static_cast<double>(c.n * c.n);
  return std::exp(-kTwoPi * kTwoPi * k2 * c.amount);
}

Vector random_field(Index size, unsigned seed) { return testing::random_normal(size, 1, seed); }

TEST(HeatDiffusion, KernelMatchesTheReferenceValuesAndTheForwardMap) {
  const HeatDiffusion heat;                            // 64×64, amount 8
  EXPECT_NEAR(heat.kernel()(1), 0.926, 5e-4);          // k = (1/64, 0)
  EXPECT_NEAR(heat.kernel()(8), 7.19e-3, 5e-6);        // k = (8/64, 0)
  EXPECT_EQ(heat.kernel()(64 * 8), heat.kernel()(8));  // k = (0, 8/64)
  EXPECT_EQ(heat.kernel()(64 - 8), heat.kernel()(8));  // k = (−8/64, 0)
  EXPECT_EQ(heat.kernel()(0), 1.0);
  // A single mode is scaled by its kernel value, along either axis.
  for (const auto& [m_i, m_j] : {std::pair<Index, Index>{8, 0}, {0, 3}, {2, 5}}) {
    const Vector mode = cosine_mode(heat.config(), m_i, m_j, 1.0);
    const double k = kernel_of(heat.config(), m_i, m_j);
    EXPECT_LT((heat.forward(mode) - k * mode).cwiseAbs().maxCoeff(), 1e-14)
        << "mode " << m_i << ", " << m_j;
  }
}

TEST(HeatDiffusion, ForwardConservesTheMean) {
  for (const HeatConfig config : {HeatConfig{64, 1, 8}, HeatConfig{64, 2, 8}}) {
    const HeatDiffusion heat(config);
    const Vector x = random_field(heat.input_dim(), 3).array() + 0.7;
    const Vector y = heat.forward(x);
    EXPECT_NEAR(y.mean(), x.mean(), 1e-14);
    EXPECT_LT(y.squaredNorm(), 0.5 * x.squaredNorm());  // and it does smooth
  }
}

TEST(HeatDiffusion, DerivativesMatchFiniteDifferencesAndTheJacobianIsSymmetric) {
  for (const HeatConfig config :
       {HeatConfig{16, 1, 8}, HeatConfig{8, 2, 8}, HeatConfig{8, 2, 0.5}}) {
    const HeatDiffusion heat(config);
    const Vector x = random_field(heat.input_dim(), 5);
    const DerivativeCheck check = check_derivatives(heat, x);
    EXPECT_TRUE(check.passed) << "n " << config.n << " dims " << config.dims << ": "
                              << check.report();
    const Matrix j = heat.jacobian(x);
    EXPECT_LT((j - j.transpose()).cwiseAbs().maxCoeff(), 1e-15);
    EXPECT_GT(std::abs(j(0, 1)), 1e-3);  // neighbours couple
  }
}

TEST(HeatDiffusion, GradientOfTheL2LossIsTheDiffusedResidual) {
  for (const HeatConfig config : {HeatConfig{16, 1, 8}, HeatConfig{8, 2, 8}}) {
    const HeatDiffusion heat(config);
    const Vector x = random_field(heat.input_dim(), 11),
                 target = random_field(heat.input_dim(), 12);
    const auto loss = [&](const Vector& at) {
      return Vector::Constant(1, 0.5 * (heat.forward(at) - target).squaredNorm());
    };
    const Vector expected = finite_difference_jacobian(loss, x).transpose();
    const Vector residual = heat.forward(x) - target;
    EXPECT_LT((heat.forward(residual) - expected).cwiseAbs().maxCoeff(), 1e-8);
    EXPECT_LT((heat.vjp(x, {}, residual) - expected).cwiseAbs().maxCoeff(), 1e-8);
  }
}

TEST(HeatDiffusion, InverseRecoversASmoothWellResolvedField) {
  for (const HeatConfig config : {HeatConfig{64, 1, 8}, HeatConfig{64, 2, 8}}) {
    const HeatDiffusion heat(config);
    const Vector x_true = (cosine_mode(config, 1, 0, 0.8) + cosine_mode(config, 1, 2, 0.5) -
                           cosine_mode(config, 2, 1, 0.4))
                              .array() +
                          0.3;
    const Vector x0 = cosine_mode(config, 0, 1, 0.2).array() + 0.1;
    const Vector y = heat.forward(x_true);
    const Vector x = heat.inverse(y, x0);
    const double error = (x - x_true).norm() / x_true.norm();
    EXPECT_LT(error, 1e-8) << "dims " << config.dims;
    EXPECT_LT(inverse_residual(heat, y, x0), 1e-12) << "dims " << config.dims;
    // From a rough guess the high modes of the guess stay (they are below the noise level),
    // so y is reproduced up to a small damped remainder.
    const Vector rough = x0 + 0.1 * random_field(heat.input_dim(), 13);
    EXPECT_LT(inverse_residual(heat, y, rough), 1e-6) << "dims " << config.dims;
  }
}

// The reference's decision for one mode of |FFT| amplitude a, transcribed
// (docs/reference_experiments.md, heat-inverse).
struct ModeDecision {
  double probability;
  double action;
  double gain;
};
ModeDecision reference_mode(double a, double n, double kernel, double f_unc) {
  const auto likelihood = [](double ratio) {
    const double v = 0.5 * std::exp(-0.5 * ratio * ratio);
    return std::isfinite(v) ? v : 0.0;
  };
  const double signal = likelihood(a / (n * kernel)), noise = likelihood(a / f_unc);
  const double p = signal + noise > 0 ? signal / (signal + noise) : 0.0;
  const double action = (p <= 0.5 || p >= 0.68) ? 2 * (p - 0.5) : 0.0;
  return {p, action, std::exp(-std::log(kernel) * action)};
}

// One cosine mode through inverse_diffusion (floor 0); returns the reference decision and
// checks the output is the input times the decided gain.
struct ModeCase {
  HeatConfig config;
  Index m_i, m_j;
  double amplitude, uncertainty_scale;
};
ModeDecision run_mode_case(const ModeCase& c) {
  const HeatDiffusion heat(c.config);
  const Vector dy = cosine_mode(c.config, c.m_i, c.m_j, c.amplitude);
  const double kernel = kernel_of(c.config, c.m_i, c.m_j);
  // |FFT| of a cosine mode is amplitude·N/2 at ±k; f_unc = scale·‖dy‖.
  const double a = c.amplitude * static_cast<double>(heat.input_dim()) / 2;
  const ModeDecision d =
      reference_mode(a, static_cast<double>(c.config.n), kernel, c.uncertainty_scale * dy.norm());
  const Vector dx = heat.inverse_diffusion(dy, c.uncertainty_scale);
  const Vector expected = d.gain * dy;
  EXPECT_LT((dx - expected).cwiseAbs().maxCoeff(), 1e-10 * expected.cwiseAbs().maxCoeff())
      << "dims " << c.config.dims << ": P " << d.probability << ", action " << d.action;
  return d;
}

TEST(HeatInverseDiffusion, ClearSignalIsInvertedExactly) {
  // |a| ≫ f_unc and moderate |a|/(n·K): P ≈ 1, gain 1/K.
  for (const ModeCase& c :
       {ModeCase{{16, 1, 8}, 2, 0, 0.1, 1e-6}, ModeCase{{8, 2, 8}, 1, 1, 1e-4, 1e-6}}) {
    const ModeDecision d = run_mode_case(c);
    EXPECT_EQ(d.action, 1.0);
    const HeatDiffusion heat(c.config);
    const Vector dy = cosine_mode(c.config, c.m_i, c.m_j, c.amplitude);
    EXPECT_LT((heat.forward(heat.inverse_diffusion(dy, c.uncertainty_scale)) - dy).norm(),
              1e-10 * dy.norm());
  }
}

TEST(HeatInverseDiffusion, ModeBelowTheNoiseIsLeftAloneWhereNKIsLarge) {
  // |a| ≪ f_unc < n·K (low k): P just above ½, action 0.
  for (const ModeCase& c :
       {ModeCase{{16, 1, 8}, 1, 0, 0.01, 100}, ModeCase{{8, 2, 8}, 1, 0, 1e-5, 100}}) {
    const ModeDecision d = run_mode_case(c);
    EXPECT_GT(d.probability, 0.5);
    EXPECT_EQ(d.action, 0.0);
  }
}

TEST(HeatInverseDiffusion, ModeBelowTheNoiseIsDampedWhereNKIsSmall) {
  // |a| ≪ f_unc and |a| ≈ n·K: P < ½, −1 < action < 0, gain K^|action| < 1.
  for (const ModeCase& c :
       {ModeCase{{16, 1, 8}, 2, 0, 0.0144, 100}, ModeCase{{8, 2, 8}, 2, 0, 6.8e-10, 100}}) {
    const ModeDecision d = run_mode_case(c);
    EXPECT_LT(d.action, -0.1);
    EXPECT_GT(d.action, -0.9);
    EXPECT_LT(d.gain, 1.0);
  }
}

TEST(HeatInverseDiffusion, ModeWithBothLikelihoodsUnderflowingIsDiffusedOnceMore) {
  // |a|/(n·K) and |a|/f_unc both above ~38: P = 0, action −1, gain K.
  for (const ModeCase& c :
       {ModeCase{{16, 1, 8}, 2, 0, 1.0, 1e-6}, ModeCase{{8, 2, 8}, 1, 1, 1.0, 1e-6}}) {
    const ModeDecision d = run_mode_case(c);
    EXPECT_EQ(d.probability, 0.0);
    EXPECT_EQ(d.action, -1.0);
  }
}

TEST(HeatInverseDiffusion, GainIsCappedAtExp88) {
  // Clear signal (no uncertainty) at a high mode whose exact gain 1/K would be e^121.
  const HeatConfig config{64, 2, 8};
  const HeatDiffusion heat(config);
  const double kernel = kernel_of(config, 28, 28);
  ASSERT_GT(-std::log(kernel), 120);
  const Vector dy = cosine_mode(config, 28, 28, 64 * kernel / 2048);  // |a| = n·K
  const Vector expected = std::exp(88.0) * dy;
  EXPECT_LT((heat.inverse_diffusion(dy, 0) - expected).cwiseAbs().maxCoeff(),
            1e-10 * expected.cwiseAbs().maxCoeff());
}

TEST(HeatDiffusion, RejectsBadConfigurationsAndShapes) {
  EXPECT_THROW(HeatDiffusion({0, 2, 8}), Error);
  EXPECT_THROW(HeatDiffusion({8, 3, 8}), Error);
  EXPECT_THROW(HeatDiffusion({8, 2, -1}), Error);
  const HeatDiffusion heat({8, 2, 8});
  EXPECT_THROW(heat.forward(Vector::Zero(8)), Error);
  EXPECT_THROW(heat.inverse(Vector::Zero(8), Vector::Zero(64)), Error);
  EXPECT_THROW(heat.inverse_diffusion(Vector::Zero(64), -1), Error);
  EXPECT_THROW(heat.vjp_batch(Matrix::Zero(64, 2), Matrix(), Matrix::Zero(64, 3)), Error);
}

}  // namespace
}  // namespace physgrad
