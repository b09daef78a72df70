// Scalar test problems — P(x) = f(x) on R → R with a given derivative, for one-dimensional
// line searches: the quartic L = (x² − 1)² and the identity that turns NaN beyond x = 2.
#pragma once

#include <functional>
#include <limits>
#include <string>
#include <utility>

#include "physgrad/physics/simulator.hpp"

namespace physgrad::testing {

// P(x) = f(x) on R → R with derivative df, for one-dimensional line-search problems.
class ScalarFunction final : public Simulator {
 public:
  ScalarFunction(std::function<double(double)> f, std::function<double(double)> df)
      : f_(std::move(f)), df_(std::move(df)) {}
  std::string name() const override { return "scalar"; }
  Index input_dim() const override { return 1; }
  Index output_dim() const override { return 1; }
  Matrix forward_batch(const Matrix& x, const Matrix& context) const override {
    check_batch(x, context, "forward_batch");
    return x.unaryExpr(f_);
  }
  Matrix vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const override {
    check_batch(x, context, "vjp_batch");
    return x.unaryExpr(df_).cwiseProduct(gy);
  }

 private:
  std::function<double(double)> f_, df_;
};

// P(x) = x² − 1 with L2Loss(2): the quartic L = (x² − 1)², minima at x = ±1.
inline ScalarFunction quartic() {
  return {[](double x) { return x * x - 1; }, [](double x) { return 2 * x; }};
}
// P(x) = x for x ≤ 2 and NaN beyond.
inline ScalarFunction nan_beyond_two() {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  return {[](double x) { return x <= 2 ? x : kNaN; }, [](double x) { return x <= 2 ? 1.0 : kNaN; }};
}

}  // namespace physgrad::testing
