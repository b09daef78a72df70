#include "physgrad/optim/stacked_jacobian.hpp"

#include <cblas.h>

#include <algorithm>
#include <exception>
#include <string>
#include <thread>

#include "physgrad/error.hpp"
#include "physgrad/threads.hpp"

namespace physgrad {

namespace {

// (∂P/∂x)ᵀ e_k for every physics output k, one batched VJP each, on jacobian_threads() threads:
// output k's VJP writes only its own matrix, worker t takes k ≡ t (mod threads), so the result
// does not depend on the thread count.
std::vector<Matrix> output_cotangents_of(const Simulator& physics, const Matrix& x,
                                         const Matrix& context) {
  const Index outputs = physics.output_dim(), batch = x.cols();
  std::vector<Matrix> cotangents(static_cast<std::size_t>(outputs));
  const Index threads = std::min<Index>(jacobian_threads(), outputs);
  const auto vjps = [&](Index first, Index stride) {
    Matrix unit(outputs, batch);
    for (Index k = first; k < outputs; k += stride) {
      unit.setZero();
      unit.row(k).setOnes();
      cotangents[static_cast<std::size_t>(k)] = physics.vjp_batch(x, context, unit);
    }
  };
  if (threads <= 1) {
    vjps(0, 1);
    return cotangents;
  }
  std::vector<std::thread> workers;
  std::vector<std::exception_ptr> errors(static_cast<std::size_t>(threads));
  try {
    for (Index t = 1; t < threads; ++t) {
      workers.emplace_back([&vjps, &errors, t, threads] {
        try {
          vjps(t, threads);
        } catch (...) {
          errors[static_cast<std::size_t>(t)] = std::current_exception();
        }
      });
    }
  } catch (...) {  // a thread could not be started: wait for the others, then report it
    for (std::thread& worker : workers) worker.join();
    throw;
  }
  try {
    vjps(0, threads);
  } catch (...) {
    errors[0] = std::current_exception();
  }
  for (std::thread& worker : workers) worker.join();
  for (const std::exception_ptr& error : errors) {
    if (error) std::rethrow_exception(error);
  }
  return cotangents;
}

}  // namespace

StackedJacobian::StackedJacobian(const Mlp& network, const MlpCache& cache,
                                 const Simulator& physics, Matrix x, Matrix context)
    : StackedJacobian(network, cache, physics, x, context,
                      output_cotangents_of(physics, x, context)) {}

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
