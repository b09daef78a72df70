// Box bounds and x_scale: the Domain's checks and operations, every direct rule staying inside
// the box and reaching the known constrained optimum (a linear least-squares fit solved by
// enumerating its active sets, a bounded Rosenbrock), the bounded line search, and x_scale.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "physgrad/catalogue.hpp"
#include "physgrad/error.hpp"
#include "physgrad/loss/loss.hpp"
#include "physgrad/optim/line_search.hpp"
#include "physgrad/optim/minimize.hpp"
#include "physgrad/physics/diagonal_scale.hpp"
#include "test_problems.hpp"

namespace physgrad {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// ½‖A x − b‖² with 5 residuals and 3 unknowns, in a box that cuts off its minimizer.
struct BoxedLeastSquares : testing::LeastSquares {
  Vector lower{{-kInf, -0.3, 0.0}};
  Vector upper{{0.2, kInf, 1.0}};

  // The constrained minimizer by brute force: every assignment of each variable to free, lower
  // or upper; the one whose free least-squares solution is feasible and satisfies the KKT signs
  // (∂L/∂xᵢ ≥ 0 at a lower bound, ≤ 0 at an upper bound).
  Vector constrained_optimum() const {
    for (int code = 0; code < 27; ++code) {
      int c = code;
      Vector x = Vector::Zero(3);
      std::vector<Index> free;
      std::vector<int> state(3);
      bool possible = true;
      for (Index i = 0; i < 3; ++i, c /= 3) {
        state[i] = c % 3;
        if (state[i] == 0) free.push_back(i);
        if (state[i] == 1) x(i) = lower(i);
        if (state[i] == 2) x(i) = upper(i);
        if (!std::isfinite(x(i))) possible = false;
      }
      if (!possible) continue;
      Matrix af(5, static_cast<Index>(free.size()));
      for (std::size_t k = 0; k < free.size(); ++k) af.col(static_cast<Index>(k)) = a.col(free[k]);
      const Vector xf = af.colPivHouseholderQr().solve(b - a * x);
      for (std::size_t k = 0; k < free.size(); ++k) x(free[k]) = xf(static_cast<Index>(k));
      const Vector g = a.transpose() * (a * x - b);
      bool kkt = true;
      for (Index i = 0; i < 3; ++i) {
        if (x(i) < lower(i) - 1e-12 || x(i) > upper(i) + 1e-12) kkt = false;
        if (state[i] == 1 && g(i) < -1e-12) kkt = false;
        if (state[i] == 2 && g(i) > 1e-12) kkt = false;
      }
      if (kkt) return x;
    }
    ADD_FAILURE() << "no KKT point found";
    return Vector();
  }
};

TEST(Domain, ChecksItsEntriesAndNamesTheOffendingOne) {
  const auto message = [](const std::function<void()>& f) {
    try {
      f();
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message([] { Domain(2, Vector{{0.0, 1.0}}, Vector{{1.0, 0.5}}, {}); }),
            "domain: lower[1] = 1 exceeds upper[1] = 0.5");
  EXPECT_EQ(message([] { Domain(2, Vector{{NAN, 0.0}}, {}, {}); }),
            "domain: lower[0] = nan must be a number below +inf");
  EXPECT_EQ(message([] { Domain(2, {}, {}, Vector{{1.0, 0.0}}); }),
            "domain: x_scale[1] = 0 must be finite and > 0");
  EXPECT_EQ(message([] { Domain(2, Vector{{0.0}}, {}, {}); }),
            "domain: lower has 1 entries, expected 2 (or none)");
  const Domain box(2, Vector{{0.0, -kInf}}, Vector{{1.0, 2.0}}, {});
  EXPECT_EQ(message([&] { box.check_contains(Vector{{0.5, 3.0}}, "x0"); }),
            "x0[1] = 3 is above its upper bound 2");

  // x0 outside the box is refused by minimize before anything runs.
  BoxedLeastSquares p;
  const auto gd = make_optimizer("gd");
  MinimizeOptions options;
  options.lower = p.lower;
  options.upper = p.upper;
  EXPECT_EQ(message([&] { minimize(*gd, p.objective, Vector{{0.0, 0.0, 2.0}}, options); }),
            "minimize: x0[2] = 2 is above its upper bound 1");
  options.lower = Vector::Zero(2);
  EXPECT_THROW(minimize(*gd, p.objective, Vector::Zero(3), options), Error);
}

TEST(Domain, ProjectionFreeVariablesAndStepToTheBox) {
  const Domain box(3, Vector{{0.0, 0.0, -kInf}}, Vector{{1.0, 1.0, kInf}}, Vector{{1.0, 2.0, 4.0}});
  EXPECT_EQ(box.project(Vector{{-1.0, 0.5, -7.0}}), (Vector{{0.0, 0.5, -7.0}}));
  const Vector x{{0.0, 1.0, 3.0}};
  // x₀ at its lower bound with g > 0 and x₁ at its upper bound with g < 0 are held.
  EXPECT_EQ(box.free_variables(x, Vector{{1.0, -1.0, 5.0}}), (std::vector<bool>{false, false, true}));
  EXPECT_EQ(box.free_variables(x, Vector{{-1.0, 1.0, 5.0}}), (std::vector<bool>{true, true, true}));
  EXPECT_DOUBLE_EQ(box.max_step(Vector{{0.5, 0.5, 0.0}}, Vector{{1.0, -0.25, 9.0}}), 0.5);
  // Projected gradient in z = x ⊘ s: x₀ held (0), x₁: (1 − Π(1 − 4·(−1)))/2 = 0, x₂: 16·5/4.
  EXPECT_DOUBLE_EQ(box.projected_gradient_norm(x, Vector{{1.0, -1.0, 5.0}}), 20.0);
  EXPECT_EQ(box.count_at_bounds(x), 2);
}

struct RuleCase {
  std::string id;
  RuleSettings settings;
  int iterations;
  double tolerance;  // on ‖x − x*‖
};

// The rules with step sizes that suit ½‖Ax − b‖² (λ_max(AᵀA) ≈ 25).
std::vector<RuleCase> least_squares_cases() {
  return {{"gd", {{"lr", 0.03}}, 5000, 1e-8},
          {"momentum", {{"lr", 0.01}}, 5000, 1e-8},
          {"adam", {{"lr", 0.01}}, 5000, 1e-4},
          {"newton", {}, 50, 1e-10},
          {"bfgs", {}, 200, 1e-7},
          {"lbfgs", {}, 200, 1e-7},
          {"gn", {}, 50, 1e-10},
          {"lm", {}, 200, 1e-8},
          {"ig", {}, 50, 1e-10},
          {"pg", {{"inverse", "lbfgs"}}, 50, 1e-6},
          {"pg", {{"inverse", "ig"}}, 50, 1e-8}};
}

void expect_feasible(const MinimizeSummary& s, const Vector& lower, const Vector& upper,
                     const std::string& what) {
  for (const IterationRecord& record : s.history) {
    EXPECT_TRUE((record.x.array() >= lower.array()).all() &&
                (record.x.array() <= upper.array()).all())
        << what << ": iterate " << record.iteration << " = " << record.x.transpose();
  }
}

TEST(Bounds, EveryRuleStaysInTheBoxAndReachesTheConstrainedLeastSquaresOptimum) {
  BoxedLeastSquares p;
  const Vector optimum = p.constrained_optimum();
  // The box matters: the unconstrained solution lies outside it.
  ASSERT_GT((p.solution() - optimum).norm(), 0.1);
  const Vector x0{{-0.5, 0.5, 0.5}};
  for (const Vector& scale : {Vector(), Vector{{0.5, 2.0, 0.1}}}) {
    for (const RuleCase& c : least_squares_cases()) {
      std::string what = c.id;
      if (c.settings.contains("inverse")) {
        what += ' ';
        what += c.settings.at("inverse").get<std::string>();
      }
      if (scale.size() != 0) what += " (x_scale)";
      // Adam's step is per component, so its step size is in z when x_scale is set.
      const auto optimizer = make_optimizer(c.id, c.settings);
      MinimizeOptions options;
      options.max_iterations = c.iterations;
      options.lower = p.lower;
      options.upper = p.upper;
      options.x_scale = scale;
      // Near the optimum L changes below its rounding: the line searches and lm's gain ratio
      // then stop the run (failed / parameter tolerance); the optimum is reached before.
      options.gradient_tolerance = 1e-10;
      options.parameter_tolerance = 1e-14;
      const MinimizeSummary s = minimize(*optimizer, p.objective, x0, options);
      EXPECT_NE(s.termination, Termination::kNumericalFailure) << what << ": " << s.message;
      EXPECT_LT((s.x - optimum).norm(), c.tolerance) << what << ": " << s.x.transpose() << " vs "
                                                     << optimum.transpose() << ", "
                                                     << to_string(s.termination);
      expect_feasible(s, p.lower, p.upper, what);
    }
  }
}

TEST(Bounds, SecondOrderRulesReachTheBoundedRosenbrockOptimum) {
  // min 100(x₂ − x₁²)² + (1 − x₁)² with x₁ ≤ 0.5: the bound is active, the optimum (0.5, 0.25).
  const testing::Rosenbrock physics;
  const L2Loss loss(2.0);
  const Objective objective(physics, loss, Vector::Zero(2));
  const Vector lower{{-kInf, -kInf}}, upper{{0.5, kInf}};
  for (const std::string id : {"newton", "bfgs", "lbfgs", "gn", "lm", "ig", "pg"}) {
    const auto optimizer = make_optimizer(id);
    MinimizeOptions options;
    options.max_iterations = 300;
    options.upper = upper;
    // |∂L/∂x₂| = 200|x₂ − x₁²| ≤ 1e-6 puts x₂ within 5e-9 of 0.25.
    options.gradient_tolerance = 1e-6;
    const MinimizeSummary s = minimize(*optimizer, objective, Vector{{-1.2, 1.0}}, options);
    EXPECT_LT((s.x - Vector{{0.5, 0.25}}).norm(), 1e-8)
        << id << ": " << s.x.transpose() << ", " << to_string(s.termination) << " " << s.message;
    EXPECT_EQ(s.termination, Termination::kGradientTolerance) << id << ": " << s.message;
    expect_feasible(s, lower, upper, id);
  }
}

TEST(Bounds, AnalyticPhysicalGradientIsProjected) {
  // P = diag(1, 4) with target (2, −2): the separable box optimum is the clamp of (2, −0.5).
  const DiagonalScale physics(Vector{{1.0, 4.0}});
  const L2Loss loss;
  const Objective objective(physics, loss, Vector{{2.0, -2.0}});
  const auto pg = make_optimizer("pg", {{"lr", 0.5}, {"inverse", "analytic"}});
  MinimizeOptions options;
  options.max_iterations = 200;
  options.lower = Vector{{-1.0, 0.0}};
  options.upper = Vector{{1.0, 1.0}};
  options.parameter_tolerance = 1e-14;
  const MinimizeSummary s = minimize(*pg, objective, Vector{{0.0, 0.5}}, options);
  EXPECT_LT((s.x - Vector{{1.0, 0.0}}).norm(), 1e-12) << s.x.transpose();
  EXPECT_EQ(s.at_bounds, 2);
}

TEST(Bounds, LineSearchStopsAtTheBoundaryWhileTheLossStillDecreases) {
  // L = ½x² from x = 2 along p = −1 with the box x ≥ 1: the ray leaves the box at α = 1, where
  // the slope is still −1. With c2 = 0.1 the curvature condition (|−1| ≤ 0.1·2) fails there, so
  // only the stop at the boundary accepts that step.
  const DiagonalScale physics(Vector{{1.0}});
  const L2Loss loss;
  const Objective objective(physics, loss, Vector::Zero(1));
  const Vector x{{2.0}}, g{{2.0}}, p{{-1.0}};
  const LineSearchResult r =
      strong_wolfe_line_search(objective, x, 2.0, g, p, 5.0, {.c2 = 0.1}, 1.0);
  EXPECT_TRUE(r.success) << r.message;
  EXPECT_EQ(r.step, 1.0);
  EXPECT_EQ(r.value, 0.5);
  EXPECT_THROW(strong_wolfe_line_search(objective, x, 2.0, g, p, 1.0, {}, 0.0), Error);
}

TEST(XScale, FirstOrderStepsAreScaledAndSecondOrderOnesAreNot) {
  // On ½‖diag(1, 100)x‖², GD in z = x ⊘ s with s = (1, 0.01) sees the identity: one step of
  // η = 1 solves it; without x_scale the same step diverges.
  const DiagonalScale physics(Vector{{1.0, 100.0}});
  const L2Loss loss;
  const Objective objective(physics, loss, Vector::Zero(2));
  const Vector x0{{0.48, 0.84}};
  const Domain scaled(2, {}, {}, Vector{{1.0, 0.01}});
  const auto gd = make_optimizer("gd", {{"lr", 1.0}});
  EXPECT_LT((x0 + gd->step(objective, x0, scaled).delta).norm(), 1e-15);
  EXPECT_GT((x0 + gd->step(objective, x0).delta).norm(), 1e3);
  // Newton, Gauss-Newton and IG are invariant to a rescaling of x (no truncation here).
  for (const std::string id : {"newton", "gn", "ig"}) {
    const auto rule = make_optimizer(id, {{"lr", 0.5}});
    EXPECT_LT((rule->step(objective, x0, scaled).delta - rule->step(objective, x0).delta).norm(), 1e-14)
        << id;
  }
}

TEST(XScale, MakesGradientDescentAndAdamConvergeOnABadlyScaledFit) {
  // P(x) = (x₁, 1000 x₂) with the solution (1, 0.001): per-variable scales s = (1, 0.001).
  const DiagonalScale physics(Vector{{1.0, 1000.0}});
  const L2Loss loss;
  const Objective objective(physics, loss, Vector{{1.0, 1.0}});
  for (const std::string id : {"gd", "momentum", "adam", "bfgs", "lbfgs"}) {
    RuleSettings settings;  // bfgs, lbfgs: the default first trial step 1
    if (id == "gd" || id == "momentum") settings["lr"] = 0.5;
    if (id == "adam") settings["lr"] = 0.1;
    const auto rule = make_optimizer(id, settings);
    MinimizeOptions options;
    options.max_iterations = 2000;
    options.loss_tolerance = 1e-12;
    const MinimizeSummary plain = minimize(*rule, objective, Vector::Zero(2), options);
    options.x_scale = Vector{{1.0, 1e-3}};
    const MinimizeSummary s = minimize(*rule, objective, Vector::Zero(2), options);
    EXPECT_EQ(s.termination, Termination::kConverged) << id << ": " << s.message;
    // Without the scale the same step size diverges (gd, momentum), crawls (adam) or needs
    // a longer line search and one more iteration (bfgs, lbfgs).
    EXPECT_TRUE(plain.termination != Termination::kConverged || s.iterations < plain.iterations)
        << id << ": " << s.iterations << " with x_scale, " << plain.iterations << " without ("
        << to_string(plain.termination) << ")";
  }
}

}  // namespace
}  // namespace physgrad
