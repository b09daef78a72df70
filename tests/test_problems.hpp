// Test problems — small simulators with known minimizers or known numerical trouble: Rosenbrock
// P(x) = (10(x₂ − x₁²), 1 − x₁), a linear map, the cube root, and the identity that breaks at a bound.
#pragma once

#include <cmath>
#include <random>
#include <string>
#include <utility>

#include "physgrad/error.hpp"
#include "physgrad/loss/loss.hpp"
#include "physgrad/optim/objective.hpp"
#include "physgrad/physics/simulator.hpp"

namespace physgrad::testing {

// Entries drawn from N(0, 1) by std::mt19937 seeded with `seed`, column by column.
inline Matrix random_normal(Index rows, Index cols, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  Matrix m(rows, cols);
  for (Index i = 0; i < m.size(); ++i) m.data()[i] = normal(rng);
  return m;
}

// Entries drawn from U[lo, hi) with the top 53 bits of the generator.
inline Matrix random_uniform(std::mt19937_64& rng, Index rows, Index cols, double lo = 0,
                             double hi = 1) {
  Matrix m(rows, cols);
  for (Index j = 0; j < cols; ++j) {
    for (Index i = 0; i < rows; ++i) {
      m(i, j) = lo + (hi - lo) * static_cast<double>(rng() >> 11) * 0x1.0p-53;
    }
  }
  return m;
}

// Extended Rosenbrock in n (even) dimensions: independent pairs (x_{2i}, x_{2i+1}) with residuals
// r_{2i} = 10(x_{2i+1} − x_{2i}²), r_{2i+1} = 1 − x_{2i}. n = 2 is the classic function; with
// L2Loss(2) and target 0 the minimum L = 0 is at x = (1, …, 1).
class Rosenbrock final : public Simulator {
 public:
  explicit Rosenbrock(Index n = 2) : n_(n) {
    if (n < 2 || n % 2 != 0) {
      throw Error("Rosenbrock: n must be even and ≥ 2, got " + std::to_string(n));
    }
  }
  std::string name() const override { return "rosenbrock"; }
  Index input_dim() const override { return n_; }
  Index output_dim() const override { return n_; }

  Matrix forward_batch(const Matrix& x, const Matrix& context) const override {
    check_batch(x, context, "forward_batch");
    Matrix y(n_, x.cols());
    for (Index i = 0; i + 1 < n_; i += 2) {
      y.row(i) = 10 * (x.row(i + 1).array() - x.row(i).array().square());
      y.row(i + 1) = 1 - x.row(i).array();
    }
    return y;
  }
  Matrix vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const override {
    check_batch(x, context, "vjp_batch");
    Matrix gx(n_, x.cols());
    for (Index i = 0; i + 1 < n_; i += 2) {
      gx.row(i) = -20 * x.row(i).array() * gy.row(i).array() - gy.row(i + 1).array();
      gx.row(i + 1) = 10 * gy.row(i);
    }
    return gx;
  }

 private:
  Index n_;
};

// P(x) = A x. With L2Loss(w) and target A x* the loss (w/2)‖A(x − x*)‖² is a convex quadratic
// with Hessian w AᵀA, minimized at x* when A has full column rank.
class LinearSimulator final : public Simulator {
 public:
  explicit LinearSimulator(Matrix a) : a_(std::move(a)) {}
  std::string name() const override { return "linear"; }
  Index input_dim() const override { return a_.cols(); }
  Index output_dim() const override { return a_.rows(); }

  Matrix forward_batch(const Matrix& x, const Matrix& context) const override {
    check_batch(x, context, "forward_batch");
    return a_ * x;
  }
  Matrix vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const override {
    check_batch(x, context, "vjp_batch");
    return a_.transpose() * gy;
  }

 private:
  Matrix a_;
};

// P(x) = ∛x: finite everywhere, but its derivative (and Hessian) is infinite at 0.
class CubeRoot final : public Simulator {
 public:
  std::string name() const override { return "cube_root"; }
  Index input_dim() const override { return 1; }
  Index output_dim() const override { return 1; }
  Matrix forward_batch(const Matrix& x, const Matrix&) const override {
    return x.unaryExpr([](double v) { return std::cbrt(v); });
  }
  Matrix vjp_batch(const Matrix& x, const Matrix&, const Matrix& gy) const override {
    return gy.cwiseQuotient(x.unaryExpr([](double v) { return 3 * std::cbrt(v) * std::cbrt(v); }));
  }
};

// P(x) = x in one dimension, except NaN where x exceeds `bound`.
class Bounded final : public Simulator {
 public:
  explicit Bounded(double bound) : bound_(bound) {}
  std::string name() const override { return "bounded"; }
  Index input_dim() const override { return 1; }
  Index output_dim() const override { return 1; }
  Matrix forward_batch(const Matrix& x, const Matrix&) const override {
    return x.unaryExpr([this](double v) { return v > bound_ ? NAN : v; });
  }
  Matrix vjp_batch(const Matrix&, const Matrix&, const Matrix& gy) const override { return gy; }

 private:
  double bound_;
};

// A well-posed linear least-squares problem ½‖A x − b‖²: 5 residuals, 3 unknowns.
struct LeastSquares {
  Matrix a = (Matrix(5, 3) << 2, -1, 0, 1, 3, 1, 0, 1, 4, -1, 0, 2, 1, 1, 1).finished();
  Vector b = (Vector(5) << 1, -2, 0.5, 3, 1).finished();
  LinearSimulator physics{a};
  L2Loss loss;
  Objective objective{physics, loss, b};
  Vector solution() const { return a.colPivHouseholderQr().solve(b); }
};

}  // namespace physgrad::testing
