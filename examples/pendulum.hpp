// Pendulum — a user-defined simulator: the damped driven pendulum φ'' = −a sin φ − γφ' + u(t) in
// K explicit Euler steps; input the K controls u, context the start s₀ = (φ₀, ω₀), output s_K.
#pragma once

#include <cmath>
#include <cstdint>
#include <random>
#include <sstream>
#include <string>

#include "physgrad/physgrad.hpp"

namespace example {

using physgrad::Index;
using physgrad::Matrix;
using physgrad::Vector;

struct PendulumConfig {
  Index steps = 20;        // K, one control per step
  double dt = 0.1;         // step size
  double stiffness = 9.81; // a = g/ℓ
  double damping = 0.2;    // γ
};

// One Euler step, written once for any scalar type T (double, or physgrad::Dual).
template <typename T>
void pendulum_step(T& angle, T& velocity, const T& control, const PendulumConfig& config) {
  using std::sin;
  const T acceleration = -config.stiffness * sin(angle) - config.damping * velocity + control;
  angle += config.dt * velocity;
  velocity += config.dt * acceleration;
}

class Pendulum : public physgrad::Simulator {
 public:
  explicit Pendulum(PendulumConfig config) : config_(config) {}

  std::string name() const override { return "pendulum"; }
  Index input_dim() const override { return config_.steps; }
  Index output_dim() const override { return 2; }
  Index context_dim() const override { return 2; }

  // One sample per column: u is K×B, s0 is 2×B, the result 2×B.
  Matrix forward_batch(const Matrix& u, const Matrix& s0) const override {
    check_batch(u, s0, "forward", /*context_required=*/true);
    Matrix y(2, u.cols());
    for (Index b = 0; b < u.cols(); ++b) {
      double angle = s0(0, b), velocity = s0(1, b);
      for (Index k = 0; k < config_.steps; ++k) pendulum_step(angle, velocity, u(k, b), config_);
      y.col(b) << angle, velocity;
    }
    return y;
  }

  // (∂s_K/∂u)ᵀ gy per column: the steps run backwards with the transposed step Jacobian
  // [[1, dt], [−dt·a·cos φ_k, 1 − dt·γ]]ᵀ; control k enters the velocity with weight dt.
  Matrix vjp_batch(const Matrix& u, const Matrix& s0, const Matrix& gy) const override {
    check_batch(u, s0, "vjp", /*context_required=*/true);
    if (gy.rows() != 2 || gy.cols() != u.cols()) {
      std::ostringstream msg;
      msg << "pendulum.vjp: gy is " << gy.rows() << "×" << gy.cols() << ", expected 2×" << u.cols();
      throw physgrad::Error(msg.str());
    }
    const double dt = config_.dt;
    Matrix gu(config_.steps, u.cols());
    Vector angles(config_.steps);
    for (Index b = 0; b < u.cols(); ++b) {
      double angle = s0(0, b), velocity = s0(1, b);
      for (Index k = 0; k < config_.steps; ++k) {
        angles(k) = angle;
        pendulum_step(angle, velocity, u(k, b), config_);
      }
      // (λ_φ, λ_ω) = ∂(gyᵀ s_K)/∂s_k, from k = K down to 0.
      double adjoint_angle = gy(0, b), adjoint_velocity = gy(1, b);
      for (Index k = config_.steps - 1; k >= 0; --k) {
        gu(k, b) = dt * adjoint_velocity;
        const double slope = -dt * config_.stiffness * std::cos(angles(k));  // ∂ω_{k+1}/∂φ_k
        const double earlier_angle = adjoint_angle + slope * adjoint_velocity;
        adjoint_velocity = dt * adjoint_angle + (1 - dt * config_.damping) * adjoint_velocity;
        adjoint_angle = earlier_angle;
      }
    }
    return gu;
  }

 private:
  PendulumConfig config_;
};

// The same map written once over the scalar type, for physgrad::AutoDiffSimulator.
struct PendulumFunction {
  PendulumConfig config;

  template <typename T>
  Eigen::Matrix<T, Eigen::Dynamic, 1> operator()(const Eigen::Matrix<T, Eigen::Dynamic, 1>& u,
                                                 const Vector& s0) const {
    T angle = s0(0), velocity = s0(1);
    for (Index k = 0; k < config.steps; ++k) pendulum_step(angle, velocity, u(k), config);
    return Eigen::Matrix<T, Eigen::Dynamic, 1>{{angle, velocity}};
  }
};

// n tasks: from a random initial state s₀ to a random target state s*, both in [−½, ½]². The
// network sees (s₀, s*) and outputs the K controls; the simulator gets s₀ as context.
inline physgrad::Dataset make_pendulum_tasks(Index n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> state(-0.5, 0.5);
  physgrad::Dataset data{Matrix(4, n), Matrix(2, n), Matrix(2, n)};
  for (Index i = 0; i < n; ++i) {
    for (Index r = 0; r < 4; ++r) data.inputs(r, i) = state(rng);
    data.context.col(i) = data.inputs.col(i).head(2);
    data.targets.col(i) = data.inputs.col(i).tail(2);
  }
  return data;
}

}  // namespace example
