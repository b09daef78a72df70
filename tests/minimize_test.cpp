// minimize()'s stopping rules on problems whose iterates are known in closed form (each rule
// stops at the iteration its inequality predicts, with its own Termination), their NaN safety,
// the option checks, and the full and brief reports.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

#include "physgrad/catalogue.hpp"
#include "physgrad/error.hpp"
#include "physgrad/loss/loss.hpp"
#include "physgrad/optim/minimize.hpp"
#include "physgrad/physics/diagonal_scale.hpp"
#include "test_problems.hpp"

namespace physgrad {
namespace {

// L(x) = ½((x − 1)² + (x + 1)²) = x² + 1: the two residuals cannot both vanish, so the minimum
// L* = 1 at x* = 0 is not a loss of zero. GD with η = 1/4 halves x: x_k = 2⁻ᵏ x₀.
struct Floor {
  Matrix a = (Matrix(2, 1) << 1, 1).finished();
  testing::LinearSimulator physics{a};
  L2Loss loss;
  Objective objective{physics, loss, Vector{{1.0, -1.0}}};
  static double x(int k) { return std::ldexp(1.0, -k); }  // x₀ = 1
  static double value(int k) { return x(k) * x(k) + 1; }
};

// L(x) = ½‖x‖² on R²: GD with η = ½ halves x, x_k = 2⁻ᵏ x₀, from x₀ = (0.48, 0.84).
struct HalfSquares {
  DiagonalScale physics{Vector{{1.0, 1.0}}};
  L2Loss loss;
  Objective objective{physics, loss, Vector::Zero(2)};
  Vector x0{{0.48, 0.84}};
};

MinimizeSummary run_gd(const Objective& objective, const Vector& x0, MinimizeOptions options,
                       double lr) {
  const auto gd = make_optimizer("gd", {{"lr", lr}});
  options.max_iterations = 1000;
  return minimize(*gd, objective, x0, options);
}

TEST(StoppingRules, RelativeLossStopsAtTheFirstIterateBelowTheFractionOfTheStart) {
  // L = ½‖x‖², GD with η = ½: L_k = 4⁻ᵏ L₀; 4⁻ᵏ ≤ 1e-6 first holds at k = 10.
  const HalfSquares p;
  MinimizeOptions options;
  options.relative_loss_tolerance = 1e-6;
  const MinimizeSummary s = run_gd(p.objective, p.x0, options, 0.5);
  EXPECT_EQ(s.termination, Termination::kRelativeLoss) << s.message;
  EXPECT_EQ(s.iterations, 10);
  EXPECT_TRUE(converged(s.termination));
  EXPECT_LE(s.loss, 1e-6 * s.initial_loss);
  EXPECT_GT(s.history[9].loss, 1e-6 * s.initial_loss);
}

TEST(StoppingRules, GradientToleranceTestsTheProjectedScaledGradient) {
  // Same problem: ∇L = x_k = 2⁻ᵏ x₀, ‖∇L‖∞ = 0.84·2⁻ᵏ ≤ 1e-3 first at k = 10.
  const HalfSquares p;
  MinimizeOptions options;
  options.gradient_tolerance = 1e-3;
  MinimizeSummary s = run_gd(p.objective, p.x0, options, 0.5);
  EXPECT_EQ(s.termination, Termination::kGradientTolerance) << s.message;
  EXPECT_EQ(s.iterations, 10);
  EXPECT_NEAR(s.gradient_norm, 0.84 / 1024, 1e-15);

  // With x_scale s = (1, 4) the test is on ‖D ∇L‖∞ = max(|x₁|, 4|x₂|). GD moves by η D² ∇L:
  // η = 1/32 shrinks x₁ by 31/32 and halves x₂. 4·0.84·2⁻ᵏ ≤ 0.5 first at k = 3 (0.42), while
  // 0.48·(31/32)ᵏ < 0.5 from the start: the scaled x₂ component decides.
  options.x_scale = Vector{{1.0, 4.0}};
  options.gradient_tolerance = 0.5;
  s = run_gd(p.objective, p.x0, options, 1.0 / 32);
  EXPECT_EQ(s.termination, Termination::kGradientTolerance) << s.message;
  EXPECT_EQ(s.iterations, 3);

  // With a bound x₂ ≥ 0.2 the optimum is (0, 0.2) and the gradient there (0, 0.2) points out
  // of the box: the projected gradient is that of x₁ alone, 0.48·2⁻ᵏ ≤ 1e-3 at k = 9.
  options = {};
  options.lower = Vector{{-1.0, 0.2}};
  options.gradient_tolerance = 1e-3;
  s = run_gd(p.objective, p.x0, options, 0.5);
  EXPECT_EQ(s.termination, Termination::kGradientTolerance) << s.message;
  EXPECT_EQ(s.iterations, 9);
  EXPECT_EQ(s.x(1), 0.2);
}

TEST(StoppingRules, FunctionToleranceStopsWhenTheLossStopsChanging) {
  // L_k − L_{k+1} = ¾·4⁻ᵏ ≤ f·L_k = f(4⁻ᵏ + 1): the first step k → k+1 that satisfies it.
  const Floor p;
  const double f = 1e-6;
  int expected = 0;
  while (!(Floor::value(expected) - Floor::value(expected + 1) <= f * Floor::value(expected))) {
    ++expected;
  }
  MinimizeOptions options;
  options.function_tolerance = f;
  const MinimizeSummary s = run_gd(p.objective, Vector{{1.0}}, options, 0.25);
  EXPECT_EQ(s.termination, Termination::kFunctionTolerance) << s.message;
  EXPECT_EQ(s.iterations, expected + 1);
  EXPECT_EQ(expected, 10);
  EXPECT_NEAR(s.loss, 1.0, 1e-6);
}

TEST(StoppingRules, ParameterToleranceComparesTheStepWithTheScaledIterate) {
  // |Δx_k| = 2⁻ᵏ⁻¹ ≤ t(|x_k| + t) = t(2⁻ᵏ + t); with x_scale s both sides are divided by s.
  const Floor p;
  for (const double scale : {1.0, 10.0}) {
    const double t = 1e-3;
    int expected = 0;
    while (!(Floor::x(expected + 1) / scale <= t * (Floor::x(expected) / scale + t))) ++expected;
    MinimizeOptions options;
    options.parameter_tolerance = t;
    if (scale != 1.0) options.x_scale = Vector{{scale}};
    // In z = x/s GD moves by η s² g: keep the same iterates with η = 1/(4s²).
    const MinimizeSummary s = run_gd(p.objective, Vector{{1.0}}, options, 0.25 / (scale * scale));
    EXPECT_EQ(s.termination, Termination::kParameterTolerance) << s.message;
    EXPECT_EQ(s.iterations, expected + 1) << "scale " << scale;
    EXPECT_NEAR(s.x(0), Floor::x(expected + 1), 1e-15);
  }
}

TEST(StoppingRules, TheFirstThatHoldsWinsAndTheAbsoluteLossComesFirst) {
  const HalfSquares p;
  MinimizeOptions options;
  options.loss_tolerance = 1e-3;
  options.relative_loss_tolerance = 1e-3;
  options.gradient_tolerance = 1e-3;
  const MinimizeSummary s = run_gd(p.objective, p.x0, options, 0.5);
  // L₀ = 0.468: L_k = 0.468·4⁻ᵏ ≤ 1e-3 at k = 5 (absolute), ≤ 0.468e-3 at k = 6 (relative),
  // gradient 0.84·2⁻ᵏ ≤ 1e-3 at k = 10.
  EXPECT_EQ(s.termination, Termination::kConverged) << s.message;
  EXPECT_EQ(s.iterations, 5);
  // A start that already satisfies a rule makes no step.
  options.loss_tolerance = 1.0;
  EXPECT_EQ(run_gd(p.objective, p.x0, options, 0.5).iterations, 0);
}

// P(x) = x with a finite value and a NaN gradient everywhere.
class NanGradient final : public Simulator {
 public:
  std::string name() const override { return "nan_gradient"; }
  Index input_dim() const override { return 1; }
  Index output_dim() const override { return 1; }
  Matrix forward_batch(const Matrix& x, const Matrix&) const override { return x; }
  Matrix vjp_batch(const Matrix& x, const Matrix&, const Matrix&) const override {
    return Matrix::Constant(x.rows(), x.cols(), NAN);
  }
};

TEST(StoppingRules, NonFiniteQuantitiesNeverCountAsConvergence) {
  // A NaN gradient satisfies no gradient tolerance, however loose.
  const NanGradient nan_gradient;
  const L2Loss loss;
  const Objective objective(nan_gradient, loss, Vector::Zero(1));
  MinimizeOptions options;
  options.gradient_tolerance = 1e300;
  MinimizeSummary s = run_gd(objective, Vector{{1.0}}, options, 0.1);
  EXPECT_EQ(s.termination, Termination::kNumericalFailure) << s.message;
  EXPECT_EQ(s.iterations, 0);

  // A step into NaN (x > 2) ends as a numerical failure, not as a function or parameter
  // tolerance met by a NaN change.
  const testing::Bounded bounded(2.0);
  const Objective to_nan(bounded, loss, Vector{{10.0}});
  options = {};
  options.function_tolerance = 0.99;
  options.parameter_tolerance = 0.99;
  s = run_gd(to_nan, Vector{{1.0}}, options, 0.5);
  EXPECT_EQ(s.termination, Termination::kNumericalFailure) << s.message;
  EXPECT_EQ(s.x, Vector{{1.0}});
}

TEST(StoppingRules, OutOfRangeOptionsAreErrorsNamingThem) {
  const DiagonalScale physics(Vector{{1.0}});
  const L2Loss loss;
  const Objective objective(physics, loss, Vector::Zero(1));
  const auto gd = make_optimizer("gd");
  const auto message = [&](MinimizeOptions options) {
    try {
      minimize(*gd, objective, Vector{{1.0}}, options);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message({.relative_loss_tolerance = 1.0}),
            "minimize: relative_loss_tolerance must be in [0, 1), got 1");
  EXPECT_EQ(message({.gradient_tolerance = -1}),
            "minimize: gradient_tolerance must be in [0, inf), got -1");
  EXPECT_EQ(message({.function_tolerance = NAN}),
            "minimize: function_tolerance must be in [0, inf), got nan");
  EXPECT_EQ(message({.parameter_tolerance = -0.5}),
            "minimize: parameter_tolerance must be in [0, inf), got -0.5");
  EXPECT_EQ(message({.loss_tolerance = -1}),
            "minimize: loss_tolerance must be in [0, inf), got -1");
  EXPECT_EQ(message({.loss_tolerance = NAN}),
            "minimize: loss_tolerance must be in [0, inf), got nan");
  EXPECT_EQ(message({.max_evaluations = -1}),
            "minimize: max_evaluations must be ≥ 0 (0: no budget), got -1");
  EXPECT_EQ(message({.max_seconds = INFINITY}),
            "minimize: max_seconds must be in [0, inf), got inf");
}

// max_iterations has no "off": 0 is refused, and no page of the docs lists it among the
// options that are off at 0.
TEST(StoppingRules, MaxIterationsIsAtLeastOneInTheCodeAndTheDocs) {
  const DiagonalScale physics(Vector{{1.0}});
  const L2Loss loss;
  const Objective objective(physics, loss, Vector::Zero(1));
  const auto gd = make_optimizer("gd");
  EXPECT_THROW(
      {
        try {
          minimize(*gd, objective, Vector{{1.0}}, {.max_iterations = 0});
        } catch (const Error& e) {
          EXPECT_STREQ(e.what(), "minimize: max_iterations must be ≥ 1, got 0");
          throw;
        }
      },
      Error);
  for (const char* page : {"docs/python.md", "docs/update_rules.md", "docs/concepts.md",
                           "docs/cli.md", "README.md"}) {
    std::ifstream in(std::string(PHYSGRAD_SOURCE_DIR) + "/" + page);
    ASSERT_TRUE(in) << page;
    std::stringstream text;
    text << in.rdbuf();
    // Paragraphs and list items: what follows "off at" up to the next one names the options.
    std::string block;
    std::istringstream lines(text.str() + "\n\n");
    for (std::string line; std::getline(lines, line);) {
      const bool item = line.rfind("- ", 0) == 0;
      if (line.empty() || item) {
        const std::size_t off = block.find("off at");
        EXPECT_TRUE(off == std::string::npos ||
                    block.find("`max_iterations`", off) == std::string::npos)
            << page << ": " << block;
        block.clear();
      }
      block += line + "\n";
    }
  }
}

TEST(Reports, FullReportListsTheRunAndWhyItEnded) {
  const Floor p;
  MinimizeOptions options;
  options.function_tolerance = 1e-6;
  options.lower = Vector{{-0.25}};
  const MinimizeSummary s = run_gd(p.objective, Vector{{1.0}}, options, 0.25);
  const std::string report = full_report(s);
  for (const std::string expected :
       {"parameters              1", "bounds                  box (0 at a bound at the end)",
        "optimizer               gd", "lr                      0.25",
        "function_tolerance      1e-06", "initial                 2",
        "iterations              11 (0 rejected trials)",
        "evaluations             23 (of the loss)",
        // x₀, then per iteration the gradient (forward and VJP) and the new point's loss.
        "simulator passes        34", "  forward samples       23", "  VJP samples           11",
        "  Jacobians             0", "Termination: function_tolerance (convergence)",
        "|ΔL| = "}) {
    EXPECT_NE(report.find(expected), std::string::npos) << expected << " in\n" << report;
  }
  EXPECT_EQ(brief_report(s).rfind(
                "gd: 11 iterations, 23 evaluations, 34 simulator passes, loss 2 → 1", 0),
            0u)
      << brief_report(s);
}

TEST(History, KeepsTheStartAndTheLatestRecordsWithinBothLimits) {
  // GD with η = ½ halves x: record k holds x_k = 2⁻ᵏ x₀ and L_k = 4⁻ᵏ L₀.
  const HalfSquares p;
  MinimizeOptions options;
  options.max_history = 4;
  const auto gd = make_optimizer("gd", {{"lr", 0.5}});
  options.max_iterations = 20;
  const MinimizeSummary s = minimize(*gd, p.objective, p.x0, options);
  ASSERT_EQ(s.history.size(), 4u);
  EXPECT_EQ(s.history_dropped, 21 - 4);
  EXPECT_EQ(s.history[0].iteration, 0);
  EXPECT_EQ(s.history[0].loss, s.initial_loss);
  for (int i = 1; i < 4; ++i) {
    EXPECT_EQ(s.history[static_cast<std::size_t>(i)].iteration, 17 + i);
    EXPECT_DOUBLE_EQ(s.history[static_cast<std::size_t>(i)].x(0), std::ldexp(0.48, -(17 + i)));
  }
  EXPECT_NE(full_report(s).find("4 records kept, 17 dropped (max_history)"), std::string::npos);
  // max_history_values = 6 entries of x, n = 2: 3 records.
  options.max_history = 100000;
  options.max_history_values = 6;
  EXPECT_EQ(minimize(*gd, p.objective, p.x0, options).history.size(), 3u);
  options.max_history = 1;
  EXPECT_THROW(minimize(*gd, p.objective, p.x0, options), Error);
}

}  // namespace
}  // namespace physgrad
