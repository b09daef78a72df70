// SipUpdate: one step against Adam on the closed-form proxy gradient, numerical against
// analytic local inverses, and a local inverse that fails numerically ending the run with
// numerical_failure instead of an exception escaping train().
#include <gtest/gtest.h>

#include <cmath>

#include "learning_fixture.hpp"
#include "physgrad/autodiff/finite_difference.hpp"
#include "physgrad/physics/diagonal_scale.hpp"
#include "test_problems.hpp"

namespace physgrad {
namespace {

using testing::NetworkThroughPhysics;

// On an invertible linear simulator, x̃ = P⁻¹(y + η(y* − y)) = x + η(P⁻¹y* − x) in closed form,
// so one SIP step is Adam on the gradient of mean ½‖f(in; θ) − x̃‖² with that x̃.
TEST(SipUpdate, OneStepOnALinearSimulatorIsAdamOnTheClosedFormProxyGradient) {
  const DiagonalScale physics(Vector{{2.0, -0.5}});
  const L2Loss loss;
  Mlp network({2, 4, 2}, Activation::kTanh);
  network.initialize(5);
  Dataset data{Matrix(2, 3), Matrix(2, 3), Matrix()};
  data.inputs << 0.1, -0.4, 0.8, 0.3, 0.5, -0.2;
  data.targets << 1.0, -2.0, 0.5, 0.25, 0.0, -1.0;
  for (const double eta : {1.0, 0.5}) {
    const Matrix x = network.forward(data.inputs);
    const Matrix x_tilde =
        x + eta * (physics.scales().cwiseInverse().asDiagonal() * data.targets - x);
    const auto proxy = [&](const Vector& theta) {
      Mlp copy = network;
      copy.set_parameters(theta);
      return Vector::Constant(1, 0.5 * (copy.forward(data.inputs) - x_tilde).squaredNorm() / 3);
    };
    const Vector gradient =
        finite_difference_jacobian(proxy, network.parameters()).row(0).transpose();
    AdamState adam({0.01});
    const Vector expected = adam.update(gradient);

    MlpCache cache;
    const BatchState state = evaluate_batch(network, {&physics, &loss}, data,
                                            UpdateNeed::kNetworkOutputs, cache);
    SipUpdate sip({.adam = {.lr = 0.01}, .y_step = eta});
    const Vector delta = sip.step(state).delta;
    // Adam's first step is lr·g/(|g| + ε) per component, insensitive to the FD error in g.
    EXPECT_LT((delta - expected).cwiseAbs().maxCoeff(), 1e-6) << "eta " << eta;
  }
}

TEST(SipUpdate, NumericalLocalInverseGivesTheAnalyticStep) {
  const NetworkThroughPhysics s;  // ComparisonToy's analytic inverse against L-BFGS
  MlpCache cache;
  const BatchState state = s.evaluate(UpdateNeed::kNetworkOutputs, cache);
  const Vector a = make_learning_update("sip", {{"inverse", "analytic"}})->step(state).delta;
  const Vector b = make_learning_update("sip", {{"inverse", "lbfgs"}})->step(state).delta;
  EXPECT_LT((a - b).cwiseAbs().maxCoeff(), 1e-6);
}

// A network whose output is exactly 0 (θ = 0) sends SIP's Gauss-Newton local inverse into J = ∞;
// the run ends as a numerical failure naming the rule, the iteration and the place.
TEST(SipUpdate, ALocalInverseThatFailsNumericallyEndsTheRunWithoutAnException) {
  const testing::CubeRoot physics;
  const L2Loss loss;
  Mlp network({1, 1}, Activation::kIdentity);  // θ = 0: f(in) = 0
  const Dataset data{Matrix::Ones(1, 4), Matrix::Constant(1, 4, 0.5), Matrix()};
  const auto sip = make_learning_update("sip", {{"inverse", "ig"}});
  TrainerOptions options;
  options.batch_size = 4;
  options.max_iterations = 5;
  TrainingSummary summary;
  ASSERT_NO_THROW(summary = train(network, *sip, {&physics, &loss}, data, nullptr, options));
  EXPECT_EQ(summary.termination, TrainingTermination::kNumericalFailure);
  EXPECT_EQ(summary.iterations, 0);
  for (const char* part : {"sip: non-finite update at iteration 1", "local inverse (ig)",
                           "non-finite entry", "the step was not applied"}) {
    EXPECT_NE(summary.message.find(part), std::string::npos) << summary.message;
  }
  EXPECT_EQ(network.parameters(), Vector::Zero(2));
}

}  // namespace
}  // namespace physgrad
