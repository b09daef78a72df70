// Mlp — a dense multilayer perceptron whose parameters θ live in one flat vector:
// z_l = W_l a_{l−1} + b_l, a_l = σ_l(z_l), θ = [vec(W_1), b_1, vec(W_2), b_2, …] (column-major W).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "physgrad/nn/activation.hpp"
#include "physgrad/nn/network.hpp"
#include "physgrad/types.hpp"

namespace physgrad {

// Weight initialisation: Glorot uniform U(±√(6/(fan_in + fan_out))), He uniform U(±√(6/fan_in)).
enum class Init { kGlorotUniform, kHeUniform };

std::string to_string(Init init);  // "glorot", "he"
Init parse_init(const std::string& text);

// What forward() keeps for the derivatives, one sample per column.
struct MlpCache final : NetworkCache {
  std::vector<Matrix> activations;  // [0] = input, [l + 1] = a_l, the output of layer l
  std::vector<Matrix> derivatives;  // [l] = σ_l'(z_l)
};

class Mlp final : public Network {
 public:
  // widths = {input, hidden…, output}: at least 2 entries, each ≥ 1. σ is `hidden` for every
  // layer but the last, which uses `output`. Parameters start at zero; see initialize().
  explicit Mlp(std::vector<Index> widths, Activation hidden = Activation::kTanh,
               Activation output = Activation::kIdentity);

  // {"kind": "mlp", "widths": […], "hidden": "tanh", "output": "identity"}.
  nlohmann::json describe() const override;

  Index num_layers() const { return static_cast<Index>(widths_.size()) - 1; }
  Index input_dim() const override { return widths_.front(); }
  Index output_dim() const override { return widths_.back(); }
  Index num_parameters() const override { return offsets_.back(); }
  const std::vector<Index>& widths() const { return widths_; }
  Activation hidden_activation() const { return hidden_; }
  Activation output_activation() const { return output_; }

  // θ itself, so optimizers update it in place. Its size must stay num_parameters();
  // set_parameters() copies without reallocating, so weight()/bias() views stay valid.
  const Vector& parameters() const override { return theta_; }
  Vector& parameters() override { return theta_; }

  // Views into θ: W_l (width[l+1] × width[l]) and b_l (width[l+1]), layer in [0, num_layers()).
  Eigen::Map<const Matrix> weight(Index layer) const;
  Eigen::Map<Matrix> weight(Index layer);
  Eigen::Map<const Vector> bias(Index layer) const;
  Eigen::Map<Vector> bias(Index layer);

  // Draws every W_l from `init` with std::mt19937_64(seed) (same θ on every platform); b_l = 0.
  void initialize(std::uint64_t seed, Init init = Init::kGlorotUniform);

  std::unique_ptr<NetworkCache> new_cache() const override;
  // f(x) for a batch x (input_dim × B); returns output_dim × B. The cache (an MlpCache) keeps
  // every layer's output and σ'; its storage is reused when shapes match.
  Matrix forward(const Matrix& x) const override;
  Matrix forward(const Matrix& x, NetworkCache& cache) const override;

  // ∇θ of Σ_b gy_bᵀ f(x_b), laid out like θ, for the batch cached by forward(); gy is
  // output_dim × B. If gx is given it receives the input cotangents (input_dim × B).
  Vector backward(const NetworkCache& cache, const Matrix& gy) const override;
  Vector backward(const NetworkCache& cache, const Matrix& gy, Matrix* gx) const;

  // Row b is ∇θ (gy_bᵀ f(x_b)) for sample b alone, from one batched backward sweep (per-sample
  // outer products δ_l[:, b] a_{l−1}[:, b]ᵀ).
  using Network::per_sample_gradients;
  void per_sample_gradients(const NetworkCache& cache, const Matrix& gy,
                            StridedMatrixRef out) const override;
  // From the layer factors (DenseLayerGram): one backward sweep over all K·B cotangents at once;
  // the gradient rows are never formed.
  Matrix per_sample_gram(const NetworkCache& cache,
                         const std::vector<Matrix>& cotangents) const override;
  // The same sweep, with only the selected columns formed (one dgemm per layer).
  Matrix per_sample_gram_columns(const NetworkCache& cache, const std::vector<Matrix>& cotangents,
                                 const std::vector<Index>& selected) const override;

  // The tangent ȧ_l = σ_l'(z_l) ⊙ (Ẇ_l a_{l−1} + ḃ_l + W_l ȧ_{l−1}), ȧ_0 = 0, through every layer
  // (about two forward passes).
  Matrix jvp(const NetworkCache& cache, Index batch, const Vector& v) const override;
  // Every layer's Σ ā āᵀ from the cached inputs and Σ δ δᵀ from one backward sweep of the K·B
  // cotangents (as per_sample_gram makes it).
  std::vector<DenseLayerFactors> dense_layer_factors(
      const NetworkCache& cache, const std::vector<Matrix>& cotangents) const override;

 private:
  Activation activation(Index layer) const;
  // One backward sweep of all K·B cotangents at once (column k·B + i for block k, sample i):
  // visit(l, δ_l, a_{l−1}) for l = L−1 … 0, δ_l of every column, a_{l−1} the layer's cached
  // inputs (one column per sample).
  void sweep_cotangents(
      const NetworkCache& cache, const std::vector<Matrix>& cotangents,
      const std::function<void(Index layer, const Matrix& deltas, const Matrix& inputs)>& visit)
      const;

  std::vector<Index> widths_;
  std::vector<Index> offsets_;  // offsets_[l] = start of layer l in θ; back() = |θ|
  Activation hidden_;
  Activation output_;
  Vector theta_;
};

}  // namespace physgrad
