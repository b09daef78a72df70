// Network — a model x = f(in; θ) with one flat parameter vector θ, as training uses it: batched
// forward with a cache, ∇θ of Σ_b gy_bᵀ f(in_b), per-sample gradient rows and their Gram matrix.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "physgrad/types.hpp"

namespace physgrad {

// What forward() keeps for the derivatives of the same batch; each network has its own kind.
class NetworkCache {
 public:
  virtual ~NetworkCache() = default;
};

// A writable matrix view with any strides, e.g. every m-th row of a bigger matrix.
using StridedMatrixRef = Eigen::Ref<Matrix, 0, Eigen::Stride<Eigen::Dynamic, Eigen::Dynamic>>;

// Batches hold one sample per column. Every update rule works on parameters() in place, so a
// network keeps θ in one Vector whose size never changes.
//
// To train your own model, implement the pure virtual members; per_sample_gram() has a default
// that forms the gradient rows, and a network made of dense layers z = W a + b can override it
// with DenseLayerGram (dense_layer_gram.hpp), which never forms them (Mlp does).
class Network {
 public:
  virtual ~Network() = default;

  // A name for messages; default: the C++ type of the network.
  virtual std::string name() const;
  virtual Index input_dim() const = 0;
  virtual Index output_dim() const = 0;
  virtual Index num_parameters() const = 0;
  virtual const Vector& parameters() const = 0;
  virtual Vector& parameters() = 0;
  // Copies θ into the existing storage; throws Error unless it has num_parameters() entries.
  void set_parameters(const Vector& theta);

  // An empty cache of this network's kind, for forward(x, cache).
  virtual std::unique_ptr<NetworkCache> new_cache() const = 0;
  // f(x) for a batch (input_dim × B), output_dim × B; the cache receives what the derivatives
  // of this batch need (its storage may be reused between calls of the same shape).
  virtual Matrix forward(const Matrix& x, NetworkCache& cache) const = 0;
  // f(x) without keeping anything.
  virtual Matrix forward(const Matrix& x) const;

  // ∇θ of Σ_b gy_bᵀ f(x_b) for the batch cached by forward(); gy is output_dim × B.
  virtual Vector backward(const NetworkCache& cache, const Matrix& gy) const = 0;
  // Row b of `out` (B × num_parameters()) receives ∇θ(gy_bᵀ f(x_b)) for sample b alone.
  virtual void per_sample_gradients(const NetworkCache& cache, const Matrix& gy,
                                    StridedMatrixRef out) const = 0;
  Matrix per_sample_gradients(const NetworkCache& cache, const Matrix& gy) const;

  // The Gram matrix of per-sample gradients for K cotangents per sample: cotangents[k] is
  // output_dim × B; with c = k·B + b for column b of cotangents[k], entry (c, d) of the
  // (K·B)² result is the dot product of the gradients of cotangents c and d. The default forms
  // the K·B gradient rows (per_sample_gradients) and multiplies them (dsyrk).
  virtual Matrix per_sample_gram(const NetworkCache& cache,
                                 const std::vector<Matrix>& cotangents) const;
  // The columns `selected` of per_sample_gram() ((K·B) × selected.size(), in the order given),
  // for a rank that holds only some columns of the Gram matrix. The default forms the whole
  // matrix and copies them; throws Error on a column outside [0, K·B).
  virtual Matrix per_sample_gram_columns(const NetworkCache& cache,
                                         const std::vector<Matrix>& cotangents,
                                         const std::vector<Index>& selected) const;
};

}  // namespace physgrad
