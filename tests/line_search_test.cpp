#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <limits>
#include <string>

#include "physgrad/error.hpp"
#include "physgrad/optim/line_search.hpp"
#include "physgrad/optim/objective.hpp"
#include "scalar_function.hpp"
#include "test_problems.hpp"

namespace physgrad {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

using testing::nan_beyond_two;
using testing::quartic;
using testing::ScalarFunction;

// Checks a successful result against a fresh evaluation of φ(α) and φ'(α).
void expect_strong_wolfe(const Objective& objective, const Vector& x, const Vector& p,
                         const LineSearchResult& result, const LineSearchOptions& options) {
  ASSERT_TRUE(result.success) << result.message;
  ASSERT_GT(result.step, 0.0);
  EXPECT_LE(result.evaluations, options.max_evaluations);
  Vector g0, g;
  const double value0 = objective.value_and_gradient(x, g0);
  const double value = objective.value_and_gradient(x + result.step * p, g);
  EXPECT_LE(value, value0 + options.c1 * result.step * g0.dot(p));
  EXPECT_LE(std::abs(g.dot(p)), options.c2 * std::abs(g0.dot(p)));
  EXPECT_EQ(result.value, value);
  EXPECT_EQ(result.gradient, g);
}

// Runs the search along steepest descent from x with both a far too long and a far too short
// first trial, for the default c2 = 0.9 and a near-exact c2 = 0.1.
void check_steepest_descent_search(const Objective& objective, const Vector& x) {
  Vector g;
  const double value = objective.value_and_gradient(x, g);
  const Vector p = -g;
  for (const double c2 : {0.9, 0.1}) {
    for (const double initial_step : {1e3, 1e-6}) {
      SCOPED_TRACE("c2 = " + std::to_string(c2) +
                   ", initial_step = " + std::to_string(initial_step));
      LineSearchOptions options;
      options.c2 = c2;
      const LineSearchResult result =
          strong_wolfe_line_search(objective, x, value, g, p, initial_step, options);
      std::cout << "  c2 = " << c2 << ", α₀ = " << initial_step << ": α = " << result.step
                << " after " << result.evaluations << " evaluations\n";
      expect_strong_wolfe(objective, x, p, result, options);
    }
  }
}

TEST(LineSearch, StrongWolfeOnQuartic) {
  const ScalarFunction simulator = quartic();
  const L2Loss loss(2.0);
  const Objective objective(simulator, loss, Vector::Zero(1));
  check_steepest_descent_search(objective, Vector::Constant(1, 3.0));
}

TEST(LineSearch, StrongWolfeOnRosenbrockSteepestDescent) {
  const testing::Rosenbrock simulator;
  const L2Loss loss(2.0);
  const Objective objective(simulator, loss, Vector::Zero(2));
  check_steepest_descent_search(objective, Vector{{-1.2, 1.0}});
}

TEST(LineSearch, RejectsAscentDirection) {
  const testing::Rosenbrock simulator;
  const L2Loss loss(2.0);
  const Objective objective(simulator, loss, Vector::Zero(2));
  const Vector x{{-1.2, 1.0}};
  Vector g;
  const double value = objective.value_and_gradient(x, g);
  const LineSearchResult result = strong_wolfe_line_search(objective, x, value, g, g, 1.0, {});
  EXPECT_FALSE(result.success);
  EXPECT_NE(result.message.find("not a descent direction"), std::string::npos) << result.message;
  EXPECT_EQ(result.evaluations, 0);
  EXPECT_EQ(result.step, 0.0);
}

TEST(LineSearch, TreatsNonFiniteTrialsAsTooLong) {
  // L = ½(x − 1.9)² on x ≤ 2, NaN beyond; from x = 0 along +1 every α > 2 is NaN.
  const ScalarFunction simulator = nan_beyond_two();
  const L2Loss loss;
  const Objective objective(simulator, loss, Vector::Constant(1, 1.9));
  const Vector x = Vector::Zero(1);
  const Vector p = Vector::Ones(1);
  Vector g;
  const double value = objective.value_and_gradient(x, g);
  for (const double c2 : {0.9, 0.1}) {
    for (const double initial_step : {1e3, 1.5}) {
      SCOPED_TRACE("c2 = " + std::to_string(c2) +
                   ", initial_step = " + std::to_string(initial_step));
      LineSearchOptions options;
      options.c2 = c2;
      const LineSearchResult result =
          strong_wolfe_line_search(objective, x, value, g, p, initial_step, options);
      EXPECT_LE(result.step, 2.0);
      EXPECT_TRUE(std::isfinite(result.value));
      expect_strong_wolfe(objective, x, p, result, options);
    }
  }
}

TEST(LineSearch, OutOfEvaluationsReturnsBestSufficientDecreaseTrial) {
  const ScalarFunction simulator = quartic();
  const L2Loss loss(2.0);
  const Objective objective(simulator, loss, Vector::Zero(1));
  const Vector x = Vector::Constant(1, 3.0);
  Vector g;
  const double value = objective.value_and_gradient(x, g);
  LineSearchOptions options;
  options.max_evaluations = 1;

  // α = 1e-6 decreases φ enough but is far too short for the curvature condition.
  const LineSearchResult short_step =
      strong_wolfe_line_search(objective, x, value, g, -g, 1e-6, options);
  EXPECT_FALSE(short_step.success);
  EXPECT_EQ(short_step.evaluations, 1);
  EXPECT_EQ(short_step.step, 1e-6);
  EXPECT_LT(short_step.value, value);
  EXPECT_NE(short_step.message.find("max_evaluations"), std::string::npos) << short_step.message;

  // α = 1e3 overshoots: no trial qualifies, so the start is returned.
  const LineSearchResult long_step =
      strong_wolfe_line_search(objective, x, value, g, -g, 1e3, options);
  EXPECT_FALSE(long_step.success);
  EXPECT_EQ(long_step.step, 0.0);
  EXPECT_EQ(long_step.value, value);
  EXPECT_EQ(long_step.gradient, g);
}

TEST(LineSearch, RejectsInvalidOptions) {
  EXPECT_NO_THROW(LineSearchOptions{}.validate());
  EXPECT_THROW(LineSearchOptions({0.9, 0.9}).validate(), Error);  // c1 = c2
  EXPECT_THROW(LineSearchOptions({0.0, 0.9}).validate(), Error);
  EXPECT_THROW(LineSearchOptions({1e-4, 1.0}).validate(), Error);
  EXPECT_THROW(LineSearchOptions({1e-4, kNaN}).validate(), Error);
  EXPECT_THROW(LineSearchOptions({1e-4, 0.9, 0}).validate(), Error);
  EXPECT_THROW(LineSearchOptions({1e-4, 0.9, 25, 0.0}).validate(), Error);
  try {
    LineSearchOptions({0.6, 0.5}).validate();  // c1 > c2
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("c2"), std::string::npos) << e.what();
  }

  const testing::Rosenbrock simulator;
  const L2Loss loss(2.0);
  const Objective objective(simulator, loss, Vector::Zero(2));
  const Vector x{{-1.2, 1.0}};
  const Vector g = objective.gradient(x);
  EXPECT_THROW(strong_wolfe_line_search(objective, x, 0, g, -g, kNaN, {}), Error);
  EXPECT_THROW(strong_wolfe_line_search(objective, x, 0, g, Vector::Ones(3), 1, {}), Error);
}

}  // namespace
}  // namespace physgrad
