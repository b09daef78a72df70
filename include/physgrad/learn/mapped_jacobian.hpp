// MappedJacobian — a StackedJacobian over memory the caller owns: J (rows × cols) stored
// row-major, read in place as the column-major Jᵀ (cols × rows), never copied (J Jᵀ by dsyrk).
#pragma once

#include "physgrad/learn/stacked_jacobian.hpp"

namespace physgrad {

// For a front end that forms the per-sample Jacobian itself (a tensor of shape (B, m, |θ|), say):
// row i·m + k is ∂y_ik/∂θ (sample-major; any row order works if ∂L/∂y uses the same one). The
// memory must stay unchanged while the object is used. Only materialize() (the SVD path) and
// normal() (the tall path) form a matrix of their own.
class MappedJacobian final : public StackedJacobian {
 public:
  // `data` holds batch·outputs rows of `cols` doubles each, row after row. Throws Error on a
  // size < 0 or a null `data` with a nonzero size.
  MappedJacobian(const double* data, Index batch, Index outputs, Index cols);

  Index batch() const override { return batch_; }
  Index outputs() const override { return outputs_; }
  Index cols() const override { return transposed_.rows(); }
  const double* data() const { return transposed_.data(); }  // the memory read

  Matrix gram() const override;
  Vector apply_transpose(const Vector& c) const override;
  Vector apply(const Vector& w) const override;
  Matrix materialize() const override;
  Normal normal(const Vector& g) const override;

 private:
  Index batch_, outputs_;
  Eigen::Map<const Matrix> transposed_;  // Jᵀ, cols × rows
};

}  // namespace physgrad
