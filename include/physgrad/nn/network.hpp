// Network — a model x = f(in; θ) with one flat parameter vector θ, as training uses it: batched
// forward with a cache, ∇θ of Σ_b gy_bᵀ f(in_b), per-sample gradient rows and their Gram matrix,
// the directional derivative ∂f/∂θ·v, and the Kronecker factors Σ āāᵀ, Σ δδᵀ of dense layers.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "physgrad/types.hpp"

namespace physgrad {

// What forward() keeps for the derivatives of the same batch; each network has its own kind.
class NetworkCache {
 public:
  virtual ~NetworkCache() = default;
};

// One dense layer z = W a + b of a network as Kronecker-factored curvature sees it: where its
// parameters lie in θ — [vec(W), b] from `offset`, which is the out × (in + 1) matrix [W b] stored
// column by column — and the two factors of its block Σ_c (ā āᵀ) ⊗ (δ_c δ_cᵀ) of JᵀJ, with
// ā = [a; 1] the layer's input (and the bias's 1) of the sample of cotangent column c and δ_c its
// output cotangent ∂/∂z. A convolution is such a layer at every output position p (a = the input
// patch there): its factors sum over the positions too, Σ_p ā_p ā_pᵀ and (1/P) Σ_{c,p} δ_cp δ_cpᵀ,
// and its θ block is [vec(Wᵀ), b] (`transposed`).
struct DenseLayerFactors {
  Index offset = 0;   // first entry of [vec(W), b] (or [vec(Wᵀ), b]) in θ
  Index outputs = 0;  // rows of W, entries of b
  Index inputs = 0;   // columns of W
  bool transposed = false;  // θ holds Wᵀ (inputs × outputs, column by column), then b
  Matrix input_gram;      // Σ_b ā_b ā_bᵀ over the batch's samples, (inputs + 1)²
  Matrix cotangent_gram;  // Σ_c δ_c δ_cᵀ over every given cotangent column, outputs²
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
  // The architecture as JSON, written beside the trained parameters (networks.json) so that a
  // reader can rebuild the network; default: {"kind": name(), "parameters": |θ|}.
  virtual nlohmann::json describe() const;
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

  // ∂f(x_b)/∂θ · v for every sample b of the batch of `batch` samples cached by forward()
  // (output_dim × batch), v of num_parameters() entries: the network's derivative along v
  // (forward mode). The default forms the gradient rows of each output (output_dim() calls of
  // per_sample_gradients); Mlp propagates the tangent through its layers instead. Throws Error
  // when v has the wrong size.
  virtual Matrix jvp(const NetworkCache& cache, Index batch, const Vector& v) const;

  // The factors of every dense layer (DenseLayerFactors) for the batch cached by forward() and K
  // cotangents per sample (cotangents[k]: output_dim × B, as for per_sample_gram), in the order
  // of θ. The default throws Error: only a network that knows its dense layers can give them
  // (Mlp does); the Kronecker-factored rules need them.
  virtual std::vector<DenseLayerFactors> dense_layer_factors(
      const NetworkCache& cache, const std::vector<Matrix>& cotangents) const;
};

}  // namespace physgrad
