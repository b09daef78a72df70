// PoissonSolve (y solves laplace(y) = x, Dirichlet 0): derivatives against central differences,
// the solve against the stencil, the inverse against the forward, and the shape checks.
#include <gtest/gtest.h>

#include "physgrad/autodiff/finite_difference.hpp"
#include "physgrad/error.hpp"
#include "physgrad/physics/poisson_solve.hpp"
#include "test_problems.hpp"

namespace physgrad {
namespace {

TEST(PoissonSolve, DerivativesMatchFiniteDifferences) {
  for (const Index n : {1, 4, 8}) {
    const PoissonSolve physics(n);
    const DerivativeCheck check =
        check_derivatives(physics, testing::random_normal(n * n, 1, 3).col(0));
    EXPECT_TRUE(check.passed) << "n " << n << ": " << check.report();
  }
}

TEST(PoissonSolve, ForwardSolvesTheStencilAndInverseUndoesIt) {
  for (const Index n : {8, 64}) {
    const PoissonSolve physics(n);
    const Poisson stencil(n);
    const Matrix x = testing::random_normal(n * n, 1, 4);
    const Matrix y = physics.forward_batch(x, Matrix());
    // laplace(P(x)) = x: the solve is exact to round-off.
    EXPECT_LT((stencil.forward_batch(y, Matrix()) - x).norm() / x.norm(), 1e-12) << "n " << n;
    // P(P⁻¹(y)) = y and P⁻¹(P(x)) = x.
    const Vector target = testing::random_normal(n * n, 1, 5).col(0);
    EXPECT_LT(inverse_residual(physics, target, Vector::Zero(n * n)), 1e-10) << "n " << n;
    EXPECT_LT((physics.inverse(y.col(0), x.col(0)) - x.col(0)).norm() / x.norm(), 1e-12);
  }
}

TEST(PoissonSolve, RejectsBadShapes) {
  EXPECT_THROW(PoissonSolve(0), Error);
  const PoissonSolve physics(4);
  EXPECT_THROW(physics.forward(Vector::Zero(15)), Error);
  EXPECT_THROW(physics.vjp(Vector::Zero(16), {}, Vector::Zero(15)), Error);
  EXPECT_THROW(physics.inverse(Vector::Zero(15), Vector::Zero(16)), Error);
  EXPECT_THROW(physics.inverse(Vector::Zero(16), Vector::Zero(15)), Error);
}

}  // namespace
}  // namespace physgrad
