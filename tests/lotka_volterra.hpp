// Lotka-Volterra test model — prey and predators, u' = αu − βuv, v' = δuv − γv from (10, 5),
// 100 RK4 steps to t = 5: x = (α, β, γ, δ) ↦ (u(5), v(5)), differentiated by dual numbers.
#pragma once

#include "physgrad/autodiff/dual.hpp"
#include "physgrad/types.hpp"

namespace physgrad::testing {

// Prey and predators, u' = αu − βuv, v' = δuv − γv from (10, 5), 100 RK4 steps to t = 5:
// x = (α, β, γ, δ) ↦ (u(5), v(5)).
struct LotkaVolterra {
  template <typename T>
  Eigen::Matrix<T, Eigen::Dynamic, 1> operator()(const Eigen::Matrix<T, Eigen::Dynamic, 1>& p,
                                                 const Vector& /*context*/) const {
    const auto rate = [&p](const T& u, const T& v) {
      Eigen::Matrix<T, 2, 1> r;
      r << p(0) * u - p(1) * u * v, p(3) * u * v - p(2) * v;
      return r;
    };
    Eigen::Matrix<T, 2, 1> s;
    s << T(10.0), T(5.0);
    const double dt = 0.05;
    for (int k = 0; k < 100; ++k) {
      const Eigen::Matrix<T, 2, 1> k1 = rate(s(0), s(1));
      const Eigen::Matrix<T, 2, 1> a = s + 0.5 * dt * k1;
      const Eigen::Matrix<T, 2, 1> k2 = rate(a(0), a(1));
      const Eigen::Matrix<T, 2, 1> b = s + 0.5 * dt * k2;
      const Eigen::Matrix<T, 2, 1> k3 = rate(b(0), b(1));
      const Eigen::Matrix<T, 2, 1> c = s + dt * k3;
      const Eigen::Matrix<T, 2, 1> k4 = rate(c(0), c(1));
      s += dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    }
    return Eigen::Matrix<T, Eigen::Dynamic, 1>(s);
  }
};

inline const AutoDiffSimulator<LotkaVolterra>& lotka() {
  static const AutoDiffSimulator<LotkaVolterra> model(LotkaVolterra{}, "lotka", 4, 2);
  return model;
}
// The parameters the tests fit.
inline const Vector kLotkaTruth{{1.0, 0.1, 1.5, 0.075}};

}  // namespace physgrad::testing
