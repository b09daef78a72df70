// HigUpdate, the κ-family of Jacobian rules: one step against the HIG paper's formula computed
// independently (finite-difference J, Eigen's JacobiSVD), every backend, κ = 1 against the normal
// equations, and numerical trouble surfacing as NumericalError.
#include <gtest/gtest.h>

#include <cmath>

#include "learning_fixture.hpp"
#include "physgrad/autodiff/finite_difference.hpp"
#include "physgrad/error.hpp"
#include "physgrad/learn/hig.hpp"

namespace physgrad {
namespace {

using testing::NetworkThroughPhysics;

// −η V diag(σᵢ^{−κ} [σᵢ > τ σ_max]) Uᵀ g with J = U Σ Vᵀ, as written in the paper's code
// (docs/reference_experiments.md, published algorithms), from a J and g computed here without
// the library's Jacobian code:
// J by central differences of the stacked outputs, g = ∂(mean ½‖y − y*‖²)/∂y = (y − y*)/B.
Vector paper_step(const NetworkThroughPhysics& s, double lr, double kappa, double tau) {
  const Matrix j = finite_difference_jacobian(
      [&](const Vector& theta) { return s.stacked_outputs(theta); }, s.network.parameters());
  const Vector y = s.stacked_outputs(s.network.parameters());
  const Vector target = s.data.targets.transpose().reshaped();
  const Vector g = (y - target) / static_cast<double>(s.data.size());
  const Eigen::JacobiSVD<Matrix> svd(j, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const Vector& sigma = svd.singularValues();
  Vector c = svd.matrixU().transpose() * g;
  for (Index i = 0; i < c.size(); ++i) {
    c(i) = sigma(i) > tau * sigma(0) ? c(i) * std::pow(sigma(i), -kappa) : 0.0;
  }
  return -lr * svd.matrixV() * c;
}

TEST(HigUpdate, OneStepIsThePapersFormulaOnEveryBackend) {
  const NetworkThroughPhysics s(6);  // J is 12 × 32: the Gram path by default
  MlpCache cache;
  const BatchState state = s.evaluate(UpdateNeed::kStackedJacobian, cache);
  constexpr double kTau = 1e-3;
  const Vector expected = paper_step(s, 0.7, 0.5, kTau);
  for (const PinvBackend backend : {PinvBackend::kAuto, PinvBackend::kSvd, PinvBackend::kGram,
                                    PinvBackend::kNormal}) {
    HigUpdate hig({.lr = 0.7, .cut = {.kappa = 0.5, .rcond = kTau}, .backend = backend});
    const Vector delta = hig.step(state).delta;
    // The finite-difference J is good to ~1e-9; the kept spectrum spans < 1e3.
    EXPECT_LT((delta - expected).norm(), 1e-6 * expected.norm()) << to_string(backend);
    EXPECT_EQ(hig.last_info().backend,
              backend == PinvBackend::kAuto ? PinvBackend::kGram : backend);
  }
  EXPECT_GT(expected.norm(), 0.0);
}

// The last step's inversion info is the rule's state: step_info() names it for the metrics,
// and a rule restored from state() makes the same auto choices, and so the same next step, as
// the one that took the step; reset() forgets it.
TEST(HigUpdate, TheLastStepsInversionIsItsStateAndStepInfo) {
  const NetworkThroughPhysics s(6);
  MlpCache cache;
  const BatchState state = s.evaluate(UpdateNeed::kStackedJacobian, cache);
  HigUpdate hig({.lr = 0.1,
                 .cut = {.kappa = 0.5, .rcond = 1e-3},
                 .precision = PinvPrecision::kAuto,
                 .eigensolver = PinvEigensolver::kAuto});
  EXPECT_TRUE(hig.state().is_null());
  EXPECT_TRUE(hig.step_info().empty());
  hig.step(state);
  const nlohmann::json info = hig.step_info();
  EXPECT_EQ(info.at("pinv_path"), "gram");
  EXPECT_EQ(info.at("kept_directions"), hig.last_info().rank);
  EXPECT_EQ(info.at("kept_condition"), kept_condition(hig.last_info()));
  EXPECT_EQ(info.at("pinv_precision"), to_string(hig.last_info().precision));
  EXPECT_EQ(info.at("pinv_eigensolver"), "tridiagonal");  // no previous step
  HigUpdate restored({.lr = 0.1,
                      .cut = {.kappa = 0.5, .rcond = 1e-3},
                      .precision = PinvPrecision::kAuto,
                      .eigensolver = PinvEigensolver::kAuto});
  restored.restore(nlohmann::json::parse(hig.state().dump()), s.network.num_parameters());
  EXPECT_EQ(restored.state(), hig.state());
  EXPECT_TRUE(restored.step(state).delta == hig.step(state).delta);
  EXPECT_EQ(restored.state(), hig.state());
  nlohmann::json broken = hig.state();
  broken["float_resolves"] = 1;
  EXPECT_THROW(restored.restore(broken, 0), Error);
  restored.reset();
  EXPECT_TRUE(restored.state().is_null());
}

TEST(HigUpdate, KappaOneIsGaussNewtonAndKappaMinusOneTheGradient) {
  const NetworkThroughPhysics s(20);  // J is 40 × 32 with full column rank
  MlpCache cache;
  const BatchState state = s.evaluate(UpdateNeed::kStackedJacobian, cache);
  const Matrix j = state.jacobian->materialize();
  const Vector& g = state.loss_gradient_y;
  // κ = 1 with nothing truncated: −η J⁺ g, here from a complete orthogonal decomposition.
  const Vector least_squares = j.completeOrthogonalDecomposition().solve(g);
  HigUpdate gn({.lr = 0.5, .cut = {.kappa = 1.0, .rcond = 0.0}, .backend = PinvBackend::kSvd});
  EXPECT_EQ(gn.id(), "gn");
  EXPECT_LT((gn.step(state).delta + 0.5 * least_squares).norm(), 1e-8 * least_squares.norm());
  // κ = −1: V Σ Uᵀ g = Jᵀ g, the plain gradient of the mean loss.
  HigUpdate gradient({.lr = 1.0, .cut = {.kappa = -1.0, .rcond = 0.0}, .backend = PinvBackend::kSvd});
  EXPECT_LT((gradient.step(state).delta + j.transpose() * g).norm(),
            1e-12 * (j.transpose() * g).norm());
}

TEST(HigUpdate, ANonFiniteJacobianIsANumericalError) {
  NetworkThroughPhysics s(4);
  MlpCache cache;
  s.network.parameters()(0) = NAN;
  const BatchState state = s.evaluate(UpdateNeed::kStackedJacobian, cache);
  for (const PinvBackend backend : {PinvBackend::kSvd, PinvBackend::kGram, PinvBackend::kNormal}) {
    HigUpdate hig({.backend = backend});
    EXPECT_THROW(hig.step(state), NumericalError) << to_string(backend);
  }
}

TEST(HigUpdate, RejectsOptionsOutOfRangeAndABatchWithoutJacobian) {
  EXPECT_THROW(HigUpdate({.lr = 0.0}), Error);
  EXPECT_THROW(HigUpdate({.cut = {.kappa = 0.5, .rcond = 1.0}}), Error);
  EXPECT_THROW(HigUpdate({.cut = {.kappa = NAN, .rcond = 1e-6}}), Error);
  HigUpdate hig;
  EXPECT_THROW(hig.step(BatchState{}), Error);
  EXPECT_THROW(hig.set_learning_rate(-1.0), Error);
  hig.set_learning_rate(0.25);
  EXPECT_EQ(hig.learning_rate(), 0.25);
  EXPECT_EQ(hig.params().at("lr"), 0.25);
  EXPECT_TRUE(hig.steps_can_be_halved());
}

}  // namespace
}  // namespace physgrad
