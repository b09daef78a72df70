// How a run of minimize() ends and what it reports of the simulator's work: a run that made the
// loss worse, or met a NaN Jacobian, never counts as converged; the simulator's work is counted
// by kind (the inner solves of pg included) and bounded by max_evaluations and max_seconds.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <string>
#include <thread>

#include "physgrad/autodiff/dual.hpp"
#include "physgrad/catalogue.hpp"
#include "physgrad/error.hpp"
#include "physgrad/optim/minimize.hpp"
#include "lotka_volterra.hpp"

namespace physgrad {
namespace {

using testing::lotka;
const Vector& kTruth = testing::kLotkaTruth;

// A rule that first raises the loss (x: 1 → 30) and then creeps (steps of 1e-12).
class Worsening final : public Optimizer {
 public:
  std::string id() const override { return "worsening"; }
  nlohmann::json params() const override { return nlohmann::json::object(); }

 private:
  Step propose(const Objective& /*objective*/, const Vector& x, const Domain& /*domain*/) override {
    return {Vector::Constant(1, x(0) < 2 ? 29.0 : 1e-12), Step::Status::kOk, {}, 0};
  }
};

TEST(Termination, ARunThatMadeTheLossWorseIsDivergedNotConverged) {
  const AutoDiffSimulator identity([](const auto& x, const Vector&) { return x; }, "identity", 1,
                                   1);
  const L2Loss loss;
  const Objective objective(identity, loss, Vector::Zero(1));
  for (const auto& [name, options] :
       {std::pair{"parameter_tolerance", MinimizeOptions{.parameter_tolerance = 1e-8}},
        std::pair{"function_tolerance", MinimizeOptions{.function_tolerance = 1e-8}}}) {
    Worsening rule;
    const MinimizeSummary s = minimize(rule, objective, Vector::Ones(1), options);
    EXPECT_EQ(s.termination, Termination::kDiverged) << name << ": " << s.message;
    EXPECT_FALSE(converged(s.termination));
    EXPECT_EQ(s.iterations, 2);
    EXPECT_EQ(s.message.rfind(std::string(name) + " held (", 0), 0u) << s.message;
    EXPECT_NE(s.message.find("is above L(x₀) = 0.5"), std::string::npos) << s.message;
    EXPECT_NE(full_report(s).find("Termination: diverged\n"), std::string::npos) << full_report(s);
  }
}

// Gauss-Newton's full steps from this start raise the loss from 16.6 to 27.5, then shrink below
// the parameter tolerance: that used to end "parameter_tolerance (convergence)".
TEST(Termination, GaussNewtonOnLotkaVolterraEndsDivergedWhenTheLossRose) {
  const L2Loss loss;
  const Objective objective(lotka(), loss, lotka().forward(kTruth));
  MinimizeOptions options;
  options.parameter_tolerance = 1e-8;
  const MinimizeSummary s =
      minimize(*make_optimizer("gn"), objective, Vector{{1.41, 0.06028, 1.044, 0.1712}}, options);
  EXPECT_GT(s.loss, s.initial_loss);
  EXPECT_EQ(s.termination, Termination::kDiverged) << brief_report(s) << ": " << s.message;
  EXPECT_EQ(s.message.rfind("parameter_tolerance held (", 0), 0u) << s.message;
}

TEST(Termination, LevenbergMarquardtNamesANanJacobianAsANumericalFailure) {
  class NanJacobian final : public Simulator {
   public:
    std::string name() const override { return "lotka"; }
    Index input_dim() const override { return 4; }
    Index output_dim() const override { return 2; }
    Matrix forward_batch(const Matrix& x, const Matrix& c) const override {
      return lotka().forward_batch(x, c);
    }
    Matrix vjp_batch(const Matrix& x, const Matrix& c, const Matrix& gy) const override {
      return lotka().vjp_batch(x, c, gy);
    }
    Matrix jacobian(const Vector&, const Vector&) const override {
      return Matrix::Constant(2, 4, NAN);
    }
  };
  const NanJacobian physics;
  const L2Loss loss;
  const Objective objective(physics, loss, lotka().forward(kTruth));
  const MinimizeSummary s = minimize(*make_optimizer("lm"), objective, 1.2 * kTruth);
  EXPECT_EQ(s.termination, Termination::kNumericalFailure) << s.message;
  EXPECT_EQ(s.iterations, 0);
  EXPECT_EQ(s.message, "iteration 1 of lm: the Jacobian at x has non-finite entries");
}

// y = A x + b (2×3) with closed forms for everything, counting the calls that reach it.
class Counted final : public Simulator {
 public:
  std::string name() const override { return "counted"; }
  Index input_dim() const override { return 3; }
  Index output_dim() const override { return 2; }
  Matrix forward_batch(const Matrix& x, const Matrix&) const override {
    seen.forward += x.cols();
    return (a_ * x).colwise() + b_;
  }
  Matrix vjp_batch(const Matrix& x, const Matrix&, const Matrix& gy) const override {
    seen.vjp += x.cols();
    return a_.transpose() * gy;
  }
  Matrix jacobian(const Vector&, const Vector&) const override {
    ++seen.jacobians;
    return a_;
  }
  Matrix weighted_hessian(const Vector&, const Vector&, const Vector&) const override {
    ++seen.hessians;
    return Matrix::Zero(3, 3);
  }
  bool has_inverse() const override { return true; }
  Vector inverse(const Vector& y, const Vector& x0, const Vector&) const override {
    ++seen.inverses;
    return x0 + pinv_ * (y - a_ * x0 - b_);
  }
  bool has_time_reversal() const override { return true; }
  Vector time_reversal(const Vector& y, const Vector&) const override {
    ++seen.reversals;
    return pinv_ * (y - b_);
  }
  // The passes of what was seen (m = 2 per Jacobian, 2n = 6 per Hessian).
  long long passes() const {
    return seen.forward + seen.vjp + 2 * seen.jacobians + 6 * seen.hessians + seen.reversals +
           seen.inverses;
  }
  mutable SimulatorCounts seen;

 private:
  Matrix a_{{2.0, 0.5, 0.0}, {0.0, 1.0, 3.0}};
  Vector b_{{0.3, -0.2}};
  Matrix pinv_ = a_.completeOrthogonalDecomposition().pseudoInverse();
};

void expect_counts(const SimulatorCounts& counted, const Counted& physics,
                   const std::string& what) {
  SimulatorCounts expected = physics.seen;
  expected.passes = physics.passes();
  EXPECT_EQ(counted, expected) << what << ": " << to_string(counted) << " vs "
                               << to_string(expected);
}

TEST(SimulatorCounts, EveryCallIsCountedByKindPerIterationAndInTotal) {
  const L2Loss loss;
  const Vector x0{{1.0, -1.0, 2.0}};
  MinimizeOptions options;
  options.max_iterations = 5;
  for (const auto& [id, settings] :
       {std::pair{"gd", RuleSettings{{"lr", 0.01}}}, std::pair{"gn", RuleSettings{}},
        std::pair{"newton", RuleSettings{}}, std::pair{"lbfgs", RuleSettings{}},
        std::pair{"pg", RuleSettings{{"inverse", "analytic"}}},
        std::pair{"pg", RuleSettings{{"inverse", "time_reversal"}}},
        std::pair{"pg", RuleSettings{{"inverse", "ig"}}},
        std::pair{"pg", RuleSettings{{"lr", 0.5}, {"inverse", "lbfgs"}}}}) {
    const Counted physics;
    const Objective objective(physics, loss, Vector{{1.0, 2.0}});
    const MinimizeSummary s = minimize(*make_optimizer(id, settings), objective, x0, options);
    const std::string what = brief_report(s);
    expect_counts(s.counts, physics, what);
    // A run that ends inside a step (stationary, say) worked after its last iterate.
    EXPECT_LE(s.history.back().counts.passes, s.counts.passes) << what;
    if (s.termination == Termination::kMaxIterations) {
      EXPECT_EQ(s.history.back().counts, s.counts) << what;
    }
    for (std::size_t k = 1; k < s.history.size(); ++k) {
      EXPECT_GT(s.history[k].counts.passes, s.history[k - 1].counts.passes) << what;
    }
  }
  // gd: x₀'s loss, then per iteration the gradient (forward, VJP) and the new point's loss.
  const Counted physics;
  const Objective objective(physics, loss, Vector{{1.0, 2.0}});
  const MinimizeSummary s = minimize(*make_optimizer("gd", {{"lr", 0.01}}), objective, x0, options);
  EXPECT_EQ(s.counts.forward, 1 + 2 * 5);
  EXPECT_EQ(s.counts.vjp, 5);
  EXPECT_EQ(s.counts.passes, 16);
  EXPECT_EQ(s.history[2].counts.passes, 7);
}

// pg through a numerical local inverse: the inner solves' work is part of the outer run's.
TEST(SimulatorCounts, PgCountsItsLocalInverseSolves) {
  const Counted physics;
  const L2Loss loss;
  const Objective objective(physics, loss, Vector{{1.0, 2.0}});
  MinimizeOptions options;
  options.max_iterations = 3;
  const MinimizeSummary s = minimize(
      *make_optimizer("pg", {{"lr", 0.5}, {"inverse", "lbfgs"}}), objective,
      Vector{{1.0, -1.0, 2.0}}, options);
  expect_counts(s.counts, physics, brief_report(s));
  EXPECT_GT(s.counts.vjp, 3 * 2);  // the L-BFGS solves' gradients
  const LocalInverseResult inverse = local_inverse(
      physics, Vector{{0.5, 0.5}}, Vector::Zero(3), Vector(), {.method = InverseMethod::kLbfgs});
  EXPECT_GT(inverse.counts.vjp, 0);
  EXPECT_EQ(inverse.counts.passes, inverse.counts.forward + inverse.counts.vjp);
}

// P(x) = sin(x) componentwise in 6 dimensions, slowed down by `delay` per call; the target 3 is
// out of reach, so a local inverse through full Gauss-Newton steps never converges.
class SlowSine final : public Simulator {
 public:
  explicit SlowSine(std::chrono::microseconds delay = {}) : delay_(delay) {}
  std::string name() const override { return "sine"; }
  Index input_dim() const override { return 6; }
  Index output_dim() const override { return 6; }
  Matrix forward_batch(const Matrix& x, const Matrix&) const override {
    std::this_thread::sleep_for(delay_);
    return x.array().sin();
  }
  Matrix vjp_batch(const Matrix& x, const Matrix&, const Matrix& gy) const override {
    std::this_thread::sleep_for(delay_);
    return x.array().cos() * gy.array();
  }

 private:
  std::chrono::microseconds delay_;
};

// pg's local inverse runs until its iteration limit (no relative or stall test).
const RuleSettings kLongInverse{{"inverse", "ig"}, {"inverse_relative_tolerance", 0.0}, {"inverse_function_tolerance", 0.0}};

// pg from 0.1 towards sin(x) = 3 with `options`.
MinimizeSummary pg_out_of_reach(const SlowSine& sine, MinimizeOptions options) {
  const L2Loss loss;
  const Objective objective(sine, loss, Vector::Constant(6, 3.0));
  options.max_iterations = 200;
  return minimize(*make_optimizer("pg", kLongInverse), objective, Vector::Constant(6, 0.1),
                  options);
}

TEST(Budgets, MaxEvaluationsEndsAPgRunInsideItsLocalInverse) {
  const MinimizeSummary s = pg_out_of_reach(SlowSine(), {.max_evaluations = 150});
  EXPECT_EQ(s.termination, Termination::kMaxEvaluations) << s.message;
  // Each inner iteration costs 8 passes (its point, a Jacobian of 6, the new point's loss).
  EXPECT_LE(s.counts.passes, 150);
  EXPECT_GT(s.counts.passes, 150 - 8);
  EXPECT_EQ(s.iterations, 0);  // the first pg step's inverse ran out of budget
  EXPECT_EQ(s.message.rfind("max_evaluations reached in iteration 1: ", 0), 0u) << s.message;
  EXPECT_EQ(s.x, s.history.back().x);  // the last accepted iterate
  EXPECT_NE(full_report(s).find("max_evaluations         150\n"), std::string::npos)
      << full_report(s);
}

TEST(Budgets, MaxSecondsEndsARunWithinOneSimulatorCall) {
  const MinimizeSummary s =
      pg_out_of_reach(SlowSine(std::chrono::microseconds(2000)), {.max_seconds = 0.05});
  EXPECT_EQ(s.termination, Termination::kMaxSeconds) << s.message;
  EXPECT_GE(s.wall_seconds, 0.05);
  EXPECT_LT(s.wall_seconds, 0.5);  // not 200 inner × 200 outer iterations of 6 ms
  EXPECT_FALSE(converged(s.termination));
}

TEST(Reports, BriefAndFullReportsShowTheSimulatorsWork) {
  const Counted physics;
  const L2Loss loss;
  const Objective objective(physics, loss, Vector{{1.0, 2.0}});
  const MinimizeSummary s =
      minimize(*make_optimizer("pg", {{"inverse", "time_reversal"}}), objective,
               Vector{{1.0, -1.0, 2.0}}, {.max_iterations = 2, .loss_tolerance = 1e-20});
  const std::string passes = std::to_string(s.counts.passes);
  EXPECT_NE(brief_report(s).find(", " + passes + " simulator passes, "), std::string::npos)
      << brief_report(s);
  const std::string report = full_report(s);
  EXPECT_NE(report.find("simulator passes        " + passes + "\n"), std::string::npos) << report;
  EXPECT_NE(report.find("  time reversals        " + std::to_string(s.counts.reversals) + "\n"),
            std::string::npos)
      << report;
  EXPECT_GT(s.counts.reversals, 0);
}

}  // namespace
}  // namespace physgrad
