// Simulators of the scale-invariance chapter: derivatives vs finite differences, inverses vs
// forward, and the shape checks at the interface.
#include <gtest/gtest.h>

#include "physgrad/autodiff/finite_difference.hpp"
#include "physgrad/error.hpp"
#include "physgrad/physics/comparison_toy.hpp"
#include "physgrad/physics/diagonal_scale.hpp"
#include "test_problems.hpp"

namespace physgrad {
namespace {

TEST(DiagonalScale, DerivativesMatchFiniteDifferences) {
  for (const double alpha : {1e-3, 1.0, 10.0, 1000.0}) {
    const DiagonalScale physics(Vector{{1.0, alpha}});
    const DerivativeCheck check = check_derivatives(physics, Vector{{0.48, -0.84}});
    EXPECT_TRUE(check.passed) << "alpha " << alpha << ": " << check.report();
  }
}

TEST(DiagonalScale, InverseReproducesForward) {
  const DiagonalScale physics(Vector{{1.0, -250.0, 3e-4}});
  const Vector y{{0.3, -7.0, 2.0}};
  EXPECT_LT(inverse_residual(physics, y, Vector::Zero(3)), 1e-15);
  EXPECT_TRUE(physics.inverse(y, Vector::Zero(3)).isApprox(Vector{{0.3, 0.028, 2.0 / 3e-4}}));
}

TEST(DiagonalScale, RejectsZeroOrNonFiniteScalesAndWrongShapes) {
  EXPECT_THROW(DiagonalScale(Vector{{1.0, 0.0}}), Error);
  EXPECT_THROW(DiagonalScale(Vector{{1.0, std::nan("")}}), Error);
  EXPECT_THROW(DiagonalScale(Vector{}), Error);
  const DiagonalScale physics(Vector{{1.0, 2.0}});
  EXPECT_THROW(physics.forward(Vector::Zero(3)), Error);
  EXPECT_THROW(physics.forward_batch(Matrix::Zero(2, 4), Matrix::Zero(1, 3)), Error);
}

TEST(ComparisonToy, DerivativesMatchFiniteDifferences) {
  const ComparisonToy physics;
  for (const Vector& x : {Vector{{3.0, 3.0}}, Vector{{-0.5, 0.2}}, Vector{{1.0, -2.0}}}) {
    const DerivativeCheck check = check_derivatives(physics, x);
    EXPECT_TRUE(check.passed) << x.transpose() << ": " << check.report();
  }
  // The analytic second derivative agrees with the generic VJP-difference default.
  const Vector x{{0.7, -1.3}}, w{{0.4, -2.5}};
  EXPECT_TRUE(physics.weighted_hessian(x, {}, w)
                  .isApprox(physics.Simulator::weighted_hessian(x, {}, w), 1e-7));
}

TEST(ComparisonToy, LocalInverseTakesTheBranchOfTheGuess) {
  const ComparisonToy physics;
  const Vector y{{2.0, 2.0}};
  EXPECT_LT(inverse_residual(physics, y, Vector{{3.0, 3.0}}), 1e-15);
  EXPECT_NEAR(physics.inverse(y, Vector{{3.0, 3.0}})(1), std::sqrt(2.0), 1e-15);
  EXPECT_NEAR(physics.inverse(y, Vector{{3.0, -0.1}})(1), -std::sqrt(2.0), 1e-15);
  // No real preimage for y₁ < 0: the nearest output is reached at x₁ = 0.
  EXPECT_EQ(physics.inverse(Vector{{1.0, -4.0}}, Vector{{1.0, 1.0}})(1), 0.0);
}

TEST(SimulatorDefaults, JacobianFromVjpAndHessianFromDifferencesAreRight) {
  const testing::Rosenbrock physics(4);
  const Vector x{{-1.2, 1.0, 0.3, 0.7}};
  const DerivativeCheck check = check_derivatives(physics, x);
  EXPECT_TRUE(check.passed) << check.report();
  // Exact: Σ_k w_k ∂²P_k/∂x² has −20 w_{2i} on the diagonal entry of x_{2i}.
  const Vector w{{1.0, 2.0, -3.0, 4.0}};
  const Matrix h = physics.weighted_hessian(x, {}, w);
  Matrix expected = Matrix::Zero(4, 4);
  expected(0, 0) = -20 * w(0);
  expected(2, 2) = -20 * w(2);
  EXPECT_LT((h - expected).cwiseAbs().maxCoeff(), 1e-7);
}

TEST(FiniteDifferenceCheck, DetectsAWrongVjp) {
  // A simulator whose VJP forgets the factor 2 of ∂(x²)/∂x must fail the check.
  class WrongVjp final : public Simulator {
   public:
    std::string name() const override { return "wrong"; }
    Index input_dim() const override { return 1; }
    Index output_dim() const override { return 1; }
    Matrix forward_batch(const Matrix& x, const Matrix&) const override {
      return x.array().square();
    }
    Matrix vjp_batch(const Matrix& x, const Matrix&, const Matrix& gy) const override {
      return x.cwiseProduct(gy);
    }
  };
  const DerivativeCheck check = check_derivatives(WrongVjp(), Vector{{1.5}});
  EXPECT_FALSE(check.passed);
  EXPECT_GT(check.jacobian_error, 0.1);
}

}  // namespace
}  // namespace physgrad
