// CheckedNetwork — a user's Network as training sees it: every call forwarded, the size of every
// returned value checked (f: out×B, ∇θ: |θ|, Gram: (K·B)×(K·B), a cache that exists).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "physgrad/nn/network.hpp"

namespace physgrad {

// Reads input_dim() and output_dim() (≥ 1) and num_parameters() (≥ 1, and parameters() of that
// size) once, at construction, and checks every result: forward() output_dim×B, backward()
// num_parameters() entries, per_sample_gram() (K·B)×(K·B), jvp() output_dim×B, the layers of
// dense_layer_factors() inside θ, new_cache() not null — or throws
// Error "network 'NAME': backward returned 3 entries, expected 12" (NAME: the network's name()).
// per_sample_gradients() writes into the block it is given, so there is no size to check.
// Exceptions of the wrapped network pass through unchanged. Read-only: the non-const
// parameters() throws (the rules get θ from the training loop, which updates the network itself).
// train_step(), mean_loss() and check_problem() put one around the network they are given.
class CheckedNetwork final : public Network {
 public:
  explicit CheckedNetwork(const Network& inner);
  CheckedNetwork(const CheckedNetwork&) = delete;
  CheckedNetwork& operator=(const CheckedNetwork&) = delete;

  // `network` itself when it is a CheckedNetwork, else one emplaced into `local` around it.
  static const CheckedNetwork& around(const Network& network, std::optional<CheckedNetwork>& local);

  const Network& inner() const { return *inner_; }

  std::string name() const override { return inner_->name(); }
  Index input_dim() const override { return input_dim_; }
  Index output_dim() const override { return output_dim_; }
  Index num_parameters() const override { return parameters_; }
  const Vector& parameters() const override { return inner_->parameters(); }
  Vector& parameters() override;
  std::unique_ptr<NetworkCache> new_cache() const override;
  Matrix forward(const Matrix& x, NetworkCache& cache) const override;
  Matrix forward(const Matrix& x) const override;
  Vector backward(const NetworkCache& cache, const Matrix& gy) const override;
  void per_sample_gradients(const NetworkCache& cache, const Matrix& gy,
                            StridedMatrixRef out) const override;
  Matrix per_sample_gram(const NetworkCache& cache,
                         const std::vector<Matrix>& cotangents) const override;
  Matrix per_sample_gram_columns(const NetworkCache& cache, const std::vector<Matrix>& cotangents,
                                 const std::vector<Index>& selected) const override;
  // output_dim × batch.
  Matrix jvp(const NetworkCache& cache, Index batch, const Vector& v) const override;
  // Each layer's parameters inside θ and its factors square of the layer's sizes.
  std::vector<DenseLayerFactors> dense_layer_factors(
      const NetworkCache& cache, const std::vector<Matrix>& cotangents) const override;

 private:
  // Throw Error unless `result` is rows×cols, or has `size` entries.
  void check_result(const char* method, const Matrix& result, Index rows, Index cols) const;
  void check_result(const char* method, const Vector& result, Index size) const;

  const Network* inner_;
  Index input_dim_, output_dim_, parameters_;
};

}  // namespace physgrad
