// Forward-mode dual numbers and AutoDiffSimulator: a value with N directional derivatives,
// a + Σᵢ bᵢεᵢ with εᵢεⱼ = 0, so f(a + bε) = f(a) + f'(a)·bε gives J = ∂P/∂x column by column.
#pragma once

#include <algorithm>
#include <cmath>
#include <compare>
#include <sstream>
#include <string>
#include <utility>

#include "physgrad/error.hpp"
#include "physgrad/physics/simulator.hpp"

namespace physgrad {

// A number carrying its value and N derivatives (one per seeded input direction). Arithmetic
// and the math functions below apply the chain rule to every derivative at once. Comparisons
// look at the value only, so branches (if, max, min) differentiate the branch taken.
// Call math functions unqualified (`using std::sin; sin(x)`) so templated code finds these
// overloads by argument-dependent lookup for Dual and std:: ones for double.
template <int N>
struct Dual {
  static_assert(N >= 1, "a Dual needs at least one derivative");
  using Derivatives = Eigen::Array<double, N, 1>;

  double value = 0;
  Derivatives derivatives = Derivatives::Zero();

  Dual() = default;
  // A constant: every derivative zero. Implicit, so double constants mix with duals.
  Dual(double v) : value(v) {}  // NOLINT(google-explicit-constructor)
  Dual(double v, const Derivatives& d) : value(v), derivatives(d) {}

  Dual& operator+=(const Dual& b) {
    value += b.value;
    derivatives += b.derivatives;
    return *this;
  }
  Dual& operator-=(const Dual& b) {
    value -= b.value;
    derivatives -= b.derivatives;
    return *this;
  }
  Dual& operator*=(const Dual& b) {
    derivatives = derivatives * b.value + value * b.derivatives;
    value *= b.value;
    return *this;
  }
  Dual& operator/=(const Dual& b) {
    const double inverse = 1.0 / b.value;
    value *= inverse;
    derivatives = (derivatives - value * b.derivatives) * inverse;
    return *this;
  }
  Dual& operator+=(double b) {
    value += b;
    return *this;
  }
  Dual& operator-=(double b) {
    value -= b;
    return *this;
  }
  Dual& operator*=(double b) {
    value *= b;
    derivatives *= b;
    return *this;
  }
  Dual& operator/=(double b) { return *this *= 1.0 / b; }

  friend Dual operator+(const Dual& a) { return a; }
  friend Dual operator-(const Dual& a) { return {-a.value, -a.derivatives}; }
  friend Dual operator+(Dual a, const Dual& b) { return a += b; }
  friend Dual operator-(Dual a, const Dual& b) { return a -= b; }
  friend Dual operator*(Dual a, const Dual& b) { return a *= b; }
  friend Dual operator/(Dual a, const Dual& b) { return a /= b; }
  friend Dual operator+(Dual a, double b) { return a += b; }
  friend Dual operator-(Dual a, double b) { return a -= b; }
  friend Dual operator*(Dual a, double b) { return a *= b; }
  friend Dual operator/(Dual a, double b) { return a /= b; }
  friend Dual operator+(double a, Dual b) { return b += a; }
  friend Dual operator-(double a, const Dual& b) { return {a - b.value, -b.derivatives}; }
  friend Dual operator*(double a, Dual b) { return b *= a; }
  friend Dual operator/(double a, const Dual& b) {
    const double q = a / b.value;
    return {q, (-q / b.value) * b.derivatives};
  }

  friend bool operator==(const Dual& a, const Dual& b) { return a.value == b.value; }
  friend std::partial_ordering operator<=>(const Dual& a, const Dual& b) {
    return a.value <=> b.value;
  }

  // f(a + bε) = f(a) + f'(a)·bε for each function.
  friend Dual abs(const Dual& a) { return a.value < 0 ? -a : a; }
  friend Dual sqrt(const Dual& a) {
    const double s = std::sqrt(a.value);
    return {s, (0.5 / s) * a.derivatives};
  }
  friend Dual exp(const Dual& a) {
    const double e = std::exp(a.value);
    return {e, e * a.derivatives};
  }
  friend Dual log(const Dual& a) { return {std::log(a.value), a.derivatives / a.value}; }
  friend Dual sin(const Dual& a) { return {std::sin(a.value), std::cos(a.value) * a.derivatives}; }
  friend Dual cos(const Dual& a) {
    return {std::cos(a.value), -std::sin(a.value) * a.derivatives};
  }
  friend Dual tan(const Dual& a) {
    const double t = std::tan(a.value);
    return {t, (1 + t * t) * a.derivatives};
  }
  friend Dual tanh(const Dual& a) {
    const double t = std::tanh(a.value);
    return {t, (1 - t * t) * a.derivatives};
  }
  friend Dual atan(const Dual& a) {
    return {std::atan(a.value), a.derivatives / (1 + a.value * a.value)};
  }
  friend Dual atan2(const Dual& y, const Dual& x) {
    const double r2 = x.value * x.value + y.value * y.value;
    return {std::atan2(y.value, x.value), (x.value * y.derivatives - y.value * x.derivatives) / r2};
  }
  // a^p for a constant exponent: p·a^(p−1)·a'.
  friend Dual pow(const Dual& a, double p) {
    const double power = std::pow(a.value, p);
    return {power, (p * std::pow(a.value, p - 1)) * a.derivatives};
  }
  // a^b = exp(b log a): defined for a > 0.
  friend Dual pow(const Dual& a, const Dual& b) {
    const double power = std::pow(a.value, b.value);
    return {power,
            power * (std::log(a.value) * b.derivatives + (b.value / a.value) * a.derivatives)};
  }
};

}  // namespace physgrad

// Lets Eigen matrices hold duals and mix them with double in expressions.
namespace Eigen {

template <int N>
struct NumTraits<physgrad::Dual<N>> : NumTraits<double> {
  using Real = physgrad::Dual<N>;
  using NonInteger = physgrad::Dual<N>;
  using Nested = physgrad::Dual<N>;
  using Literal = double;
  enum { RequireInitialization = 1, ReadCost = N + 1, AddCost = N + 1, MulCost = 2 * N + 1 };
};

template <int N, typename BinaryOp>
struct ScalarBinaryOpTraits<physgrad::Dual<N>, double, BinaryOp> {
  using ReturnType = physgrad::Dual<N>;
};

template <int N, typename BinaryOp>
struct ScalarBinaryOpTraits<double, physgrad::Dual<N>, BinaryOp> {
  using ReturnType = physgrad::Dual<N>;
};

}  // namespace Eigen

namespace physgrad {

// A Simulator made from a function written once as a template over its scalar type T:
//
//   struct MyPhysics {
//     template <typename T>
//     Eigen::Matrix<T, -1, 1> operator()(const Eigen::Matrix<T, -1, 1>& x,
//                                        const Vector& context) const;
//   };
//   AutoDiffSimulator physics(MyPhysics{}, "my_physics", n, m, context_dim);
//
// forward_batch calls it with T = double. jacobian() calls it with T = Dual<Width> in ⌈n/Width⌉
// passes, each seeding Width inputs with unit derivatives, and reads J's columns from the output
// derivatives. vjp_batch is Jᵀ·gy per column, from that Jacobian.
//
// Cost: one Jacobian, and so one VJP, costs about n forward evaluations (⌈n/Width⌉ passes, each
// Width derivative lanes wide), whereas a hand-written adjoint gives a VJP for about one forward
// evaluation whatever n. Measured on the pendulum of examples/pendulum_hig.cpp (VJP of 256
// samples): 3× the hand-written time at n = 20, 16× at n = 160. Duals suit small n and checking
// an adjoint; write the VJP by hand when n is large. The second derivatives (weighted_hessian)
// keep the default: differences of the VJP.
template <typename F, int Width = 8>
class AutoDiffSimulator : public Simulator {
 public:
  using DualScalar = Dual<Width>;
  using DualVector = Eigen::Matrix<DualScalar, Eigen::Dynamic, 1>;

  // Throws Error naming the bad dimension unless n ≥ 1, m ≥ 1 and context_dim ≥ 0.
  AutoDiffSimulator(F function, std::string name, Index input_dim, Index output_dim,
                    Index context_dim = 0)
      : function_(std::move(function)),
        name_(std::move(name)),
        input_dim_(input_dim),
        output_dim_(output_dim),
        context_dim_(context_dim) {
    if (input_dim < 1 || output_dim < 1 || context_dim < 0) {
      std::ostringstream msg;
      msg << name_ << ": dimensions must be input_dim ≥ 1, output_dim ≥ 1, context_dim ≥ 0, got "
          << input_dim << ", " << output_dim << ", " << context_dim;
      throw Error(msg.str());
    }
  }

  std::string name() const override { return name_; }
  Index input_dim() const override { return input_dim_; }
  Index output_dim() const override { return output_dim_; }
  Index context_dim() const override { return context_dim_; }
  const F& function() const { return function_; }

  Matrix forward_batch(const Matrix& x, const Matrix& context) const override {
    check_batch(x, context, "forward");
    Matrix y(output_dim_, x.cols());
    for (Index b = 0; b < x.cols(); ++b) {
      y.col(b) = evaluate<double>(x.col(b), column(context, b));
    }
    return y;
  }

  Matrix vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const override {
    check_batch(x, context, "vjp");
    if (gy.rows() != output_dim_ || gy.cols() != x.cols()) {
      std::ostringstream msg;
      msg << name_ << ".vjp: gy is " << gy.rows() << "×" << gy.cols() << ", expected "
          << output_dim_ << "×" << x.cols();
      throw Error(msg.str());
    }
    Matrix gx(input_dim_, x.cols());
    for (Index b = 0; b < x.cols(); ++b) {
      gx.col(b) = dual_jacobian(x.col(b), column(context, b)).transpose() * gy.col(b);
    }
    return gx;
  }

  Matrix jacobian(const Vector& x, const Vector& context = {}) const override {
    check_batch(x, context, "jacobian");
    return dual_jacobian(x, context);
  }
  bool has_jacobian() const override { return true; }

 private:
  static Vector column(const Matrix& context, Index b) {
    return context.size() == 0 ? Vector() : Vector(context.col(b));
  }

  template <typename T>
  Eigen::Matrix<T, Eigen::Dynamic, 1> evaluate(const Eigen::Matrix<T, Eigen::Dynamic, 1>& x,
                                               const Vector& context) const {
    Eigen::Matrix<T, Eigen::Dynamic, 1> y = function_(x, context);
    if (y.size() != output_dim_) {
      std::ostringstream msg;
      msg << name_ << ": the function returned " << y.size() << " outputs, expected output_dim "
          << output_dim_;
      throw Error(msg.str());
    }
    return y;
  }

  Matrix dual_jacobian(const Vector& x, const Vector& context) const {
    Matrix j(output_dim_, input_dim_);
    DualVector xd = x.cast<DualScalar>();
    for (Index start = 0; start < input_dim_; start += Width) {
      const Index lanes = std::min<Index>(Width, input_dim_ - start);
      for (Index i = 0; i < lanes; ++i) xd(start + i).derivatives(i) = 1.0;
      const DualVector yd = evaluate<DualScalar>(xd, context);
      for (Index i = 0; i < lanes; ++i) xd(start + i).derivatives(i) = 0.0;
      for (Index k = 0; k < output_dim_; ++k) {
        for (Index i = 0; i < lanes; ++i) j(k, start + i) = yd(k).derivatives(i);
      }
    }
    return j;
  }

  F function_;
  std::string name_;
  Index input_dim_;
  Index output_dim_;
  Index context_dim_;
};

}  // namespace physgrad
