// SinRotation — the sine characterisation problem: a rotated, ill-conditioned sine map.
// Book: x̂ = R_φ x, P(x) = (sin(x̂₁)/ξ, ξ·x̂₂); code: x̂ = diag(s/ξ, s·ξ) R_φ x, P(x) = (sin(x̂₁), x̂₂).
#pragma once

#include <Eigen/Dense>

#include "physgrad/physics/simulator.hpp"

namespace physgrad {

struct SinRotationConfig {
  // kBook: the chapter's formula. kCode: the SIP repository's, with the overall factor s.
  enum class Form { kBook, kCode };
  double xi = 1;            // ξ > 0: conditioning; the Jacobian's singular values differ by ξ²
  double phi_degrees = 15;  // φ: coupling of the two components by a counter-clockwise rotation
  Form form = Form::kBook;
  double global_scale = 10;  // s > 0, code form only
};

// R_φ = [[cos φ, −sin φ], [sin φ, cos φ]] with φ converted to radians by the exact π (the
// original code's 3.1415 is not reproduced). Input and output dimension 2, no context.
class SinRotation final : public Simulator {
 public:
  // Throws Error unless ξ and s are finite and positive and φ is finite.
  explicit SinRotation(SinRotationConfig config = {});

  std::string name() const override { return "sin_rotation"; }
  Index input_dim() const override { return 2; }
  Index output_dim() const override { return 2; }
  const SinRotationConfig& config() const { return config_; }

  Matrix forward_batch(const Matrix& x, const Matrix& context) const override;
  Matrix vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const override;
  // Exact: Σ_k w_k ∂²P_k/∂x² = −w₁·o₁·sin(x̂₁)·m mᵀ, m = ∂x̂₁/∂x, o₁ the first output factor.
  Matrix weighted_hessian(const Vector& x, const Vector& context, const Vector& w) const override;

  // The exact preimage nearest x0: x̂₂ from the linear part, x̂₁ ∈ {asin v + 2πn,
  // π − asin v + 2πn} (v = y₁ / o₁) nearest the guess's x̂₁, mapped back to x. With x̂₂ fixed,
  // nearest in x̂₁ is nearest in x. For |v| > 1 there is no real preimage: x̂₁ is the nearest
  // point where sin x̂₁ = sign(v), i.e. the output nearest y.
  bool has_inverse() const override { return true; }
  Vector inverse(const Vector& y, const Vector& x0, const Vector& context = {}) const override;
  Vector closest_preimage(const Vector& y, const Vector& x0) const { return inverse(y, x0); }

 private:
  SinRotationConfig config_;
  Eigen::Matrix2d to_hat_;    // x̂ = to_hat_ · x
  Eigen::Matrix2d from_hat_;  // its inverse
  double out1_ = 1;           // P₁ = out1_ · sin(x̂₁)
  double out2_ = 1;           // P₂ = out2_ · x̂₂
};

}  // namespace physgrad
