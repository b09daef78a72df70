// Poisson (5-point Dirichlet Laplacian): derivatives against central differences, the stencil
// and its symmetry, the exact inverse and the shape checks.
#include <gtest/gtest.h>

#include <random>

#include "physgrad/autodiff/finite_difference.hpp"
#include "physgrad/error.hpp"
#include "physgrad/physics/poisson.hpp"

namespace physgrad {
namespace {

Vector random_vector(std::mt19937_64& rng, Index size) {
  std::normal_distribution<double> normal;
  Vector v(size);
  for (Index i = 0; i < size; ++i) v(i) = normal(rng);
  return v;
}

TEST(Poisson, DerivativesMatchFiniteDifferences) {
  std::mt19937_64 rng(1);
  for (const Index n : {1, 3, 8}) {
    const Poisson physics(n);
    const DerivativeCheck check = check_derivatives(physics, random_vector(rng, n * n));
    EXPECT_TRUE(check.passed) << "n " << n << ": " << check.report();
  }
}

TEST(Poisson, JacobianIsTheSymmetricFivePointStencil) {
  const Poisson physics;
  const Matrix j = physics.jacobian(Vector::Zero(64));
  EXPECT_EQ((j - j.transpose()).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(j.diagonal(), Vector::Constant(64, -4.0));
  // Cell (i, j) = (2, 3) is entry 2 + 8·3 = 26; its neighbours are 25, 27, 18 and 34.
  EXPECT_EQ(j.row(26).sum(), 0.0);
  EXPECT_EQ(j(26, 25) + j(26, 27) + j(26, 18) + j(26, 34), 4.0);
  // Corner (0, 0) sees two zero ghost cells: its row sums to −2.
  EXPECT_EQ(j.row(0).sum(), -2.0);
  EXPECT_EQ(j(0, 1) + j(0, 8), 2.0);
}

TEST(Poisson, InverseSolvesTheLaplaceEquation) {
  std::mt19937_64 rng(2);
  for (const Index n : {8, 64}) {
    const Poisson physics(n);
    const Vector y = random_vector(rng, n * n);
    EXPECT_LT(inverse_residual(physics, y, Vector::Zero(n * n)), 1e-12) << "n " << n;
    const Vector x = random_vector(rng, n * n);
    EXPECT_LT((physics.inverse(physics.forward(x), x) - x).norm() / x.norm(), 1e-12) << "n " << n;
  }
}

TEST(Poisson, RejectsBadShapes) {
  EXPECT_THROW(Poisson(0), Error);
  const Poisson physics(4);
  EXPECT_THROW(physics.forward(Vector::Zero(15)), Error);
  EXPECT_THROW(physics.vjp(Vector::Zero(16), {}, Vector::Zero(15)), Error);
  EXPECT_THROW(physics.inverse(Vector::Zero(15), Vector::Zero(16)), Error);
  EXPECT_THROW(physics.inverse(Vector::Zero(16), Vector::Zero(15)), Error);
}

}  // namespace
}  // namespace physgrad
