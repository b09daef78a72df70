#include "physgrad/optim/stacked_jacobian.hpp"

#include <cblas.h>

namespace physgrad {

StackedJacobian::StackedJacobian(const Mlp& network, const MlpCache& cache,
                                 const Simulator& physics, Matrix x, Matrix context)
    : network_(&network),
      cache_(&cache),
      physics_(&physics),
      x_(std::move(x)),
      context_(std::move(context)),
      batch_(x_.cols()),
      outputs_(physics.output_dim()) {
  Matrix unit(outputs_, batch_);
  for (Index k = 0; k < outputs_; ++k) {
    unit.setZero();
    unit.row(k).setOnes();
    output_cotangents_.push_back(physics.vjp_batch(x_, context_, unit));
  }
}

Matrix StackedJacobian::materialize() const {
  Matrix j(rows(), cols());
  for (Index k = 0; k < outputs_; ++k) {
    network_->per_sample_gradients(*cache_, output_cotangents_[static_cast<std::size_t>(k)],
                                   j.middleRows(k * batch_, batch_));
  }
  return j;
}

Matrix StackedJacobian::gram() const {
  const Index n = rows();
  const Index b = batch_;
  const auto lapack = [](Index value) { return static_cast<blasint>(value); };
  // D_l of all outputs at once: one backward sweep over the B·m columns (column k·B + i), so
  // every layer costs one matrix product instead of m.
  const std::vector<Matrix>& derivatives = cache_->derivatives;
  Matrix delta(network_->output_dim(), n);
  for (Index k = 0; k < outputs_; ++k) {
    delta.middleCols(k * b, b) =
        output_cotangents_[static_cast<std::size_t>(k)].cwiseProduct(derivatives.back());
  }
  Matrix gram = Matrix::Zero(n, n);
  Matrix block = Matrix::Zero(n, n);  // D_lᵀ D_l; dsyrk writes only the lower triangle
  Matrix inputs(b, b);
  Matrix next;
  for (Index l = network_->num_layers() - 1;; --l) {
    cblas_dsyrk(CblasColMajor, CblasLower, CblasTrans, lapack(n), lapack(delta.rows()), 1.0,
                delta.data(), lapack(delta.rows()), 0.0, block.data(), lapack(n));
    const Matrix& a = cache_->activations[static_cast<std::size_t>(l)];
    inputs.noalias() = a.transpose() * a;  // a_{l−1,i} · a_{l−1,j}
    inputs.array() += 1.0;                  // + 1 for the bias
    // The lower blocks (k ≥ kk) only; within a diagonal block the strict upper part is junk
    // (zero in block) and is overwritten by the mirror below.
    for (Index kk = 0; kk < outputs_; ++kk) {
      for (Index k = kk; k < outputs_; ++k) {
        gram.block(k * b, kk * b, b, b).array() +=
            block.block(k * b, kk * b, b, b).array() * inputs.array();
      }
    }
    if (l == 0) break;
    next.noalias() = network_->weight(l).transpose() * delta;
    for (Index k = 0; k < outputs_; ++k) {
      next.middleCols(k * b, b).array() *= derivatives[static_cast<std::size_t>(l - 1)].array();
    }
    delta.swap(next);
  }
  gram.triangularView<Eigen::StrictlyUpper>() = gram.transpose();
  return gram;
}

Vector StackedJacobian::apply_transpose(const Vector& c) const {
  // Σ_{i,k} c_{k·B+i} ∂y_ik/∂θ = ∇θ of Σ_i C_iᵀ y_i with C (m × B) holding c output by output.
  const Matrix weights = c.reshaped(batch_, outputs_).transpose();
  return network_->backward(*cache_, physics_->vjp_batch(x_, context_, weights));
}

}  // namespace physgrad
