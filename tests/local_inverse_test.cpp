// The numerical local inverse's options: the tolerance relative to the start residual, the stall
// test on an unreachable y, the gn inverse's cutoff on the singular values of an ill-conditioned
// J (heat diffusion), the box, and the option checks; every method reports converged only when
// the tolerance was met, and refuses non-finite input.
#include <gtest/gtest.h>

#include <cmath>

#include "physgrad/error.hpp"
#include "physgrad/optim/local_inverse.hpp"
#include "physgrad/physics/comparison_toy.hpp"
#include "physgrad/physics/heat_diffusion.hpp"
#include "test_problems.hpp"

namespace physgrad {
namespace {

// P(x) = 2x on R², with an inverse y/2 + offset and a time reversal R(y) = y/2 + curl·y⊙y (the
// anchored reversal is exact for curl = 0, off by about curl·|Δy|² otherwise).
class Doubling final : public Simulator {
 public:
  Doubling(double offset, double curl) : offset_(offset), curl_(curl) {}
  std::string name() const override { return "doubling"; }
  Index input_dim() const override { return 2; }
  Index output_dim() const override { return 2; }
  Matrix forward_batch(const Matrix& x, const Matrix& context) const override {
    check_batch(x, context, "forward_batch");
    return 2 * x;
  }
  Matrix vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const override {
    check_batch(x, context, "vjp_batch");
    return 2 * gy;
  }
  bool has_inverse() const override { return true; }
  Vector inverse(const Vector& y, const Vector&, const Vector&) const override {
    return (0.5 * y).array() + offset_;
  }
  bool has_time_reversal() const override { return true; }
  Vector time_reversal(const Vector& y, const Vector&) const override {
    return 0.5 * y + curl_ * y.cwiseProduct(y);
  }

 private:
  double offset_, curl_;
};

TEST(LocalInverse, ClosedFormsAreConvergedOnlyWhenTheToleranceIsMet) {
  const Vector x0{{0.0, 0.0}}, y{{3.0, -4.0}};  // ‖P(x₀) − y‖ = 5
  const LocalInverseOptions analytic{.method = InverseMethod::kAnalytic};
  const LocalInverseResult exact = local_inverse(Doubling(0, 0), y, x0, {}, analytic);
  EXPECT_TRUE(exact.converged);
  EXPECT_EQ(exact.residual, 0.0);
  EXPECT_EQ(exact.evaluations, 2);
  // An inverse that is off by 1 in each entry: residual 2√2, far above 1e-10·(1 + 5).
  const LocalInverseResult off = local_inverse(Doubling(1, 0), y, x0, {}, analytic);
  EXPECT_NEAR(off.residual, 2 * std::sqrt(2.0), 1e-12);
  EXPECT_FALSE(off.converged);
  // Off by 1e-9: 2.8e-9 misses the absolute test (6e-10) but meets the relative one
  // (1e-8·5 = 5e-8), for which P(x₀) costs one more forward pass.
  const LocalInverseResult close = local_inverse(Doubling(1e-9, 0), y, x0, {}, analytic);
  EXPECT_TRUE(close.converged);
  EXPECT_EQ(close.evaluations, 3);
  LocalInverseOptions absolute_only = analytic;
  absolute_only.relative_tolerance = 0;
  EXPECT_FALSE(local_inverse(Doubling(1e-9, 0), y, x0, {}, absolute_only).converged);

  const LocalInverseOptions reversal{.method = InverseMethod::kTimeReversal};
  EXPECT_TRUE(local_inverse(Doubling(0, 0), y, x0, {}, reversal).converged);
  const LocalInverseResult curled = local_inverse(Doubling(0, 0.1), y, x0, {}, reversal);
  EXPECT_GT(curled.residual, 1.0);
  EXPECT_FALSE(curled.converged);
}

TEST(LocalInverse, NonFiniteInputIsRefusedByEveryMethodNamingTheEntry) {
  const Vector x0{{0.0, 0.0}};
  for (const InverseMethod method : {InverseMethod::kAuto, InverseMethod::kAnalytic,
                                     InverseMethod::kTimeReversal, InverseMethod::kLbfgs,
                                     InverseMethod::kInverseGradient}) {
    const auto message = [&](const Simulator& physics, const Vector& y, const Vector& x) {
      try {
        local_inverse(physics, y, x, {}, {.method = method});
      } catch (const NumericalError& e) {
        return std::string(e.what());
      }
      return std::string("no NumericalError");
    };
    const Doubling exact(0, 0);
    EXPECT_EQ(message(exact, Vector{{1.0, NAN}}, x0),
              "local inverse: y has a non-finite entry at index 1 (nan)")
        << to_string(method);
    EXPECT_EQ(message(exact, Vector{{1.0, 1.0}}, Vector{{-INFINITY, 0.0}}),
              "local inverse: x0 has a non-finite entry at index 0 (-inf)")
        << to_string(method);
  }
  // An inverse that answers NaN is named, not handed on.
  EXPECT_EQ(
      [] {
        try {
          local_inverse(Doubling(NAN, 0), Vector{{1.0, 1.0}}, Vector{{0.0, 0.0}}, {},
                        {.method = InverseMethod::kAnalytic});
        } catch (const NumericalError& e) {
          return std::string(e.what());
        }
        return std::string("no NumericalError");
      }(),
      "the local inverse (analytic) gave no finite preimage: the simulator's inverse (analytic) "
      "has a non-finite entry at index 0 (nan)");
}

TEST(LocalInverse, RelativeToleranceStopsAtAFractionOfTheStartResidual) {
  // y = (2, 2) from (3, 3): start residual ‖(3, 9) − (2, 2)‖ = √50.
  const ComparisonToy physics;
  const Vector y{{2.0, 2.0}}, x0{{3.0, 3.0}};
  LocalInverseOptions options{.method = InverseMethod::kLbfgs, .tolerance = 1e-14};
  options.relative_tolerance = 1e-3;
  const LocalInverseResult loose = local_inverse(physics, y, x0, {}, options);
  options.relative_tolerance = 1e-9;
  const LocalInverseResult tight = local_inverse(physics, y, x0, {}, options);
  const double start = std::sqrt(50.0);
  EXPECT_TRUE(loose.converged);
  EXPECT_LE(loose.residual, 1e-3 * start);
  EXPECT_LE(tight.residual, 1e-9 * start);
  EXPECT_LT(loose.iterations, tight.iterations);
  EXPECT_LT(loose.evaluations, tight.evaluations);
}

TEST(LocalInverse, AnUnreachableTargetEndsAtTheStallInsteadOfTheIterationBudget) {
  // P(x) = (x, x) cannot reach y = (1, −1): the best preimage is x = 0 with residual √2.
  const testing::LinearSimulator physics((Matrix(2, 1) << 1, 1).finished());
  const Vector y{{1.0, -1.0}};
  for (const InverseMethod method : {InverseMethod::kLbfgs, InverseMethod::kInverseGradient}) {
    const LocalInverseResult r =
        local_inverse(physics, y, Vector{{3.0}}, {}, {.method = method, .max_iterations = 200});
    EXPECT_FALSE(r.converged) << to_string(method);
    EXPECT_NEAR(r.x(0), 0.0, 1e-8) << to_string(method);
    EXPECT_NEAR(r.residual, std::sqrt(2.0), 1e-12) << to_string(method);
    EXPECT_LT(r.iterations, 10) << to_string(method);
  }
}

TEST(LocalInverse, GaussNewtonResolvesIllConditionedDiffusionWithItsDefaultCutoff) {
  // 1-D diffusion of 32 cells, amount 2: the singular values of J run from 1 down to 2.7e-9.
  const HeatDiffusion physics({32, 1, 2.0});
  Vector x_true(32);
  for (Index i = 0; i < 32; ++i) x_true(i) = std::sin(0.7 * static_cast<double>(i * i));
  const Vector y = physics.forward(x_true);
  LocalInverseOptions options{.method = InverseMethod::kInverseGradient};
  const LocalInverseResult resolved = local_inverse(physics, y, Vector::Zero(32), {}, options);
  EXPECT_TRUE(resolved.converged);
  EXPECT_LE(resolved.iterations, 2);
  EXPECT_LE(resolved.residual, 1e-10 * (1 + y.norm()));
  // A cutoff of 1e-6·σ_max (what a cutoff of 1e-12 on the eigenvalues of JᵀJ keeps) drops the
  // smallest modes: the residual stays above the tolerance and the solve ends at its stall.
  options.rcond = 1e-6;
  const LocalInverseResult truncated = local_inverse(physics, y, Vector::Zero(32), {}, options);
  EXPECT_FALSE(truncated.converged);
  EXPECT_GT(truncated.residual, 1e-9);
  EXPECT_LT(truncated.iterations, 10);
}

TEST(LocalInverse, NumericalInversesStayInTheBoxAndClosedFormsAreProjected) {
  // y = (2, 2) has the preimage (2, ±√2); with x₁ ≤ 1 the nearest feasible point is (2, 1).
  const ComparisonToy physics;
  const Domain box(2, Vector{{-10.0, -10.0}}, Vector{{10.0, 1.0}}, {});
  for (const InverseMethod method :
       {InverseMethod::kLbfgs, InverseMethod::kInverseGradient, InverseMethod::kAnalytic}) {
    const LocalInverseResult r =
        local_inverse(physics, Vector{{2.0, 2.0}}, Vector{{0.5, 0.5}}, {}, {.method = method}, box);
    EXPECT_NEAR(r.x(0), 2.0, 1e-8) << to_string(method);
    EXPECT_NEAR(r.x(1), 1.0, 1e-8) << to_string(method);
    EXPECT_LE(r.x(1), 1.0) << to_string(method);
    EXPECT_FALSE(r.converged) << to_string(method);  // ‖P(x) − y‖ = 1
  }
}

TEST(LocalInverse, OutOfRangeOptionsAndMissingCapabilitiesAreErrors) {
  const ComparisonToy physics;
  const Vector y{{2.0, 2.0}}, x0{{3.0, 3.0}};
  const auto message = [&](const LocalInverseOptions& options) {
    try {
      local_inverse(physics, y, x0, {}, options);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message({.method = InverseMethod::kLbfgs, .relative_tolerance = 1.5}),
            "local inverse: inverse_relative_tolerance must be in [0, 1), got 1.5");
  EXPECT_EQ(message({.method = InverseMethod::kInverseGradient, .rcond = -1}),
            "local inverse: inverse_rcond must be in [0, 1), got -1");
  EXPECT_EQ(message({.method = InverseMethod::kLbfgs, .max_iterations = 0}),
            "local inverse: inverse_iterations must be an integer in [1, 2147483647], got 0");
  EXPECT_EQ(message({.method = InverseMethod::kTimeReversal}),
            "simulator 'comparison_toy' has no time reversal; use a numerical inverse (lbfgs or ig)");
  EXPECT_THROW(parse_inverse_method("reverse"), Error);
  // "gn" names Gauss-Newton only; the inverse that runs inverse-gradient steps is "ig".
  EXPECT_EQ(parse_inverse_method("ig"), InverseMethod::kInverseGradient);
  EXPECT_EQ(to_string(InverseMethod::kInverseGradient), "ig");
  try {
    parse_inverse_method("gn");
    ADD_FAILURE() << "gn was taken for an inverse method";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(),
                 "unknown inverse method 'gn' (known: auto, analytic, time_reversal, lbfgs, ig)");
  }
}

}  // namespace
}  // namespace physgrad
