// SinRotation: derivatives vs finite differences, the nearest exact preimage vs a brute-force
// branch scan, and the ξ² conditioning of the Jacobian.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "physgrad/autodiff/finite_difference.hpp"
#include "physgrad/error.hpp"
#include "physgrad/physics/sin_rotation.hpp"

namespace physgrad {
namespace {

using Form = SinRotationConfig::Form;

std::vector<SinRotationConfig> all_configs() {
  std::vector<SinRotationConfig> configs;
  for (const Form form : {Form::kBook, Form::kCode}) {
    for (const double xi : {1.0, 32.0}) {
      for (const double phi : {0.0, 15.0, 45.0}) configs.push_back({xi, phi, form, 10});
    }
  }
  return configs;
}

std::string describe(const SinRotationConfig& c) {
  return std::string(c.form == Form::kBook ? "book" : "code") + " xi " + std::to_string(c.xi) +
         " phi " + std::to_string(c.phi_degrees);
}

// The test's own transcription of the formulas: x̂ = to_hat(c)·x, P = (o₁ sin x̂₁, o₂ x̂₂).
Eigen::Matrix2d to_hat(const SinRotationConfig& c) {
  const double phi = c.phi_degrees * std::numbers::pi / 180;
  Eigen::Matrix2d rotation;
  rotation << std::cos(phi), -std::sin(phi), std::sin(phi), std::cos(phi);
  const bool book = c.form == Form::kBook;
  const Eigen::Vector2d scale{book ? 1.0 : c.global_scale / c.xi,
                              book ? 1.0 : c.global_scale * c.xi};
  return scale.asDiagonal() * rotation;
}
double hat1(const SinRotationConfig& c, const Vector& x) { return to_hat(c).row(0).dot(x); }
double out1(const SinRotationConfig& c) { return c.form == Form::kBook ? 1 / c.xi : 1.0; }
double out2(const SinRotationConfig& c) { return c.form == Form::kBook ? c.xi : 1.0; }

TEST(SinRotation, ForwardFollowsBothFormulasWithACounterClockwiseRotation) {
  // φ = 90°: R x = (−x₂, x₁).
  const Vector x{{0.3, -0.2}};
  const SinRotation book({4, 90, Form::kBook, 10});
  EXPECT_NEAR(book.forward(x)(0), std::sin(0.2) / 4, 1e-15);
  EXPECT_NEAR(book.forward(x)(1), 4 * 0.3, 1e-15);
  const SinRotation code({4, 90, Form::kCode, 10});
  EXPECT_NEAR(code.forward(x)(0), std::sin(10.0 / 4 * 0.2), 1e-15);
  EXPECT_NEAR(code.forward(x)(1), 10.0 * 4 * 0.3, 1e-13);
}

TEST(SinRotation, DerivativesMatchFiniteDifferences) {
  for (const SinRotationConfig& config : all_configs()) {
    const SinRotation physics(config);
    for (const Vector& x : {Vector{{0.48, -0.84}}, Vector{{-0.13, 0.05}}, Vector{{1.7, 0.9}}}) {
      const DerivativeCheck check = check_derivatives(physics, x, {}, 1e-6);
      EXPECT_TRUE(check.passed) << describe(config) << " at " << x.transpose() << ": "
                                << check.report();
    }
  }
}

TEST(SinRotation, InverseIsTheNearestExactPreimage) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(-1, 1);
  for (const SinRotationConfig& config : all_configs()) {
    const SinRotation physics(config);
    for (int trial = 0; trial < 50; ++trial) {
      // |y₁|/o₁ ≤ 1: an exact preimage exists.
      const Vector y{{out1(config) * unit(rng), 3 * unit(rng)}};
      const Eigen::Vector2d x0{2 * unit(rng), 2 * unit(rng)};
      const Vector x = physics.closest_preimage(y, x0);
      ASSERT_LT(inverse_residual(physics, y, x0), 1e-12) << describe(config);

      // Brute force: every branch and period n ∈ [−5, 5], mapped back to x, nearest to x0.
      double best = std::numeric_limits<double>::infinity();
      Eigen::Vector2d nearest = Eigen::Vector2d::Zero();
      const double base = std::asin(y(0) / out1(config));
      for (int n = -5; n <= 5; ++n) {
        for (const double branch : {base, std::numbers::pi - base}) {
          const Eigen::Vector2d hat{branch + 2 * std::numbers::pi * n, y(1) / out2(config)};
          const Eigen::Vector2d candidate = to_hat(config).inverse() * hat;
          if ((candidate - x0).norm() < best) {
            best = (candidate - x0).norm();
            nearest = candidate;
          }
        }
      }
      ASSERT_LT((x - nearest).norm(), 1e-9 * std::max(1.0, x.norm()))
          << describe(config) << ": x " << x.transpose() << ", brute force " << nearest.transpose();
    }
  }
}

TEST(SinRotation, WithoutARealPreimageTheInverseReachesTheNearestPeak) {
  for (const SinRotationConfig& config : all_configs()) {
    const SinRotation physics(config);
    const Vector y{{-2.5 * out1(config), 0.4}};
    const Vector x = physics.inverse(y, Vector{{0.7, -0.3}});
    const Vector reached = physics.forward(x);
    EXPECT_NEAR(reached(0), -out1(config), 1e-12) << describe(config);
    EXPECT_NEAR(reached(1), y(1), 1e-12) << describe(config);
    EXPECT_LE(std::abs(hat1(config, x) - hat1(config, Vector{{0.7, -0.3}})), std::numbers::pi)
        << describe(config);
  }
}

TEST(SinRotation, JacobianSingularValuesDifferByXiSquared) {
  for (const SinRotationConfig& config : all_configs()) {
    const SinRotation physics(config);
    // A point with x̂₁ = 2π, where cos x̂₁ = 1.
    const Vector x = to_hat(config).inverse() * Eigen::Vector2d{2 * std::numbers::pi, 0.3};
    ASSERT_NEAR(std::cos(hat1(config, x)), 1.0, 1e-12) << describe(config);
    const Vector s = Eigen::JacobiSVD<Matrix>(physics.jacobian(x)).singularValues();
    EXPECT_NEAR(s(0) / s(1), config.xi * config.xi, 1e-9 * config.xi * config.xi)
        << describe(config);
  }
}

TEST(SinRotation, RejectsBadConfigurationsAndShapes) {
  EXPECT_THROW(SinRotation({0, 15, Form::kBook, 10}), Error);
  EXPECT_THROW(SinRotation({-1, 15, Form::kBook, 10}), Error);
  EXPECT_THROW(SinRotation({1, std::nan(""), Form::kBook, 10}), Error);
  EXPECT_THROW(SinRotation({1, 15, Form::kCode, 0}), Error);
  const SinRotation physics;
  EXPECT_THROW(physics.forward(Vector::Zero(3)), Error);
  EXPECT_THROW(physics.inverse(Vector::Zero(3), Vector::Zero(2)), Error);
  EXPECT_THROW(physics.vjp_batch(Matrix::Zero(2, 2), Matrix(), Matrix::Zero(2, 3)), Error);
}

}  // namespace
}  // namespace physgrad
