// HeatDiffusion — periodic heat diffusion on n cells (1-D) or n×n cells (2-D), unit cell size:
// y = P(x) = IFFT(K ⊙ FFT(x)), K(k) = exp(−4π²|k|²·amount), k = fftfreq(n) per axis, amount = ν·t.
#pragma once

#include "physgrad/physics/simulator.hpp"

namespace physgrad {

struct HeatConfig {
  Index n = 64;       // cells per axis
  int dims = 2;       // 1 or 2
  double amount = 8;  // ν·t ≥ 0
};

// A field has n (1-D) or n² (2-D) values; in 2-D cell (i, j) is entry i + n·j. k = fftfreq(n)
// counts cycles per cell: 0, 1/n, …, −1/n. P is linear and symmetric (real, even kernel), so
// the VJP is P(gy) and the second derivatives vanish. Batched: one field per column.
class HeatDiffusion final : public Simulator {
 public:
  // Throws Error unless n ≥ 1, dims ∈ {1, 2} and amount is finite and ≥ 0, and unless the
  // kernels and a field's spectra fit in memory (physgrad/memory.hpp). A batch polls for a stop
  // request (physgrad/stop.hpp) before each field.
  explicit HeatDiffusion(HeatConfig config = {});

  std::string name() const override { return "heat_diffusion"; }
  Index input_dim() const override { return size_; }
  Index output_dim() const override { return size_; }
  const HeatConfig& config() const { return config_; }
  // K per Fourier mode, flattened like a field (mode (k_i, k_j) = (fftfreq_i, fftfreq_j)).
  const Vector& kernel() const { return kernel_; }

  Matrix forward_batch(const Matrix& x, const Matrix& context) const override;
  Matrix vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const override;
  Matrix weighted_hessian(const Vector& x, const Vector& context, const Vector& w) const override;

  // Regularised inverse diffusion of a field difference dy (the SIP heat inverse). With the
  // per-cell uncertainty u = |dy|·scale + floor and f = √Σu², each mode's amplitude a = FFT(dy)
  // gets the signal probability p = s/(s + r), s = ½exp(−½(|a|/(n·K))²), r = ½exp(−½(|a|/f)²)
  // (a non-finite likelihood counts as 0; p = 0 when s + r = 0), the action
  // α = 2(p − ½) if p ≤ ½ or p ≥ 0.68, else 0, and the gain exp(α·4π²|k|²·amount):
  // α = 1 inverts the mode exactly (1/K), α = 0 leaves it, α < 0 damps it (α = −1: K).
  // n is the cells per axis in 1-D and 2-D alike. The exponent is capped at 88 (⌊ln of the
  // largest float⌋); the reference applies no cap, so the two differ only above gain e⁸⁸.
  // Training-time form: scale 1e-6, floor 0 (uncertainty |y* − y|·1e-6).
  Vector inverse_diffusion(const Vector& dy, double uncertainty_scale,
                           double uncertainty_floor = 0) const;

  // Local inverse x0 + inverse_diffusion(y − P(x0), 1e-6, 1e-8): the stand-alone form, whose
  // floor keeps round-off in absent modes from being amplified. The true inverse of P has gain
  // exp(+4π²|k|²·amount), which blows up at high k; this regularised one is the local inverse
  // a SIP update uses, exact on modes that are clearly signal.
  bool has_inverse() const override { return true; }
  Vector inverse(const Vector& y, const Vector& x0, const Vector& context = {}) const override;

 private:
  // IFFT(K ⊙ FFT(field)) for every column.
  Matrix diffuse(const Matrix& fields) const;

  HeatConfig config_;
  Index size_ = 0;
  Vector log_kernel_;  // 4π²|k|²·amount
  Vector kernel_;      // exp(−log_kernel_)
};

}  // namespace physgrad
