// JacobianOperator — a Jacobian J (rows × cols) seen through the forms an inversion uses:
// J Jᵀ, Jᵀc, Jw, J itself, and the normal equations JᵀJ, Jᵀg; DenseJacobian is a formed matrix.
#pragma once

#include <optional>

#include "physgrad/types.hpp"

namespace physgrad {

struct PowerPinvOptions;
struct PowerPinvInfo;
struct PowerPinvTiming;

// power_pinv_apply() (power_pinv.hpp) asks for the one form its path needs, so an implementation
// may form J Jᵀ without forming J (a network's per-sample factors, learn/stacked_jacobian.hpp) or
// sum JᵀJ over the ranks of a data-parallel run (learn/sharded_jacobian.hpp).
class JacobianOperator {
 public:
  virtual ~JacobianOperator() = default;

  virtual Index rows() const = 0;
  virtual Index cols() const = 0;
  // J Jᵀ (rows × rows; its lower triangle is what counts).
  virtual Matrix gram() const = 0;
  // Jᵀ c for c in row space.
  virtual Vector apply_transpose(const Vector& c) const = 0;
  // J w for w of cols() entries (the matrix-free rules, learn/lanczos_hig.hpp). The default forms
  // J (materialize()); an operator that can apply J without forming it overrides this.
  virtual Vector apply(const Vector& w) const { return materialize() * w; }
  // J itself (rows × cols).
  virtual Matrix materialize() const = 0;
  // Jᵀ J (cols × cols; its lower triangle is what counts) and Jᵀ g.
  struct Normal {
    Matrix matrix;
    Vector rhs;
  };
  virtual Normal normal(const Vector& g) const = 0;
  // J^{−κ} g on the Gram path when the ranks of a data-parallel run solve it together, each
  // forming and holding some columns of J Jᵀ (learn/sharded_jacobian.hpp from
  // distributed_gram_rows() rows on, parallel/distributed_eigen.hpp); nothing when this process
  // solves it alone from gram().
  virtual std::optional<Vector> shared_gram_apply(const Vector& /*g*/,
                                                  const PowerPinvOptions& /*options*/,
                                                  PowerPinvInfo* /*info*/,
                                                  PowerPinvTiming* /*timing*/) const {
    return std::nullopt;
  }
};

// A formed matrix as an operator (J Jᵀ and JᵀJ by BLAS dsyrk, lower triangle, the upper zero);
// holds a reference to the matrix, which must outlive the operator.
class DenseJacobian final : public JacobianOperator {
 public:
  explicit DenseJacobian(const Matrix& j) : j_(&j) {}

  Index rows() const override { return j_->rows(); }
  Index cols() const override { return j_->cols(); }
  Matrix gram() const override;
  Vector apply_transpose(const Vector& c) const override;
  Vector apply(const Vector& w) const override { return *j_ * w; }
  Matrix materialize() const override { return *j_; }
  Normal normal(const Vector& g) const override;

 private:
  const Matrix* j_;
};

}  // namespace physgrad
