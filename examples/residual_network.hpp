// ResidualNetwork — a user-defined network for physgrad::Network: a dense tanh layer, one residual
// block a₂ = a₁ + tanh(W₂a₁ + b₂), and a linear read-out; its J Jᵀ from dense-layer factors.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "physgrad/physgrad.hpp"

namespace example {

using physgrad::Index;
using physgrad::Matrix;
using physgrad::Vector;

// x ↦ a₁ = tanh(W₁x + b₁) ↦ a₂ = a₁ + tanh(W₂a₁ + b₂) ↦ y = W₃a₂ + b₃, with
// θ = [vec W₁, b₁, vec W₂, b₂, vec W₃, b₃] (column-major W, as physgrad's Mlp).
class ResidualNetwork final : public physgrad::Network {
 public:
  // What forward() keeps: the inputs of the three dense layers and the two tanh slopes.
  struct Cache final : physgrad::NetworkCache {
    Matrix x, a1, a2;  // inputs of layers 1, 2 (a₁) and 3 (a₂)
    Matrix slope1, slope2;  // 1 − tanh² of layers 1 and 2
  };

  ResidualNetwork(Index inputs, Index width, Index outputs)
      : inputs_(inputs),
        width_(width),
        outputs_(outputs),
        theta_(Vector::Zero((inputs + 1) * width + (width + 1) * width + (width + 1) * outputs)) {}

  Index input_dim() const override { return inputs_; }
  Index output_dim() const override { return outputs_; }
  Index num_parameters() const override { return theta_.size(); }
  const Vector& parameters() const override { return theta_; }
  Vector& parameters() override { return theta_; }

  // Glorot-uniform weights, zero biases; the residual branch starts small (×0.1).
  void initialize(std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    const auto fill = [&rng](Eigen::Map<Matrix> w, double scale) {
      const double limit = scale * std::sqrt(6.0 / static_cast<double>(w.rows() + w.cols()));
      std::uniform_real_distribution<double> uniform(-limit, limit);
      for (Index i = 0; i < w.size(); ++i) w.data()[i] = uniform(rng);
    };
    theta_.setZero();
    fill(weight(0), 1.0);
    fill(weight(1), 0.1);
    fill(weight(2), 1.0);
  }

  std::unique_ptr<physgrad::NetworkCache> new_cache() const override {
    return std::make_unique<Cache>();
  }

  using physgrad::Network::forward;
  Matrix forward(const Matrix& x, physgrad::NetworkCache& network_cache) const override {
    if (x.rows() != inputs_) throw physgrad::Error("ResidualNetwork: wrong input size");
    Cache& cache = own(network_cache);
    cache.x = x;
    cache.a1 = ((weight(0) * x).colwise() + bias(0)).array().tanh();
    cache.slope1 = 1 - cache.a1.array().square();
    const Matrix branch = ((weight(1) * cache.a1).colwise() + bias(1)).array().tanh();
    cache.slope2 = 1 - branch.array().square();
    cache.a2 = cache.a1 + branch;
    return (weight(2) * cache.a2).colwise() + bias(2);
  }

  Vector backward(const physgrad::NetworkCache& network_cache, const Matrix& gy) const override {
    const Cache& cache = own(network_cache);
    const Deltas d = deltas(cache, {gy});
    Vector gradient(num_parameters());
    const Matrix* inputs[3] = {&cache.x, &cache.a1, &cache.a2};
    for (int l = 0; l < 3; ++l) {
      Eigen::Map<Matrix>(gradient.data() + offset(l), rows(l), cols(l)) =
          d[l] * inputs[l]->transpose();
      gradient.segment(offset(l) + rows(l) * cols(l), rows(l)) = d[l].rowwise().sum();
    }
    return gradient;
  }

  using physgrad::Network::per_sample_gradients;
  void per_sample_gradients(const physgrad::NetworkCache& network_cache, const Matrix& gy,
                            physgrad::StridedMatrixRef out) const override {
    const Cache& cache = own(network_cache);
    const Deltas d = deltas(cache, {gy});
    const Matrix* inputs[3] = {&cache.x, &cache.a1, &cache.a2};
    for (Index b = 0; b < gy.cols(); ++b) {
      for (int l = 0; l < 3; ++l) {
        // Row b of ∂/∂W_l is δ_l[:, b] a_{l−1}[:, b]ᵀ (column-major), of ∂/∂b_l δ_l[:, b].
        for (Index c = 0; c < cols(l); ++c) {
          out.row(b).segment(offset(l) + c * rows(l), rows(l)) =
              d[l].col(b).transpose() * (*inputs[l])(c, b);
        }
        out.row(b).segment(offset(l) + rows(l) * cols(l), rows(l)) = d[l].col(b).transpose();
      }
    }
  }

  // Every parameter belongs to a dense layer, so J Jᵀ = Σ_l (D_lᵀD_l) ⊙ (A_lᵀA_l + 1) with the
  // deltas of all K·B cotangents from one sweep (DenseLayerGram): the rows are never formed.
  Matrix per_sample_gram(const physgrad::NetworkCache& network_cache,
                         const std::vector<Matrix>& cotangents) const override {
    const Cache& cache = own(network_cache);
    const Deltas d = deltas(cache, cotangents);
    physgrad::DenseLayerGram gram(d[2].cols(), cache.x.cols());
    gram.add(d[2], cache.a2);
    gram.add(d[1], cache.a1);
    gram.add(d[0], cache.x);
    return gram.finish();
  }

 private:
  using Deltas = std::array<Matrix, 3>;  // ∂/∂z of layers 1, 2, 3, one column per cotangent

  static const Cache& own(const physgrad::NetworkCache& cache) {
    const auto* mine = dynamic_cast<const Cache*>(&cache);
    if (mine == nullptr) throw physgrad::Error("ResidualNetwork: not its cache");
    return *mine;
  }
  static Cache& own(physgrad::NetworkCache& cache) {
    auto* mine = dynamic_cast<Cache*>(&cache);
    if (mine == nullptr) throw physgrad::Error("ResidualNetwork: not its cache");
    return *mine;
  }

  // One backward sweep for K blocks of B cotangents at once (column k·B + b belongs to sample b).
  Deltas deltas(const Cache& cache, const std::vector<Matrix>& cotangents) const {
    const Index batch = cache.x.cols();
    const auto blocks = static_cast<Index>(cotangents.size());
    const auto times = [&](Matrix m, const Matrix& slope) {  // slope of sample b on every block
      for (Index k = 0; k < blocks; ++k) m.middleCols(k * batch, batch).array() *= slope.array();
      return m;
    };
    Deltas d;
    d[2].resize(outputs_, blocks * batch);
    for (Index k = 0; k < blocks; ++k) {
      if (cotangents[k].rows() != outputs_ || cotangents[k].cols() != batch) {
        throw physgrad::Error("ResidualNetwork: a cotangent block does not fit the cached batch");
      }
      d[2].middleCols(k * batch, batch) = cotangents[k];
    }
    const Matrix through_readout = weight(2).transpose() * d[2];          // ∂/∂a₂
    d[1] = times(through_readout, cache.slope2);                           // branch: ∂/∂z₂
    d[0] = times(through_readout + weight(1).transpose() * d[1], cache.slope1);  // ∂/∂z₁
    return d;
  }

  Index rows(int layer) const { return layer == 2 ? outputs_ : width_; }
  Index cols(int layer) const { return layer == 0 ? inputs_ : width_; }
  Index offset(int layer) const {
    Index at = 0;
    for (int l = 0; l < layer; ++l) at += rows(l) * (cols(l) + 1);
    return at;
  }
  Eigen::Map<const Matrix> weight(int layer) const {
    return {theta_.data() + offset(layer), rows(layer), cols(layer)};
  }
  Eigen::Map<Matrix> weight(int layer) {
    return {theta_.data() + offset(layer), rows(layer), cols(layer)};
  }
  Eigen::Map<const Vector> bias(int layer) const {
    return {theta_.data() + offset(layer) + rows(layer) * cols(layer), rows(layer)};
  }

  Index inputs_, width_, outputs_;
  Vector theta_;
};

}  // namespace example
