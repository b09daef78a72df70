#include "physgrad/optim/stacked_jacobian.hpp"

#include <string>

#include "physgrad/error.hpp"

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

StackedJacobian::StackedJacobian(const Mlp& network, const MlpCache& cache,
                                 const Simulator& physics, Matrix x, Matrix context,
                                 std::vector<Matrix> output_cotangents)
    : network_(&network),
      cache_(&cache),
      physics_(&physics),
      x_(std::move(x)),
      context_(std::move(context)),
      batch_(x_.cols()),
      outputs_(physics.output_dim()),
      output_cotangents_(std::move(output_cotangents)) {
  if (static_cast<Index>(output_cotangents_.size()) != outputs_) {
    throw Error("StackedJacobian: " + std::to_string(output_cotangents_.size()) +
                " output cotangents for a simulator with " + std::to_string(outputs_) +
                " outputs");
  }
  for (const Matrix& c : output_cotangents_) {
    if (c.rows() != x_.rows() || c.cols() != batch_) {
      throw Error("StackedJacobian: an output cotangent is " + std::to_string(c.rows()) + "×" +
                  std::to_string(c.cols()) + ", the network outputs are " +
                  std::to_string(x_.rows()) + "×" + std::to_string(batch_));
    }
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
  const Index layers = network_->num_layers();
  const Index b = batch_;
  // D_l for every layer, filled output by output.
  std::vector<Matrix> stacked(static_cast<std::size_t>(layers));
  for (Index k = 0; k < outputs_; ++k) {
    const std::vector<Matrix> deltas =
        network_->layer_deltas(*cache_, output_cotangents_[static_cast<std::size_t>(k)]);
    for (Index l = 0; l < layers; ++l) {
      Matrix& d = stacked[static_cast<std::size_t>(l)];
      if (k == 0) d.resize(deltas[static_cast<std::size_t>(l)].rows(), rows());
      d.middleCols(k * b, b) = deltas[static_cast<std::size_t>(l)];
    }
  }
  Matrix gram = Matrix::Zero(rows(), rows());
  Matrix block(rows(), rows());
  for (Index l = 0; l < layers; ++l) {
    const Matrix& a = cache_->activations[static_cast<std::size_t>(l)];
    Matrix inputs = a.transpose() * a;  // a_{l−1,i} · a_{l−1,j}
    inputs.array() += 1.0;               // + 1 for the bias
    const Matrix& d = stacked[static_cast<std::size_t>(l)];
    block.noalias() = d.transpose() * d;
    for (Index k = 0; k < outputs_; ++k) {
      for (Index kk = 0; kk < outputs_; ++kk) {
        gram.block(k * b, kk * b, b, b).array() +=
            block.block(k * b, kk * b, b, b).array() * inputs.array();
      }
    }
  }
  return gram;
}

Vector StackedJacobian::apply_transpose(const Vector& c) const {
  // Σ_{i,k} c_{k·B+i} ∂y_ik/∂θ = ∇θ of Σ_i C_iᵀ y_i with C (m × B) holding c output by output.
  const Matrix weights = c.reshaped(batch_, outputs_).transpose();
  return network_->backward(*cache_, physics_->vjp_batch(x_, context_, weights));
}

}  // namespace physgrad
