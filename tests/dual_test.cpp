#include "physgrad/autodiff/dual.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <type_traits>

#include "physgrad/autodiff/finite_difference.hpp"
#include "physgrad/error.hpp"
#include "physgrad/physics/comparison_toy.hpp"
#include "physgrad/physics/diagonal_scale.hpp"

namespace physgrad {
namespace {

// Every operator and function of Dual, written once for double and Dual.
template <typename T>
T every_operation(const T& a, const T& b) {
  using std::abs, std::atan, std::atan2, std::cos, std::exp, std::log, std::pow, std::sin,
      std::sqrt, std::tan, std::tanh;
  T r = sin(a) * exp(b) / (1.0 + a * a) + pow(a, 3.0) - atan2(b, a);
  r += sqrt(1.0 + b * b) * log(2.0 + a);
  r += tanh(a - b) + pow(1.5 + a * a, b) + tan(0.3 * a) + atan(b) - cos(b) + abs(a - 3.0);
  r -= 2.0 - a / 4.0;
  r *= 0.5;
  r /= 1.0 + 3.0 / (2.0 + b * b);
  return -r + a * 2;
}

TEST(Dual, OperationsMatchFiniteDifferences) {
  const Vector x{{0.7, -0.4}};
  const auto f = [](const Vector& v) { return Vector{{every_operation(v(0), v(1))}}; };
  const Matrix expected = finite_difference_jacobian(f, x);
  const Dual<2> a(x(0), Dual<2>::Derivatives(1, 0));
  const Dual<2> b(x(1), Dual<2>::Derivatives(0, 1));
  const Dual<2> r = every_operation(a, b);
  EXPECT_DOUBLE_EQ(r.value, every_operation(x(0), x(1)));
  EXPECT_NEAR(r.derivatives(0), expected(0, 0), 1e-8);
  EXPECT_NEAR(r.derivatives(1), expected(0, 1), 1e-8);
}

TEST(Dual, ComparisonsLookAtTheValueOnly) {
  const Dual<1> a(1.0, Dual<1>::Derivatives(5.0));
  const Dual<1> b(2.0, Dual<1>::Derivatives(-1.0));
  EXPECT_TRUE(a < b);
  EXPECT_TRUE(a == Dual<1>(1.0));
  EXPECT_TRUE(0.5 < a && a <= 1);
  EXPECT_EQ(std::max(a, b).derivatives(0), -1.0);  // the branch taken
}

TEST(Dual, EigenExpressionsMixDoubleAndDual) {
  const Matrix a{{1.0, 2.0}, {-3.0, 0.5}, {4.0, 1.0}};
  Eigen::Matrix<Dual<2>, Eigen::Dynamic, 1> x(2);
  x << Dual<2>(0.3, Dual<2>::Derivatives(1, 0)), Dual<2>(-1.2, Dual<2>::Derivatives(0, 1));
  const Eigen::Matrix<Dual<2>, Eigen::Dynamic, 1> y = a * x;
  const Dual<2> norm2 = y.squaredNorm();
  const Vector xv{{0.3, -1.2}};
  for (Index k = 0; k < 3; ++k) {
    EXPECT_DOUBLE_EQ(y(k).value, (a * xv)(k));
    EXPECT_DOUBLE_EQ(y(k).derivatives(0), a(k, 0));
    EXPECT_DOUBLE_EQ(y(k).derivatives(1), a(k, 1));
  }
  const Vector gradient = 2.0 * a.transpose() * (a * xv);  // ∇‖Ax‖²
  EXPECT_NEAR(norm2.derivatives(0), gradient(0), 1e-12);
  EXPECT_NEAR(norm2.derivatives(1), gradient(1), 1e-12);
}

struct ComparisonFunction {
  template <typename T>
  Eigen::Matrix<T, Eigen::Dynamic, 1> operator()(const Eigen::Matrix<T, Eigen::Dynamic, 1>& x,
                                                 const Vector& /*context*/) const {
    Eigen::Matrix<T, Eigen::Dynamic, 1> y(2);
    y << x(0), x(1) * x(1);
    return y;
  }
};

TEST(DualSimulator, MatchesTheHandWrittenComparisonToy) {
  const ComparisonToy hand;
  const AutoDiffSimulator dual(ComparisonFunction{}, "comparison_dual", 2, 2);
  const Matrix x{{3.0, -1.0, 0.2}, {3.0, 0.5, -2.0}};
  const Matrix gy{{1.0, -2.0, 0.3}, {0.5, 4.0, -1.0}};
  EXPECT_TRUE(dual.forward_batch(x, {}).isApprox(hand.forward_batch(x, {}), 1e-15));
  EXPECT_TRUE(dual.vjp_batch(x, {}, gy).isApprox(hand.vjp_batch(x, {}, gy), 1e-15));
  EXPECT_TRUE(dual.jacobian(x.col(2)).isApprox(hand.jacobian(x.col(2)), 1e-15));
}

// A width of 4 splits the 11 inputs into passes of 4, 4 and 3 lanes.
TEST(DualSimulator, ChunkedJacobianMatchesDiagonalScale) {
  Vector scales(11);
  for (Index i = 0; i < scales.size(); ++i) scales(i) = std::pow(10.0, static_cast<double>(i % 4));
  const DiagonalScale hand(scales);
  const auto scale = [scales](const auto& x, const Vector& /*context*/) {
    using T = typename std::decay_t<decltype(x)>::Scalar;
    return Eigen::Matrix<T, Eigen::Dynamic, 1>(scales.cwiseProduct(x));
  };
  const AutoDiffSimulator<decltype(scale), 4> dual(scale, "scale_dual", 11, 11);
  const Vector x = Vector::LinSpaced(11, -1.0, 2.0);
  EXPECT_EQ(dual.jacobian(x), hand.jacobian(x));
  const Matrix gy = Matrix::Ones(11, 2);
  const Matrix xs = x.replicate(1, 2);
  EXPECT_TRUE(dual.vjp_batch(xs, {}, gy).isApprox(hand.vjp_batch(xs, {}, gy)));
}

// A nonlinear map R¹¹ → R³ with a 2-entry context.
struct Mixing {
  template <typename T>
  Eigen::Matrix<T, Eigen::Dynamic, 1> operator()(const Eigen::Matrix<T, Eigen::Dynamic, 1>& x,
                                                 const Vector& context) const {
    using std::cos, std::exp, std::sin;
    Eigen::Matrix<T, Eigen::Dynamic, 1> y(3);
    y(0) = context(0) * x.squaredNorm();
    y(1) = sin(x(0) * x(10)) + context(1) * exp(x.head(5).sum() / 5.0);
    y(2) = T(0.0);
    for (Index i = 0; i < x.size(); ++i) y(2) += cos(static_cast<double>(i) * x(i)) * x(i);
    return y;
  }
};

TEST(DualSimulator, ContextAndChunksMatchFiniteDifferences) {
  const AutoDiffSimulator<Mixing, 4> dual(Mixing{}, "mixing", 11, 3, 2);
  const Vector x = Vector::LinSpaced(11, -0.5, 0.8);
  const Vector c{{0.7, -1.3}};
  const Matrix expected =
      finite_difference_jacobian([&](const Vector& v) { return dual.forward(v, c); }, x);
  EXPECT_LT((dual.jacobian(x, c) - expected).cwiseAbs().maxCoeff(), 1e-8);
  const DerivativeCheck check = check_derivatives(dual, x, c, 1e-6);
  EXPECT_TRUE(check.passed) << check.report();
}

TEST(DualSimulator, RejectsBadShapesNamingThem) {
  EXPECT_THROW(AutoDiffSimulator(ComparisonFunction{}, "bad", 0, 2), Error);
  const AutoDiffSimulator wrong_m(ComparisonFunction{}, "wrong_m", 2, 3);
  try {
    wrong_m.forward(Vector::Zero(2));
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("returned 2 outputs, expected output_dim 3"),
              std::string::npos)
        << e.what();
  }
  const AutoDiffSimulator ok(ComparisonFunction{}, "ok", 2, 2);
  EXPECT_THROW(ok.vjp_batch(Matrix::Zero(2, 2), {}, Matrix::Zero(2, 3)), Error);
  EXPECT_THROW(ok.jacobian(Vector::Zero(3)), Error);
}

}  // namespace
}  // namespace physgrad
