// DenseLayerGram — J Jᵀ of per-sample gradients accumulated over dense layers z = W a + b without
// forming J: the gradient of column c is δ_c ⊗ [a_i; 1], so (J Jᵀ)_cd = Σ_l (δ_c·δ_d)(a_i·a_j + 1).
#pragma once

#include "physgrad/types.hpp"

namespace physgrad {

// Columns c = k·B + i (K cotangents per sample, B samples) belong to sample i. For a layer with
// output cotangents D (width_out × K·B, column c = ∂/∂z for column c) and inputs A
// (width_in × B), add() accumulates (DᵀD) ⊙ (AᵀA + 1) — the +1 is the bias; without one, AᵀA.
// An entry costs width_out + width_in multiply-adds instead of |θ|.
class DenseLayerGram {
 public:
  // Throws Error unless columns is a multiple of batch (0 columns: an empty result).
  DenseLayerGram(Index columns, Index batch);

  // Throws Error on shapes that do not fit (D: columns() columns, A: batch() columns).
  void add(const Matrix& deltas, const Matrix& inputs, bool with_bias = true);
  // The symmetric (columns × columns) sum, taken once; add() and finish() throw afterwards.
  Matrix finish();

  Index columns() const { return columns_; }
  Index batch() const { return batch_; }

 private:
  Index columns_;
  Index batch_;
  Matrix gram_;    // lower blocks accumulated
  Matrix block_;   // DᵀD of the current layer (lower triangle)
  Matrix inputs_;  // AᵀA (+ 1)
  bool finished_ = false;
};

}  // namespace physgrad
