// Direct-optimization update rules on problems with known answers, the optimizer-comparison
// reference iterates, scale invariance, and the minimize() driver's stopping rules.
#include <gtest/gtest.h>

#include <cmath>

#include "physgrad/error.hpp"
#include "physgrad/loss/loss.hpp"
#include "physgrad/optim/adam.hpp"
#include "physgrad/optim/gauss_newton.hpp"
#include "physgrad/optim/gradient_descent.hpp"
#include "physgrad/optim/inverse_gradient.hpp"
#include "physgrad/optim/levenberg_marquardt.hpp"
#include "physgrad/optim/minimize.hpp"
#include "physgrad/optim/momentum.hpp"
#include "physgrad/optim/newton.hpp"
#include "physgrad/optim/physical_gradient.hpp"
#include "physgrad/catalogue.hpp"
#include "physgrad/physics/comparison_toy.hpp"
#include "physgrad/physics/diagonal_scale.hpp"
#include "test_problems.hpp"

namespace physgrad {
namespace {

using testing::LeastSquares;

std::vector<Vector> iterates(Optimizer& optimizer, const Objective& objective, const Vector& x0,
                             int steps) {
  MinimizeOptions options;
  options.max_iterations = steps;
  const MinimizeSummary summary = minimize(optimizer, objective, x0, options);
  std::vector<Vector> out;
  for (const IterationRecord& record : summary.history) out.push_back(record.x);
  return out;
}

TEST(GradientDescent, StepIsMinusLrTimesGradient) {
  LeastSquares p;
  GradientDescent gd({0.05});
  const Vector x{{0.3, -0.2, 1.0}};
  EXPECT_TRUE(gd.step(p.objective, x).delta.isApprox(-0.05 * p.objective.gradient(x)));
  EXPECT_THROW(GradientDescent({-1.0}), Error);
  EXPECT_THROW(GradientDescent({std::nan("")}), Error);
}

TEST(Momentum, AccumulatesVelocityAndConverges) {
  LeastSquares p;
  Momentum momentum({0.01, 0.5});
  const Vector x{{0.3, -0.2, 1.0}};
  const Vector g = p.objective.gradient(x);
  EXPECT_TRUE(momentum.step(p.objective, x).delta.isApprox(-0.01 * g));
  EXPECT_TRUE(momentum.step(p.objective, x).delta.isApprox(-0.01 * (0.5 * g + g)));
  MinimizeOptions options;
  options.max_iterations = 2000;
  const MinimizeSummary s = minimize(momentum, p.objective, Vector::Zero(3), options);
  EXPECT_LT((s.x - p.solution()).norm(), 1e-8);
  EXPECT_THROW(Momentum({0.1, 1.0}), Error);
}

TEST(Adam, FirstStepHasLengthLrPerComponentAndConverges) {
  LeastSquares p;
  Adam adam({0.1});
  const Vector x{{0.3, -0.2, 1.0}};
  const Vector g = p.objective.gradient(x);
  const Vector dx = adam.step(p.objective, x).delta;
  for (Index i = 0; i < 3; ++i) EXPECT_NEAR(dx(i), -0.1 * (g(i) > 0 ? 1 : -1), 1e-8);
  MinimizeOptions options;
  options.max_iterations = 3000;
  const MinimizeSummary s = minimize(adam, p.objective, Vector::Zero(3), options);
  EXPECT_LT((s.x - p.solution()).norm(), 1e-4);
}

TEST(Newton, OneFullStepSolvesAQuadratic) {
  LeastSquares p;
  Newton newton({1.0});
  const Vector x{{5.0, -3.0, 2.0}};
  EXPECT_LT((x + newton.step(p.objective, x).delta - p.solution()).norm(), 1e-12);
}

TEST(Newton, ConvergesOnRosenbrockWithTheExactHessian) {
  const testing::Rosenbrock physics;
  const L2Loss loss(2.0);
  const Objective objective(physics, loss, Vector::Zero(2));
  Newton newton({1.0});
  MinimizeOptions options;
  options.max_iterations = 50;
  options.loss_tolerance = 1e-20;
  const MinimizeSummary s = minimize(newton, objective, Vector{{-1.2, 1.0}}, options);
  EXPECT_EQ(s.termination, Termination::kConverged);
  EXPECT_LT((s.x - Vector::Ones(2)).norm(), 1e-9);
}

TEST(GaussNewton, OneFullStepIsTheLeastSquaresSolution) {
  LeastSquares p;
  GaussNewton gn({1.0});
  const Vector x{{5.0, -3.0, 2.0}};
  EXPECT_LT((x + gn.step(p.objective, x).delta - p.solution()).norm(), 1e-10);
}

TEST(InverseGradient, FullStepIsTheLeastSquaresSolutionAndMinimumNormWhenUnderdetermined) {
  LeastSquares p;
  InverseGradient ig({1.0});
  const Vector x{{5.0, -3.0, 2.0}};
  EXPECT_LT((x + ig.step(p.objective, x).delta - p.solution()).norm(), 1e-10);

  // Two outputs, three inputs: the step is the minimum-norm solution of J Δx = Δy.
  const Matrix a = (Matrix(2, 3) << 1, 2, 0, 0, 1, 3).finished();
  const testing::LinearSimulator wide(a);
  const L2Loss loss;
  const Objective objective(wide, loss, Vector{{1.0, -1.0}});
  const Vector dx = ig.step(objective, Vector::Zero(3)).delta;
  EXPECT_LT((a * dx - Vector{{1.0, -1.0}}).norm(), 1e-12);
  EXPECT_LT((dx - a.transpose() * (a * a.transpose()).ldlt().solve(Vector{{1.0, -1.0}})).norm(),
            1e-12);
}

TEST(LevenbergMarquardt, ConvergesOnRosenbrockAndRejectsUphillTrials) {
  const testing::Rosenbrock physics;
  const L2Loss loss(2.0);
  const Objective objective(physics, loss, Vector::Zero(2));
  LevenbergMarquardt lm;
  MinimizeOptions options;
  options.max_iterations = 200;
  options.loss_tolerance = 1e-20;
  const MinimizeSummary s = minimize(lm, objective, Vector{{-1.2, 1.0}}, options);
  EXPECT_EQ(s.termination, Termination::kConverged);
  EXPECT_LT((s.x - Vector::Ones(2)).norm(), 1e-9);
  for (std::size_t k = 1; k < s.history.size(); ++k) {
    EXPECT_LE(s.history[k].loss, s.history[k - 1].loss) << "iteration " << k;
  }
}

TEST(PhysicalGradient, AnalyticStepLandsOnTheScaledTarget) {
  const DiagonalScale physics(Vector{{1.0, 40.0}});
  const L2Loss loss;
  const Objective objective(physics, loss, Vector{{1.0, 2.0}});
  PhysicalGradient pg({0.25, {InverseMethod::kAnalytic}});
  const Vector x{{0.2, 0.3}};
  const Vector y = physics.forward(x);
  const Vector y_new = physics.forward(x + pg.step(objective, x).delta);
  EXPECT_LT((y_new - (y + 0.25 * (objective.target() - y))).norm(), 1e-12);
}

TEST(PhysicalGradient, NumericalInversesMatchTheAnalyticOne) {
  const ComparisonToy physics;
  const L2Loss loss(2.0);
  const Objective objective(physics, loss, Vector::Zero(2));
  const Vector x{{3.0, 3.0}};
  PhysicalGradient analytic({0.3, {InverseMethod::kAnalytic}});
  const Vector expected = analytic.step(objective, x).delta;
  for (const InverseMethod method : {InverseMethod::kLbfgs, InverseMethod::kInverseGradient}) {
    PhysicalGradient numerical({0.3, {method}});
    EXPECT_LT((numerical.step(objective, x).delta - expected).norm(), 1e-7) << to_string(method);
  }
}

TEST(PhysicalGradient, AnalyticInverseOfASimulatorWithoutOneIsAClearError) {
  const testing::Rosenbrock physics;
  const L2Loss loss;
  const Objective objective(physics, loss, Vector::Zero(2));
  PhysicalGradient pg({1.0, {InverseMethod::kAnalytic}});
  try {
    pg.step(objective, Vector::Zero(2));
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("rosenbrock"), std::string::npos) << e.what();
  }
}

TEST(LocalInverse, LbfgsFindsThePreimageOfTheComparisonNotebook) {
  // docs/reference_experiments.md (comparison): y = (2, 2) from (3, 3) → (2, √2).
  const ComparisonToy physics;
  const LocalInverseResult r = local_inverse(physics, Vector{{2.0, 2.0}}, Vector{{3.0, 3.0}}, {},
                                             {InverseMethod::kLbfgs, 1e-12, 200});
  EXPECT_TRUE(r.converged);
  EXPECT_NEAR(r.x(0), 2.0, 1e-9);
  EXPECT_NEAR(r.x(1), std::sqrt(2.0), 1e-9);
}

// docs/reference_experiments.md (comparison): the notebook's printed iterates (float32) after
// each of 10 steps.
constexpr double kGd[10][2] = {{2.94, 1.9200001},          {2.8812, 1.6368846},
                               {2.823576, 1.4614503},      {2.7671044, 1.3365935},
                               {2.7117622, 1.2410815},     {2.657527, 1.1646168},
                               {2.6043763, 1.1014326},     {2.5522888, 1.0479842},
                               {2.501243, 1.0019454},      {2.4512184, 0.96171147}};
constexpr double kNewton[10][2] = {{2., 2.6666667},          {1.3333333, 2.3703704},
                                   {0.88888884, 2.1069958},  {0.59259254, 1.8728852},
                                   {0.39506167, 1.6647868},  {0.26337445, 1.4798105},
                                   {0.17558296, 1.315387},   {0.1170553, 1.1692328},
                                   {0.07803687, 1.0393181},  {0.05202458, 0.92383826}};
constexpr double kPg[10][2] = {{2.1, 2.5099802},         {1.4699999, 2.1000001},
                               {1.0289999, 1.7569861},   {0.72029996, 1.47},
                               {0.50421, 1.2298902},     {0.352947, 1.029},
                               {0.24706289, 0.86092323}, {0.17294402, 0.7203},
                               {0.12106082, 0.60264623}, {0.08474258, 0.50421}};

void expect_matches_notebook(const std::string& id, double lr, const double (&printed)[10][2],
                             InverseMethod inverse, double tolerance) {
  const ComparisonToy physics;
  const L2Loss loss(2.0);
  const Objective objective(physics, loss, Vector::Zero(2));
  const auto optimizer = make_optimizer(id, {{"lr", lr}, {"inverse", to_string(inverse)}});
  const std::vector<Vector> xs = iterates(*optimizer, objective, Vector{{3.0, 3.0}}, 10);
  ASSERT_EQ(xs.size(), 11u);
  for (int k = 0; k < 10; ++k) {
    for (int i = 0; i < 2; ++i) {
      EXPECT_NEAR(xs[k + 1](i), printed[k][i], tolerance * std::abs(printed[k][i]))
          << id << " step " << k << " component " << i;
    }
  }
}

// float32 keeps ~7 digits; ten steps accumulate a few ulps.
constexpr double kFloat32Tolerance = 1e-6;

TEST(ComparisonReference, GdNewtonAndPgReproduceTheNotebookIterates) {
  expect_matches_notebook("gd", 0.01, kGd, InverseMethod::kAuto, kFloat32Tolerance);
  expect_matches_notebook("newton", 1.0 / 3.0, kNewton, InverseMethod::kAuto, kFloat32Tolerance);
  expect_matches_notebook("pg", 0.3, kPg, InverseMethod::kAnalytic, kFloat32Tolerance);
  // PG through the numerical L-BFGS inverse: the notebook printed an MAE of 1e-6 with scipy.
  expect_matches_notebook("pg", 0.3, kPg, InverseMethod::kLbfgs, 1e-6);
}

// docs/reference_experiments.md (scaled toy): on L = ½‖(x₁, αx₂)‖² the inverted rules follow the
// same trajectory for every α.
TEST(ScaleInvariance, InvertedRulesAreIndependentOfAlphaAndGdIsNot) {
  const L2Loss loss;
  const Vector x0{{0.48, 0.84}};
  const auto trajectory = [&](const std::string& id, double lr, double alpha) {
    const DiagonalScale physics(Vector{{1.0, alpha}});
    const Objective objective(physics, loss, Vector::Zero(2));
    RuleSettings settings;
    if (lr > 0) settings["lr"] = lr;
    const auto optimizer = make_optimizer(id, settings);
    return iterates(*optimizer, objective, x0, 8);
  };
  for (const std::string id : {"newton", "gn", "ig", "pg", "lm"}) {
    const std::vector<Vector> reference = trajectory(id, id == "lm" ? 0 : 0.5, 1.0);
    for (const double alpha : {3.0, 5.0, 100.0, 1e4}) {
      const std::vector<Vector> xs = trajectory(id, id == "lm" ? 0 : 0.5, alpha);
      ASSERT_EQ(xs.size(), reference.size()) << id << " alpha " << alpha;
      for (std::size_t k = 0; k < xs.size(); ++k) {
        EXPECT_LT((xs[k] - reference[k]).norm(), 1e-9) << id << " alpha " << alpha << " k " << k;
      }
    }
  }
  // GD contracts x₂ by (1 − ηα²): the same step size behaves completely differently.
  const std::vector<Vector> gd1 = trajectory("gd", 0.01, 1.0);
  const std::vector<Vector> gd5 = trajectory("gd", 0.01, 5.0);
  EXPECT_NEAR(gd1[1](1), 0.84 * (1 - 0.01), 1e-15);
  EXPECT_NEAR(gd5[1](1), 0.84 * (1 - 0.01 * 25), 1e-15);
  EXPECT_GT((gd1.back() - gd5.back()).norm(), 0.1);
}

TEST(Minimize, StopsOnNonFiniteLossAndKeepsTheLastFiniteIterate) {
  const DiagonalScale physics(Vector{{1.0, 1000.0}});
  const L2Loss loss;
  const Objective objective(physics, loss, Vector::Zero(2));
  GradientDescent gd({1.0});  // η α² = 1e6: every step multiplies x₂ by about −1e6
  MinimizeOptions options;
  options.max_iterations = 1000;
  const MinimizeSummary s = minimize(gd, objective, Vector{{0.5, 0.5}}, options);
  EXPECT_EQ(s.termination, Termination::kNumericalFailure);
  EXPECT_TRUE(all_finite(s.x));
  EXPECT_TRUE(std::isfinite(s.loss));
  EXPECT_LT(s.iterations, 1000);
  EXPECT_FALSE(s.message.empty());
}

TEST(Minimize, ConvergesStationaryAndCallbackStop) {
  LeastSquares p;
  Newton newton({1.0});
  MinimizeOptions options;
  options.loss_tolerance = 1e-30;
  // Newton solves it in one step, then the gradient is (numerically) zero.
  MinimizeSummary s = minimize(newton, p.objective, Vector::Zero(3), options);
  EXPECT_TRUE(s.termination == Termination::kStationary ||
              s.termination == Termination::kConverged ||
              s.termination == Termination::kMaxIterations);
  EXPECT_LT((s.x - p.solution()).norm(), 1e-12);

  // At the minimum L = 0.5 of P(x) = (x₀, x₁²) with target (0, −1) the gradient is zero.
  const ComparisonToy physics;
  const L2Loss loss;
  const Objective at_minimum(physics, loss, Vector{{0.0, -1.0}});
  GradientDescent gd({0.1});
  s = minimize(gd, at_minimum, Vector::Zero(2), {10, 0.0, nullptr});
  EXPECT_EQ(s.termination, Termination::kStationary);

  options = {};
  options.max_iterations = 100;
  options.callback = [](const IterationRecord& r) { return r.iteration == 3; };
  s = minimize(gd, p.objective, Vector::Zero(3), options);
  EXPECT_EQ(s.termination, Termination::kStopped);
  EXPECT_EQ(s.iterations, 3);
  EXPECT_THROW(minimize(gd, p.objective, Vector::Zero(3), {0, 0.0, nullptr}), Error);
}

TEST(Catalogue, BuildsEveryDirectRuleAndRejectsUnknownIdsAndBadValues) {
  for (const std::string& id : rule_ids(RuleKind::kDirect)) {
    EXPECT_EQ(make_optimizer(id)->id(), id);
  }
  try {
    make_optimizer("sgdd");
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("'sgdd'"), std::string::npos);
  }
  EXPECT_THROW(make_optimizer("adam", {{"lr", -0.1}}), Error);
}

// Numerical trouble inside a rule (a non-finite Hessian, curvature matrix or Jacobian) ends the
// run with kNumericalFailure naming the rule and the iteration; nothing escapes minimize(). (lm
// rejects such trials itself and reports kFailed.)
TEST(Minimize, ANumericalErrorInsideARuleEndsTheRun) {
  const testing::CubeRoot physics;
  const L2Loss loss;
  const Objective objective(physics, loss, Vector::Ones(1));
  for (const std::string id : {"newton", "gn", "ig"}) {
    const auto optimizer = make_optimizer(id);
    MinimizeSummary s;
    ASSERT_NO_THROW(s = minimize(*optimizer, objective, Vector::Zero(1))) << id;
    EXPECT_EQ(s.termination, Termination::kNumericalFailure) << id << ": " << s.message;
    EXPECT_EQ(s.message.rfind("iteration 1 of " + id + ": ", 0), 0u) << s.message;
    EXPECT_EQ(s.x, Vector::Zero(1)) << id;
  }
}

}  // namespace
}  // namespace physgrad
