#include "physgrad/inversion/tridiagonal_eigen.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "physgrad/error.hpp"
#include "test_problems.hpp"

namespace physgrad {
namespace {

// A symmetric tridiagonal T: its diagonal, subdiagonal and the dense matrix.
struct Tridiagonal {
  Vector d, e;
  Matrix dense() const {
    const Index n = d.size();
    Matrix t = Matrix::Zero(n, n);
    t.diagonal() = d;
    if (n > 1) {
      t.diagonal(1) = e;
      t.diagonal(-1) = e;
    }
    return t;
  }
};

// d and then e drawn from N(0, 1).
Tridiagonal random_tridiagonal(Index n, unsigned seed) {
  const Vector entries = testing::random_normal(std::max<Index>(2 * n - 1, 0), 1, seed);
  return {entries.head(n), entries.tail(std::max<Index>(n - 1, 0))};
}

Vector random_vector(Index n, unsigned seed) { return testing::random_normal(n, 1, seed); }

// What every decomposition must satisfy, to `tolerance` relative to ‖T‖: its eigenvalues are
// T's (dense solver), S is orthogonal (S Sᵀ v = v, ‖Sᵀ v‖ = ‖v‖) and S Λ Sᵀ v = T v.
void expect_decomposes(const Tridiagonal& t, double tolerance) {
  const Matrix dense = t.dense();
  const Index n = dense.rows();
  const TridiagonalEigen eig(t.d, t.e);
  const double norm = std::max(dense.norm(), std::numeric_limits<double>::min());
  Vector sorted = eig.eigenvalues();
  std::sort(sorted.data(), sorted.data() + n);
  const Vector expected = Eigen::SelfAdjointEigenSolver<Matrix>(dense).eigenvalues();
  EXPECT_LT((sorted - expected).cwiseAbs().maxCoeff(), tolerance * norm);
  const Vector v = random_vector(n, 7);
  const Vector rotated = eig.apply_transpose(v);
  EXPECT_NEAR(rotated.norm(), v.norm(), tolerance * v.norm());
  EXPECT_LT((eig.apply(rotated) - v).norm(), tolerance * v.norm());
  const Vector tv = eig.apply(eig.eigenvalues().cwiseProduct(rotated));
  EXPECT_LT((tv - dense * v).norm(), tolerance * norm * v.norm());
}

TEST(TridiagonalEigen, DecomposesRandomMatrices) {
  for (const Index n : {2, 3, 17, 200}) {
    SCOPED_TRACE(n);
    expect_decomposes(random_tridiagonal(n, static_cast<unsigned>(n)), 1e-13);
  }
}

// Eigenvalues spanning 1 … 1e-12 (the Gram matrices' range) and Wilkinson's W21⁺, whose largest
// eigenvalues come in pairs that agree to 1e-14 and more: the rotations stay orthogonal and
// the reconstruction exact, and the iteration needs about n² rotations, as the header says.
TEST(TridiagonalEigen, DecomposesWideSpectraAndCloseEigenvalues) {
  Tridiagonal graded = random_tridiagonal(120, 3);
  for (Index i = 0; i < 120; ++i) graded.d(i) = std::pow(10.0, -12.0 * static_cast<double>(i) / 119);
  graded.e *= 1e-3;
  expect_decomposes(graded, 1e-13);

  Tridiagonal wilkinson{Vector(21), Vector::Ones(20)};
  for (Index i = 0; i < 21; ++i) wilkinson.d(i) = std::abs(static_cast<double>(i - 10));
  expect_decomposes(wilkinson, 1e-13);

  const Tridiagonal large = random_tridiagonal(400, 11);
  const TridiagonalEigen eig(large.d, large.e);
  EXPECT_GT(eig.rotations(), 400u * 400u / 2);
  EXPECT_LT(eig.rotations(), 2u * 400u * 400u);
}

// The iteration runs on T scaled by a power of two, so T·2^±600 gives the same rotations and
// eigenvalues scaled by exactly 2^±600.
TEST(TridiagonalEigen, ScalingByAPowerOfTwoIsExact) {
  const Tridiagonal t = random_tridiagonal(60, 5);
  const TridiagonalEigen eig(t.d, t.e);
  const Vector v = random_vector(60, 9);
  for (const int exponent : {600, -600}) {
    const double scale = std::ldexp(1.0, exponent);
    const TridiagonalEigen scaled(t.d * scale, t.e * scale);
    EXPECT_TRUE(scaled.eigenvalues() == eig.eigenvalues() * scale) << exponent;
    EXPECT_TRUE(scaled.apply_transpose(v) == eig.apply_transpose(v)) << exponent;
  }
}

// A graded T is always iterated with its larger end at the bottom, so T and its reversal P T P
// give the same eigenvalues, bit for bit, and S_PTPᵀ (P v) = S_Tᵀ v.
TEST(TridiagonalEigen, AMatrixAndItsReversalDecomposeAlike) {
  Tridiagonal graded = random_tridiagonal(80, 13);
  for (Index i = 0; i < 80; ++i) graded.d(i) = std::pow(10.0, -8.0 * static_cast<double>(i) / 79);
  Tridiagonal reversed{graded.d.reverse(), graded.e.reverse()};
  const TridiagonalEigen eig(graded.d, graded.e), eig_reversed(reversed.d, reversed.e);
  EXPECT_TRUE(eig.eigenvalues() == eig_reversed.eigenvalues());
  const Vector v = random_vector(80, 17);
  EXPECT_TRUE(eig_reversed.apply_transpose(v.reverse()) == eig.apply_transpose(v));
  EXPECT_TRUE(eig_reversed.apply(v) == eig.apply(v).reverse());
  expect_decomposes(graded, 1e-13);
  expect_decomposes(reversed, 1e-13);
}

TEST(TridiagonalEigen, DiagonalZeroAndTinyMatricesNeedNoRotation) {
  const Vector d = Vector::LinSpaced(5, -2.0, 2.0);
  const TridiagonalEigen diagonal(d, Vector::Zero(4));
  EXPECT_TRUE(diagonal.eigenvalues() == d);
  EXPECT_EQ(diagonal.rotations(), 0u);
  const Vector v = random_vector(5, 1);
  EXPECT_TRUE(diagonal.apply(v) == v);

  const TridiagonalEigen zero(Vector::Zero(4), Vector::Zero(3));
  EXPECT_TRUE(zero.eigenvalues() == Vector::Zero(4));

  const TridiagonalEigen one(Vector::Constant(1, 3.0), Vector(0));
  EXPECT_EQ(one.eigenvalues()(0), 3.0);
  const TridiagonalEigen empty(Vector(0), Vector(0));
  EXPECT_EQ(empty.eigenvalues().size(), 0);
  EXPECT_EQ(empty.apply(Vector(0)).size(), 0);
}

TEST(TridiagonalEigen, BadInputIsAnError) {
  EXPECT_THROW(TridiagonalEigen(Vector::Ones(3), Vector::Ones(3)), Error);
  Vector e = Vector::Ones(2);
  e(1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(TridiagonalEigen(Vector::Ones(3), e), NumericalError);
  const TridiagonalEigen eig(Vector::Ones(3), Vector::Ones(2));
  EXPECT_THROW(eig.apply(Vector::Ones(2)), Error);
  EXPECT_THROW(eig.apply_transpose(Vector::Ones(4)), Error);
}

}  // namespace
}  // namespace physgrad
