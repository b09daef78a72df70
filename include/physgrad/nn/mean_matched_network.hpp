// MeanMatchedNetwork — a network whose output field takes the mean of its input field:
// f'(in) = f(in) − mean(f(in)) + mean(in), so ∂f'/∂θ = C·∂f/∂θ with the centring C = I − 11ᵀ/m.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "physgrad/nn/network.hpp"

namespace physgrad {

// The heat reference's output correction (docs/reference_experiments.md): diffusion keeps a
// field's mean, so the mean of the initial state x* equals that of the network's input y*, and
// each prediction is shifted to it. θ is the wrapped network's; every derivative is the wrapped
// one's with the cotangents (or tangents) centred, so each rule that trains the wrapped network
// trains this one, batch norm and all.
class MeanMatchedNetwork final : public Network {
 public:
  // Throws Error unless `inner` exists and has as many outputs as inputs.
  explicit MeanMatchedNetwork(std::unique_ptr<Network> inner);

  std::string name() const override { return "mean-matched " + inner_->name(); }
  // The wrapped network's description with "output_mean": "input".
  nlohmann::json describe() const override;
  Index input_dim() const override { return inner_->input_dim(); }
  Index output_dim() const override { return inner_->output_dim(); }
  Index num_parameters() const override { return inner_->num_parameters(); }
  const Vector& parameters() const override { return inner_->parameters(); }
  Vector& parameters() override { return inner_->parameters(); }
  const Network& inner() const { return *inner_; }

  std::unique_ptr<NetworkCache> new_cache() const override { return inner_->new_cache(); }
  using Network::forward;
  Matrix forward(const Matrix& x, NetworkCache& cache) const override;
  Vector backward(const NetworkCache& cache, const Matrix& gy) const override;
  using Network::per_sample_gradients;
  void per_sample_gradients(const NetworkCache& cache, const Matrix& gy,
                            StridedMatrixRef out) const override;
  Matrix per_sample_gram(const NetworkCache& cache,
                         const std::vector<Matrix>& cotangents) const override;
  Matrix per_sample_gram_columns(const NetworkCache& cache, const std::vector<Matrix>& cotangents,
                                 const std::vector<Index>& selected) const override;
  Matrix jvp(const NetworkCache& cache, Index batch, const Vector& v) const override;
  std::vector<DenseLayerFactors> dense_layer_factors(
      const NetworkCache& cache, const std::vector<Matrix>& cotangents) const override;

 private:
  std::unique_ptr<Network> inner_;
};

}  // namespace physgrad
