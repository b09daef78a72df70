// Time reversal as a local inverse: the velocity-Verlet FPU chain (derivatives against finite
// differences, P(R(y)) = y to rounding), the coupled oscillators with the initial state as input
// (RK4 reversed: P(R(y)) = y only to the truncation error, measured here), the anchored local
// inverse, PG and SIP through it.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "physgrad/autodiff/finite_difference.hpp"
#include "physgrad/catalogue.hpp"
#include "physgrad/error.hpp"
#include "physgrad/loss/loss.hpp"
#include "physgrad/nn/mlp.hpp"
#include "physgrad/optim/minimize.hpp"
#include "physgrad/physics/coupled_oscillators.hpp"
#include "physgrad/physics/fpu_chain.hpp"
#include "physgrad/train/step.hpp"
#include "test_problems.hpp"

namespace physgrad {
namespace {

using testing::random_uniform;

double relative(const Vector& a, const Vector& b) { return (a - b).norm() / b.norm(); }

// The oscillators with the initial state as input, `steps` steps of the paper's dt.
OscillatorConfig state_oscillators(Index steps = 48) {
  OscillatorConfig config = OscillatorConfig::paper();
  config.steps = steps;
  config.input = OscillatorInput::kInitialState;
  return config;
}

TEST(FpuChain, DerivativesMatchFiniteDifferences) {
  std::mt19937_64 rng(3);
  for (const FpuChainConfig& config :
       {FpuChainConfig{}, FpuChainConfig{1, 30, 0.05, 0.5}, FpuChainConfig{3, 60, 0.1, 2.0}}) {
    const FpuChain physics(config);
    const Vector x = random_uniform(rng, physics.input_dim(), 1, -0.8, 0.8);
    const DerivativeCheck check = check_derivatives(physics, x, {}, 1e-6);
    EXPECT_TRUE(check.passed) << "N " << config.masses << ": " << check.report();
  }
}

TEST(FpuChain, BatchedCallsEqualColumnByColumnCallsAndEnergyStaysNearItsStart) {
  std::mt19937_64 rng(5);
  const FpuChain physics;
  const Matrix x = random_uniform(rng, 16, 4, -1, 1), gy = random_uniform(rng, 16, 4, -1, 1);
  const Matrix y = physics.forward_batch(x, {}), gx = physics.vjp_batch(x, {}, gy);
  const auto energy = [](const Vector& s) {
    const Vector q = s.head(8);
    double e = 0.5 * s.tail(8).squaredNorm();
    for (Index b = 0; b <= 8; ++b) {
      const double d = (b < 8 ? q(b) : 0.0) - (b > 0 ? q(b - 1) : 0.0);
      e += 0.5 * d * d + 0.25 * d * d * d * d;
    }
    return e;
  };
  for (Index b = 0; b < 4; ++b) {
    EXPECT_LT((y.col(b) - physics.forward(x.col(b))).norm(), 1e-14);
    EXPECT_LT((gx.col(b) - physics.vjp(x.col(b), {}, gy.col(b))).norm(), 1e-14);
    // Verlet keeps a nearby energy: the error is O(dt²), bounded over the run.
    EXPECT_NEAR(energy(y.col(b)), energy(x.col(b)), 0.02 * energy(x.col(b)));
  }
}

TEST(FpuChain, TimeReversalInvertsTheSimulatorToRounding) {
  std::mt19937_64 rng(9);
  const FpuChain physics;
  double worst = 0;
  for (int trial = 0; trial < 10; ++trial) {
    const Vector y = random_uniform(rng, 16, 1, -1, 1);
    const Vector x = physics.time_reversal(y);
    worst = std::max(worst, relative(physics.forward(x), y));
    worst = std::max(worst, relative(physics.time_reversal(physics.forward(y)), y));
  }
  std::printf("FPU chain (8 masses, 100 Verlet steps): max ‖P(R(y)) − y‖/‖y‖ = %.2e\n", worst);
  EXPECT_LT(worst, 1e-12);
  EXPECT_THROW(physics.time_reversal(Vector::Zero(3)), Error);
}

TEST(Oscillators, DerivativesWithTheInitialStateAsInputMatchFiniteDifferences) {
  std::mt19937_64 rng(13);
  const CoupledOscillators physics(state_oscillators());
  EXPECT_EQ(physics.input_dim(), 4);
  EXPECT_EQ(physics.context_dim(), 48);
  const Vector s0 = random_uniform(rng, 4, 1, 0, 1), u = random_uniform(rng, 48, 1, -1, 1);
  for (const Vector& controls : {Vector(), u}) {
    const DerivativeCheck check = check_derivatives(physics, s0, controls, 1e-6);
    EXPECT_TRUE(check.passed) << check.report();
  }
  // The same trajectory as the control-input simulator.
  const CoupledOscillators by_controls(OscillatorConfig{state_oscillators().oscillators, 48});
  EXPECT_LT((physics.forward(s0, u) - by_controls.forward(u, s0)).norm(), 1e-15);
  EXPECT_FALSE(by_controls.has_time_reversal());
  EXPECT_THROW(by_controls.time_reversal(s0, u), Error);
}

TEST(Oscillators, Rk4TimeReversalInvertsOnlyToTheTruncationError) {
  std::mt19937_64 rng(17);
  for (const Index steps : {Index{48}, Index{96}}) {
    const CoupledOscillators physics(state_oscillators(steps));
    double worst = 0, least = 1;
    for (int trial = 0; trial < 10; ++trial) {
      const Vector y = random_uniform(rng, 4, 1, 0, 1), u = random_uniform(rng, steps, 1, -1, 1);
      const double error = relative(physics.forward(physics.time_reversal(y, u), u), y);
      worst = std::max(worst, error);
      least = std::min(least, error);
    }
    std::printf("oscillators (RK4, dt 0.125, %ld steps): ‖P(R(y)) − y‖/‖y‖ from %.2e to %.2e\n",
                static_cast<long>(steps), least, worst);
    // Far above rounding (RK4 is not reversible) and far below the state's size.
    EXPECT_GT(least, 1e-9);
    EXPECT_LT(worst, 1e-2);
  }
}

TEST(LocalInverse, TimeReversalIsAnchoredAtTheGuess) {
  // x₀ + R(y) − R(P(x₀)): P(x₀) maps back to x₀ (to rounding) even for the inexact RK4 reversal
  // (so PG through it has the exact solution as its fixed point), and a nearby y to a point
  // much closer to it than x₀ (the error is first order in y − P(x₀)).
  std::mt19937_64 rng(19);
  const CoupledOscillators physics(state_oscillators());
  const Vector u = random_uniform(rng, 48, 1, -1, 1), x0 = random_uniform(rng, 4, 1, 0, 1);
  const Vector y0 = physics.forward(x0, u);
  const LocalInverseOptions options{.method = InverseMethod::kTimeReversal};
  EXPECT_LT((local_inverse(physics, y0, x0, u, options).x - x0).norm(), 1e-13);
  const Vector y = y0 + 0.01 * random_uniform(rng, 4, 1, -1, 1);
  const LocalInverseResult anchored = local_inverse(physics, y, x0, u, options);
  EXPECT_LT(anchored.residual, 0.2 * (y - y0).norm());
  // auto picks the time reversal when the simulator has one and no analytic inverse.
  EXPECT_EQ(local_inverse(physics, y, x0, u, {}).x, anchored.x);
  EXPECT_EQ(parse_inverse_method("time_reversal"), InverseMethod::kTimeReversal);
}

TEST(PhysicalGradient, TimeReversalSolvesTheVerletChainInOneStepAndTheRk4OscillatorsInFew) {
  std::mt19937_64 rng(23);
  const L2Loss loss;
  {
    const FpuChain physics;
    const Vector x_true = random_uniform(rng, 16, 1, -1, 1);
    const Objective objective(physics, loss, physics.forward(x_true));
    const auto pg = make_optimizer("pg", {{"inverse", "time_reversal"}});
    const MinimizeSummary s =
        minimize(*pg, objective, Vector::Zero(16), {.max_iterations = 10, .loss_tolerance = 1e-24});
    EXPECT_EQ(s.termination, Termination::kConverged) << s.message;
    EXPECT_EQ(s.iterations, 1);
    EXPECT_LT((s.x - x_true).norm(), 1e-12);
  }
  {
    const CoupledOscillators physics(state_oscillators());
    const Vector u = random_uniform(rng, 48, 1, -1, 1), x_true = random_uniform(rng, 4, 1, 0, 1);
    const Objective objective(physics, loss, physics.forward(x_true, u), u);
    const auto pg = make_optimizer("pg", {{"inverse", "time_reversal"}});
    const MinimizeSummary s =
        minimize(*pg, objective, Vector::Zero(4), {.max_iterations = 20, .loss_tolerance = 1e-24});
    EXPECT_EQ(s.termination, Termination::kConverged) << s.message;
    EXPECT_GT(s.iterations, 1);
    EXPECT_LE(s.iterations, 6);
    EXPECT_LT((s.x - x_true).norm(), 1e-11);
  }
}

TEST(SipUpdate, TimeReversalGivesTheStepOfTheNumericalInverse) {
  // A 4 → 8 → 4 network predicting initial states of a two-mass chain from its final states.
  const FpuChain physics({2, 20, 0.1, 1.0});
  const L2Loss loss;
  std::mt19937_64 rng(29);
  Mlp network({4, 8, 4}, Activation::kTanh);
  network.initialize(7);
  const Matrix x_true = random_uniform(rng, 4, 6, -0.5, 0.5);
  Dataset data{physics.forward_batch(x_true, {}), Matrix(), Matrix()};
  data.targets = data.inputs;
  MlpCache cache;
  const BatchState state =
      evaluate_batch(network, {&physics, &loss}, data, UpdateNeed::kNetworkOutputs, cache);
  const Vector reversal =
      make_learning_update("sip", {{"inverse", "time_reversal"}})->step(state).delta;
  const Vector numerical =
      make_learning_update("sip", {{"inverse", "ig"}})->step(state).delta;
  EXPECT_LT((reversal - numerical).cwiseAbs().maxCoeff(), 1e-6);
}

}  // namespace
}  // namespace physgrad
