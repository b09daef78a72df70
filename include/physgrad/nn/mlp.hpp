// Mlp — a dense multilayer perceptron whose parameters θ live in one flat vector:
// z_l = W_l a_{l−1} + b_l, a_l = σ_l(z_l), θ = [vec(W_1), b_1, vec(W_2), b_2, …] (column-major W).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "physgrad/nn/activation.hpp"
#include "physgrad/types.hpp"

namespace physgrad {

// Weight initialisation: Glorot uniform U(±√(6/(fan_in + fan_out))), He uniform U(±√(6/fan_in)).
enum class Init { kGlorotUniform, kHeUniform };

std::string to_string(Init init);  // "glorot", "he"
Init parse_init(const std::string& text);

// What forward() keeps for backward(), one sample per column.
struct MlpCache {
  std::vector<Matrix> activations;  // [0] = input, [l + 1] = a_l, the output of layer l
  std::vector<Matrix> derivatives;  // [l] = σ_l'(z_l)
};

// A writable matrix view with any strides, e.g. every m-th row of a bigger matrix.
using StridedMatrixRef = Eigen::Ref<Matrix, 0, Eigen::Stride<Eigen::Dynamic, Eigen::Dynamic>>;

class Mlp {
 public:
  // widths = {input, hidden…, output}: at least 2 entries, each ≥ 1. σ is `hidden` for every
  // layer but the last, which uses `output`. Parameters start at zero; see initialize().
  explicit Mlp(std::vector<Index> widths, Activation hidden = Activation::kTanh,
               Activation output = Activation::kIdentity);

  Index num_layers() const { return static_cast<Index>(widths_.size()) - 1; }
  Index input_dim() const { return widths_.front(); }
  Index output_dim() const { return widths_.back(); }
  Index num_parameters() const { return offsets_.back(); }
  const std::vector<Index>& widths() const { return widths_; }
  Activation hidden_activation() const { return hidden_; }
  Activation output_activation() const { return output_; }

  // θ itself, so optimizers update it in place. Its size must stay num_parameters().
  const Vector& parameters() const { return theta_; }
  Vector& parameters() { return theta_; }
  // Copies θ without reallocating, so weight()/bias() views stay valid.
  void set_parameters(const Vector& theta);

  // Views into θ: W_l (width[l+1] × width[l]) and b_l (width[l+1]), layer in [0, num_layers()).
  Eigen::Map<const Matrix> weight(Index layer) const;
  Eigen::Map<Matrix> weight(Index layer);
  Eigen::Map<const Vector> bias(Index layer) const;
  Eigen::Map<Vector> bias(Index layer);

  // Draws every W_l from `init` with std::mt19937_64(seed) (same θ on every platform); b_l = 0.
  void initialize(std::uint64_t seed, Init init = Init::kGlorotUniform);

  // f(x) for a batch x (input_dim × B); returns output_dim × B.
  Matrix forward(const Matrix& x) const;
  // Same, filling `cache` for backward(); the cache's storage is reused when shapes match.
  Matrix forward(const Matrix& x, MlpCache& cache) const;

  // ∇θ of Σ_b gy_bᵀ f(x_b), laid out like θ, for the batch cached by forward(); gy is
  // output_dim × B. If gx is given it receives the input cotangents (input_dim × B).
  Vector backward(const MlpCache& cache, const Matrix& gy, Matrix* gx = nullptr) const;

  // δ_l = ∂(Σ_b gy_bᵀ f(x_b))/∂z_l for every layer l (width[l+1] × B), from one batched backward
  // sweep. With the cached inputs a_{l−1} they factor each per-sample gradient: ∂/∂W_l is
  // δ_l[:, b] a_{l−1}[:, b]ᵀ and ∂/∂b_l is δ_l[:, b].
  std::vector<Matrix> layer_deltas(const MlpCache& cache, const Matrix& gy) const;

  // B × num_parameters(): row b is ∇θ (gy_bᵀ f(x_b)) for sample b alone, from one batched
  // backward sweep (per-sample outer products δ_l[:, b] a_{l−1}[:, b]ᵀ).
  Matrix per_sample_gradients(const MlpCache& cache, const Matrix& gy) const;
  // Same, written into a caller's B × num_parameters() view (e.g. every m-th row of a
  // stacked Jacobian).
  void per_sample_gradients(const MlpCache& cache, const Matrix& gy, StridedMatrixRef out) const;

 private:
  Activation activation(Index layer) const;

  std::vector<Index> widths_;
  std::vector<Index> offsets_;  // offsets_[l] = start of layer l in θ; back() = |θ|
  Activation hidden_;
  Activation output_;
  Vector theta_;
};

}  // namespace physgrad
