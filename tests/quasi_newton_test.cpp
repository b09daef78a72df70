#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <iostream>
#include <limits>
#include <vector>

#include "physgrad/error.hpp"
#include "physgrad/optim/bfgs.hpp"
#include "physgrad/optim/lbfgs.hpp"
#include "physgrad/optim/line_search.hpp"
#include "physgrad/optim/minimize.hpp"
#include "scalar_function.hpp"
#include "test_problems.hpp"

namespace physgrad {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

using testing::nan_beyond_two;
using testing::ScalarFunction;

// P(x) = x on the diagonal x₁ = x₂ of R², NaN everywhere else.
class DiagonalOnly final : public Simulator {
 public:
  std::string name() const override { return "diagonal_only"; }
  Index input_dim() const override { return 2; }
  Index output_dim() const override { return 2; }
  Matrix forward_batch(const Matrix& x, const Matrix& context) const override {
    check_batch(x, context, "forward_batch");
    return mask(x, x);
  }
  Matrix vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const override {
    check_batch(x, context, "vjp_batch");
    return mask(x, gy);
  }

 private:
  static Matrix mask(const Matrix& x, Matrix out) {
    for (Index j = 0; j < x.cols(); ++j) {
      if (x(0, j) != x(1, j)) out.col(j).setConstant(kNaN);
    }
    return out;
  }
};

// A Simulator that forwards to another and records the x of every gradient (VJP) call.
class Recording final : public Simulator {
 public:
  explicit Recording(const Simulator& inner) : inner_(inner) {}
  std::string name() const override { return "recording"; }
  Index input_dim() const override { return inner_.input_dim(); }
  Index output_dim() const override { return inner_.output_dim(); }
  Matrix forward_batch(const Matrix& x, const Matrix& context) const override {
    return inner_.forward_batch(x, context);
  }
  Matrix vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const override {
    gradient_points.emplace_back(x);
    return inner_.vjp_batch(x, context, gy);
  }
  mutable std::vector<Vector> gradient_points;

 private:
  const Simulator& inner_;
};

// Runs minimize() and checks that x reaches x_star to 1e-6 within max_iterations.
MinimizeSummary solve(Optimizer& optimizer, const Objective& objective, const Vector& x0,
                      const Vector& x_star, double loss_tolerance, int max_iterations,
                      const std::string& label) {
  MinimizeOptions options;
  options.loss_tolerance = loss_tolerance;
  options.max_iterations = max_iterations;
  MinimizeSummary summary = minimize(optimizer, objective, x0, options);
  std::cout << "  " << optimizer.id() << " " << label << ": " << summary.iterations
            << " iterations, " << summary.history.back().evaluations
            << " evaluations, ‖x − x*‖ = " << (summary.x - x_star).norm() << "\n";
  EXPECT_EQ(summary.termination, Termination::kConverged) << summary.message;
  EXPECT_LT((summary.x - x_star).norm(), 1e-6);
  return summary;
}

// Classic start (−1.2, 1). At (1, 1) the Hessian's eigenvalues are ≈ 1001.6 and 0.3994, so
// L ≤ 1e-14 implies ‖x − (1, 1)‖ < 2.3e-7 near the minimum.
int rosenbrock_iterations(Optimizer& optimizer) {
  const testing::Rosenbrock simulator;
  const L2Loss loss(2.0);
  const Objective objective(simulator, loss, Vector::Zero(2));
  return solve(optimizer, objective, Vector{{-1.2, 1.0}}, Vector::Ones(2), 1e-14, 100, "rosenbrock")
      .iterations;
}

// n = 10 quadratic ½‖A(x − x*)‖² with A = Q diag(1, …, 10), Q orthogonal: the Hessian AᵀA has
// condition number 100 and L ≤ 5e-13 implies ‖x − x*‖ ≤ 1e-6.
int quadratic_iterations(Optimizer& optimizer) {
  constexpr Index n = 10;
  Matrix m(n, n);
  for (Index i = 0; i < n; ++i) {
    for (Index j = 0; j < n; ++j) m(i, j) = std::sin(1.0 + 1.3 * double(i) + 0.7 * double(j * j));
  }
  const Matrix q = Eigen::HouseholderQR<Matrix>(m).householderQ();
  const testing::LinearSimulator simulator(q * Vector::LinSpaced(n, 1, 10).asDiagonal());
  Vector x_star(n);
  for (Index i = 0; i < n; ++i) x_star(i) = std::cos(double(i)) + 0.5;
  const L2Loss loss;
  const Objective objective(simulator, loss, simulator.forward(x_star));
  return solve(optimizer, objective, Vector::Zero(n), x_star, 5e-13, 50, "quadratic n=10")
      .iterations;
}

LineSearchOptions near_exact() {
  LineSearchOptions options;
  options.c2 = 0.1;
  return options;
}

// First a normal step on a quadratic, so the curvature memory is no longer the identity; then a
// step at x = (1, 1) on DiagonalOnly, where the quasi-Newton direction leaves the diagonal (all
// NaN) and only the restart along −∇L = −(1, 1) can succeed.
void check_restart(Optimizer& optimizer) {
  const testing::LinearSimulator scaled(Vector{{1.0, 2.0}}.asDiagonal());
  const DiagonalOnly diagonal;
  const L2Loss loss;
  const Objective warm_up(scaled, loss, Vector::Zero(2));
  const Objective objective(diagonal, loss, Vector::Zero(2));
  const Vector x = Vector::Ones(2);
  ASSERT_EQ(optimizer.step(warm_up, x).status, Step::Status::kOk);
  const Step step = optimizer.step(objective, x);
  ASSERT_EQ(step.status, Step::Status::kOk) << step.message;
  EXPECT_NE(step.message.find("restarted"), std::string::npos) << step.message;
  EXPECT_EQ(step.delta(0), step.delta(1));  // stayed on the diagonal
  EXPECT_LT(step.delta(0), 0.0);
  // The gradient at x, a failed search of all-NaN trials, then one accepted trial along −∇L.
  EXPECT_EQ(step.evaluations, 1 + LineSearchOptions{}.max_evaluations + 1);

  // With no memory to drop, a search whose every trial is non-finite is numerical trouble: from
  // x = 2 towards the target 3 every trial lands in the NaN region.
  const ScalarFunction wall = nan_beyond_two();
  const Objective beyond(wall, loss, Vector::Constant(1, 3.0));
  optimizer.reset();
  try {
    optimizer.step(beyond, Vector::Constant(1, 2.0));
    ADD_FAILURE() << "expected a NumericalError";
  } catch (const NumericalError& e) {
    EXPECT_EQ(std::string(e.what()),
              "line search: all " + std::to_string(LineSearchOptions{}.max_evaluations) +
                  " trial points gave a non-finite loss or gradient");
  }
}

// The gradient of the point a step moved to is reused; at any other x it is evaluated afresh.
// Every gradient evaluation is counted in Step::evaluations.
void check_gradient_cache(Optimizer& optimizer) {
  const testing::Rosenbrock rosenbrock;
  const Recording simulator(rosenbrock);
  const L2Loss loss(2.0);
  const Objective objective(simulator, loss, Vector::Zero(2));
  const auto gradient_evaluations = [&](const Vector& x, Step& step) {
    const std::size_t before = simulator.gradient_points.size();
    step = optimizer.step(objective, x);
    const std::vector<Vector> points(simulator.gradient_points.begin() + std::ptrdiff_t(before),
                                     simulator.gradient_points.end());
    EXPECT_EQ(step.evaluations, int(points.size()));
    return points;
  };
  Step step;
  const Vector x0{{-1.2, 1.0}};
  std::vector<Vector> points = gradient_evaluations(x0, step);
  ASSERT_FALSE(points.empty());
  EXPECT_EQ(points.front(), x0);

  const Vector x1 = x0 + step.delta;
  points = gradient_evaluations(x1, step);
  for (const Vector& p : points) EXPECT_NE(p, x1);

  const Vector elsewhere{{0.5, 0.5}};
  points = gradient_evaluations(elsewhere, step);
  ASSERT_FALSE(points.empty());
  EXPECT_EQ(points.front(), elsewhere);
}

TEST(Bfgs, RosenbrockFromClassicStart) {
  Bfgs bfgs;
  EXPECT_LE(rosenbrock_iterations(bfgs), 50);  // measured 37
}

TEST(Bfgs, QuadraticInAboutNIterations) {
  Bfgs bfgs({1.0, near_exact()});
  EXPECT_LE(quadratic_iterations(bfgs), 12);  // n + 2; measured 11
}

TEST(Bfgs, RestartsAlongSteepestDescentOnce) {
  Bfgs bfgs;
  check_restart(bfgs);
}

TEST(Bfgs, ReusesGradientOnlyAtTheReachedPoint) {
  Bfgs bfgs;
  check_gradient_cache(bfgs);
}

TEST(Bfgs, ParamsAndInvalidOptions) {
  EXPECT_EQ(Bfgs().id(), "bfgs");
  EXPECT_EQ(Bfgs({0.5, near_exact()}).params(),
            (nlohmann::json{{"initial_step", 0.5}, {"c1", 1e-4}, {"c2", 0.1}}));
  EXPECT_THROW(Bfgs({kNaN, {}}), Error);
  EXPECT_THROW(Bfgs({0.0, {}}), Error);
  EXPECT_THROW(Bfgs({1.0, {0.5, 0.5}}), Error);  // c1 ≥ c2
}

TEST(Lbfgs, RosenbrockFromClassicStart) {
  Lbfgs lbfgs;
  EXPECT_LE(rosenbrock_iterations(lbfgs), 50);  // measured 36
}

TEST(Lbfgs, QuadraticInAboutNIterations) {
  Lbfgs lbfgs({10, 1.0, near_exact()});
  EXPECT_LE(quadratic_iterations(lbfgs), 12);  // n + 2; measured 11
}

TEST(Lbfgs, ExtendedRosenbrock20WithMemory5) {
  const testing::Rosenbrock simulator(20);
  const L2Loss loss(2.0);
  const Objective objective(simulator, loss, Vector::Zero(20));
  Vector x0(20);
  for (Index i = 0; i < 20; i += 2) x0.segment(i, 2) << -1.2, 1.0;
  Lbfgs lbfgs({5, 1.0, {}});
  const MinimizeSummary summary =
      solve(lbfgs, objective, x0, Vector::Ones(20), 1e-14, 200, "extended rosenbrock n=20");
  EXPECT_LE(summary.iterations, 45);  // measured 34
}

TEST(Lbfgs, RestartsAlongSteepestDescentOnce) {
  Lbfgs lbfgs;
  check_restart(lbfgs);
}

TEST(Lbfgs, ReusesGradientOnlyAtTheReachedPoint) {
  Lbfgs lbfgs;
  check_gradient_cache(lbfgs);
}

TEST(Lbfgs, ParamsAndInvalidOptions) {
  EXPECT_EQ(Lbfgs().id(), "lbfgs");
  EXPECT_EQ(Lbfgs({3, 0.5, {}}).params(),
            (nlohmann::json{{"memory", 3}, {"initial_step", 0.5}, {"c1", 1e-4}, {"c2", 0.9}}));
  EXPECT_THROW(Lbfgs({0, 1.0, {}}), Error);
  EXPECT_THROW(Lbfgs({10, kNaN, {}}), Error);
  EXPECT_THROW(Lbfgs({10, 1.0, {0.9, 0.9}}), Error);  // c1 ≥ c2
}

}  // namespace
}  // namespace physgrad
