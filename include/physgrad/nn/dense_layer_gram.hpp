// DenseLayerGram — J Jᵀ of per-sample gradients accumulated over dense layers z = W a + b without
// forming J: the gradient of column c is δ_c ⊗ [a_i; 1], so (J Jᵀ)_cd = Σ_l (δ_c·δ_d)(a_i·a_j + 1).
#pragma once

#include <vector>

#include "physgrad/types.hpp"

namespace physgrad {

// Columns c = k·B + i (K cotangents per sample, B samples) belong to sample i. For a layer with
// output cotangents D (width_out × K·B, column c = ∂/∂z for column c) and inputs A
// (width_in × B), add() accumulates (DᵀD) ⊙ (AᵀA + 1) — the +1 is the bias; without one, AᵀA.
// An entry costs width_out + width_in multiply-adds instead of |θ|.
//
// With `selected` columns, only those columns of J Jᵀ are formed (columns × selected.size(), in
// the order given): (Dᵀ D[:, S]) ⊙ (AᵀA + 1)[·, S] by one dgemm per layer, so ranks that each
// hold some columns of the Gram matrix form only theirs.
class DenseLayerGram {
 public:
  // Throws Error unless columns is a multiple of batch (0 columns: an empty result).
  DenseLayerGram(Index columns, Index batch);
  // Only the `selected` columns (each in [0, columns)); throws Error on one outside.
  DenseLayerGram(Index columns, Index batch, std::vector<Index> selected);

  // Throws Error on shapes that do not fit (D: columns() columns, A: batch() columns).
  void add(const Matrix& deltas, const Matrix& inputs, bool with_bias = true);
  // The symmetric (columns × columns) sum, or its selected columns, taken once; add() and
  // finish() throw afterwards.
  Matrix finish();

  Index columns() const { return columns_; }
  Index batch() const { return batch_; }

 private:
  void add_selected(const Matrix& deltas);

  Index columns_;
  Index batch_;
  std::vector<Index> selected_;  // empty: all columns (lower blocks, mirrored by finish())
  bool all_ = true;
  Matrix gram_;    // lower blocks accumulated, or the selected columns
  Matrix block_;   // DᵀD of the current layer (lower triangle), or Dᵀ D[:, S]
  Matrix inputs_;  // AᵀA (+ 1)
  bool finished_ = false;
};

}  // namespace physgrad
