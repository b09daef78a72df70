#include "physgrad/physics/sin_rotation.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <string>

#include "physgrad/error.hpp"

namespace physgrad {

SinRotation::SinRotation(SinRotationConfig config) : config_(config) {
  require(std::isfinite(config.xi) && config.xi > 0, "sin_rotation",
          "xi must be finite and positive", config.xi);
  require(std::isfinite(config.phi_degrees), "sin_rotation", "phi_degrees must be finite",
          config.phi_degrees);
  require(std::isfinite(config.global_scale) && config.global_scale > 0, "sin_rotation",
          "global_scale must be finite and positive", config.global_scale);
  const double phi = config.phi_degrees * std::numbers::pi / 180;
  Eigen::Matrix2d rotation;
  rotation << std::cos(phi), -std::sin(phi), std::sin(phi), std::cos(phi);
  Eigen::Vector2d scale{1.0, 1.0};
  if (config.form == SinRotationConfig::Form::kBook) {
    out1_ = 1 / config.xi;
    out2_ = config.xi;
  } else {
    scale = {config.global_scale / config.xi, config.global_scale * config.xi};
  }
  to_hat_ = scale.asDiagonal() * rotation;
  from_hat_ = rotation.transpose() * scale.cwiseInverse().asDiagonal();
}

Matrix SinRotation::forward_batch(const Matrix& x, const Matrix& context) const {
  check_batch(x, context, "forward");
  const Matrix hat = to_hat_ * x;
  Matrix y(2, x.cols());
  y.row(0) = out1_ * hat.row(0).array().sin().matrix();
  y.row(1) = out2_ * hat.row(1);
  return y;
}

Matrix SinRotation::vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const {
  check_vjp_batch(x, context, gy);
  Matrix g_hat(2, x.cols());
  g_hat.row(0) = out1_ * ((to_hat_.row(0) * x).array().cos() * gy.row(0).array()).matrix();
  g_hat.row(1) = out2_ * gy.row(1);
  return to_hat_.transpose() * g_hat;
}

Matrix SinRotation::weighted_hessian(const Vector& x, const Vector& context,
                                     const Vector& w) const {
  check_batch(x, context, "weighted_hessian");
  if (w.size() != 2) throw Error("sin_rotation.weighted_hessian: w must have 2 entries");
  const Eigen::Vector2d m = to_hat_.row(0).transpose();
  return -w(0) * out1_ * std::sin(m.dot(x)) * (m * m.transpose());
}

Vector SinRotation::inverse(const Vector& y, const Vector& x0, const Vector& context) const {
  check_batch(x0, context, "inverse");
  if (y.size() != 2) {
    throw Error(std::string("sin_rotation.inverse: y must have 2 entries, got ") +
                std::to_string(y.size()));
  }
  constexpr double kTwoPi = 2 * std::numbers::pi;
  const double guess = to_hat_.row(0).dot(x0);
  const double base = std::asin(std::clamp(y(0) / out1_, -1.0, 1.0));
  // Each branch shifted by the multiple of 2π that brings it nearest the guess.
  const auto nearest = [&](double branch) {
    return branch + kTwoPi * std::round((guess - branch) / kTwoPi);
  };
  const double a = nearest(base), b = nearest(std::numbers::pi - base);
  const double hat1 = std::abs(a - guess) <= std::abs(b - guess) ? a : b;
  return from_hat_ * Eigen::Vector2d{hat1, y(1) / out2_};
}

}  // namespace physgrad
