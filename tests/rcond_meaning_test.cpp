// rcond means one thing on every path: relative to the largest singular value σ of the matrix J
// pseudo-inverted. The normal-equation solve of direct Gauss-Newton (and Newton's Hessian solve)
// cuts λ = σ² at rcond²·λ_max, so that it drops the same directions as the SVD of J.
#include <gtest/gtest.h>

#include "physgrad/inversion/power_pinv.hpp"
#include "physgrad/optim/gauss_newton.hpp"
#include "physgrad/optim/newton.hpp"
#include "factored_jacobian.hpp"

namespace physgrad {
namespace {

using testing::factored;
using testing::Factored;
using testing::relative_error;

// σ = 1, 1e-4, 1e-8 with rcond = 1e-5: σ = 1e-4 is kept and σ = 1e-8 dropped on every path
// (on λ = σ² = 1e-8 and 1e-16 the cut is rcond² = 1e-10).
TEST(RcondMeaning, TheNormalEquationSolveDropsTheDirectionsTheSvdDrops) {
  Vector s(3);
  s << 1, 1e-4, 1e-8;
  const Factored f = factored(6, 4, s, 11);
  const Vector g = testing::random_normal(6, 1, 12).col(0);
  const double rcond = 1e-5;
  const Vector by_svd =
      power_pinv_apply(f.j, g, {.cut = {.rcond = rcond}, .backend = PinvBackend::kSvd});
  const Vector by_normal_equations =
      symmetric_pinv_apply(f.j.transpose() * f.j, f.j.transpose() * g, {.rcond = rcond});
  EXPECT_LT(relative_error(by_normal_equations, by_svd), 1e-6);
  EXPECT_LT(relative_error(by_svd, testing::formula(f, g, 1.0, rcond)), 1e-8);
}

// An indefinite symmetric matrix (Newton's Hessian) is cut on |λ| = σ²: |λ| = 1e-9 goes at
// rcond = 1e-4 (cut 1e-8·|λ|max) and stays at rcond = 1e-5 (cut 1e-10), where 1e-11 goes.
TEST(RcondMeaning, NewtonsHessianSolveCutsAbsoluteEigenvaluesAtRcondSquared) {
  const Matrix q = testing::random_orthonormal(3, 3, 5);
  Vector lambda(3);
  lambda << -1, 1e-9, 1e-11;
  const Matrix h = q * lambda.asDiagonal() * q.transpose();
  const Vector g = q * Vector::Ones(3);
  const Vector x = symmetric_pinv_apply(h, g, {.rcond = 1e-4});  // keeps |λ| > 1e-8: only −1
  EXPECT_LT((x - q.col(0) * -1.0).norm(), 1e-6);
  const Vector y = symmetric_pinv_apply(h, g, {.rcond = 1e-5});  // keeps |λ| > 1e-10: −1 and 1e-9
  const Vector expected = q.col(0) * -1.0 + q.col(1) * 1e9;
  EXPECT_LT((y - expected).norm(), 1e-5 * expected.norm());
}

// The direct rules' default cut, 1e-6 on σ, is the former 1e-12 on their eigenvalues.
TEST(RcondMeaning, DirectDefaultsKeepTheirFormerCutOnEigenvalues) {
  EXPECT_EQ(GaussNewtonOptions{}.rcond * GaussNewtonOptions{}.rcond, 1e-12);
  EXPECT_EQ(NewtonOptions{}.rcond * NewtonOptions{}.rcond, 1e-12);
}

}  // namespace
}  // namespace physgrad
