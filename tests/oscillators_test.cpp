// Coupled oscillators: the RK4 adjoint against central differences, batching, the RK4 energy
// behaviour of a free oscillator, the zero-control reference losses and the shape checks.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>

#include "physgrad/autodiff/finite_difference.hpp"
#include "physgrad/error.hpp"
#include "physgrad/physics/coupled_oscillators.hpp"
#include "test_problems.hpp"

namespace physgrad {
namespace {

using testing::random_uniform;

TEST(Oscillators, DerivativesMatchFiniteDifferences) {
  std::mt19937_64 rng(7);
  const OscillatorConfig chain{3, 40, 0.1, 0.3, 0.5, 2.0};  // exercises inner oscillators
  for (const OscillatorConfig& config :
       {OscillatorConfig::paper(), OscillatorConfig::book(), chain}) {
    const CoupledOscillators physics(config);
    for (int trial = 0; trial < 2; ++trial) {
      const Vector u = random_uniform(rng, physics.input_dim(), 1, -1, 1);
      const Vector s0 = random_uniform(rng, physics.context_dim(), 1);
      const DerivativeCheck check = check_derivatives(physics, u, s0, 1e-6);
      EXPECT_TRUE(check.passed) << "N " << config.oscillators << ", Nt " << config.steps << ": "
                                << check.report();
    }
  }
}

TEST(Oscillators, BatchedCallsEqualColumnByColumnCalls) {
  std::mt19937_64 rng(11);
  const CoupledOscillators physics;
  const Matrix u = random_uniform(rng, physics.input_dim(), 5, -1, 1);
  const Matrix s0 = random_uniform(rng, physics.context_dim(), 5);
  const Matrix gy = random_uniform(rng, physics.output_dim(), 5, -1, 1);
  const Matrix y = physics.forward_batch(u, s0), gx = physics.vjp_batch(u, s0, gy);
  for (Index b = 0; b < 5; ++b) {
    EXPECT_LT((y.col(b) - physics.forward(u.col(b), s0.col(b))).norm(), 1e-14);
    EXPECT_LT((gx.col(b) - physics.vjp(u.col(b), s0.col(b), gy.col(b))).norm(), 1e-14);
  }
}

TEST(Oscillators, FreeOscillatorEnergyDecaysAsTheRk4StabilityFunction) {
  // ẍ = −x: one RK4 step multiplies the state by R(hA) = αI + βA, so the energy ½(x² + v²)
  // shrinks by exactly |R(ih)|² = 1 − h⁶/72 + h⁸/576 per step.
  for (const OscillatorConfig& preset : {OscillatorConfig::paper(), OscillatorConfig::book()}) {
    OscillatorConfig config = preset;
    config.oscillators = 1;
    config.linear_coupling = config.cubic_coupling = 0;
    const CoupledOscillators physics(config);
    const Vector s0{{0.8, -0.3}};
    const Vector s = physics.forward(Vector::Zero(config.steps), s0);
    const double h = config.dt, steps = static_cast<double>(config.steps);
    const double drift = 1 - s.squaredNorm() / s0.squaredNorm();
    const double expected = 1 - std::pow(1 - std::pow(h, 6) / 72 + std::pow(h, 8) / 576, steps);
    EXPECT_NEAR(drift, expected, 1e-13) << "dt " << h;
    EXPECT_GT(drift, 0.9 * steps * std::pow(h, 6) / 72) << "dt " << h;
  }
}

TEST(Oscillators, ZeroControlLossMatchesTheReference) {
  // Mean per-sample Σ(s(T) − s₀)² over s₀ ~ U[0,1)⁴ with u = 0 (docs/reference_experiments.md).
  struct Case {
    OscillatorConfig config;
    double expected;
  };
  for (const Case& c :
       {Case{OscillatorConfig::book(), 0.726}, Case{OscillatorConfig::paper(), 0.796}}) {
    const CoupledOscillators physics(c.config);
    std::mt19937_64 rng(2024);
    const Matrix s0 = random_uniform(rng, 4, 20000);
    const Matrix s = physics.forward_batch(Matrix::Zero(c.config.steps, 20000), s0);
    const double mean = (s - s0).colwise().squaredNorm().mean();
    EXPECT_NEAR(mean, c.expected, 0.01) << "Nt " << c.config.steps;
  }
}

TEST(Oscillators, RejectsBadShapesAndConfigurations) {
  const CoupledOscillators physics(OscillatorConfig::book());
  const Vector u = Vector::Zero(24), s0 = Vector::Zero(4);
  EXPECT_THROW(physics.forward(Vector::Zero(23), s0), Error);
  EXPECT_THROW(physics.forward(u), Error);  // the initial state is required
  EXPECT_THROW(physics.vjp(u, {}, Vector::Zero(4)), Error);
  EXPECT_THROW(physics.forward(u, Vector::Zero(3)), Error);
  EXPECT_THROW(physics.vjp(u, s0, Vector::Zero(3)), Error);
  EXPECT_NO_THROW(physics.vjp(u, s0, Vector::Zero(4)));
  EXPECT_THROW(CoupledOscillators(OscillatorConfig{0, 24, 0.5, 0, 0, 1}), Error);
  EXPECT_THROW(CoupledOscillators(OscillatorConfig{2, 0, 0.5, 0, 0, 1}), Error);
  EXPECT_THROW(CoupledOscillators(OscillatorConfig{2, 24, -0.5, 0, 0, 1}), Error);
  EXPECT_THROW(CoupledOscillators(OscillatorConfig{2, 24, 0.5, std::nan(""), 0, 1}), Error);
}

}  // namespace
}  // namespace physgrad
