#include "physgrad/learn/stacked_jacobian.hpp"

#include <algorithm>
#include <exception>
#include <string>
#include <thread>

#include "physgrad/error.hpp"
#include "physgrad/threads.hpp"

namespace physgrad {

namespace {

// Runs work(t, threads) for t = 0 … threads − 1, t > 0 on threads of their own; the first
// exception any of them threw is rethrown after all have ended.
template <typename Work>
void on_threads(Index threads, const Work& work) {
  if (threads <= 1) {
    work(0, 1);
    return;
  }
  std::vector<std::thread> workers;
  std::vector<std::exception_ptr> errors(static_cast<std::size_t>(threads));
  try {
    for (Index t = 1; t < threads; ++t) {
      workers.emplace_back([&work, &errors, t, threads] {
        try {
          work(t, threads);
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
    work(0, threads);
  } catch (...) {
    errors[0] = std::current_exception();
  }
  for (std::thread& worker : workers) worker.join();
  for (const std::exception_ptr& error : errors) {
    if (error) std::rethrow_exception(error);
  }
}

}  // namespace

std::vector<Matrix> output_cotangents(const Simulator& physics, const Matrix& x,
                                      const Matrix& context) {
  const Index outputs = physics.output_dim(), batch = x.cols();
  std::vector<Matrix> cotangents(static_cast<std::size_t>(outputs));
  if (physics.has_jacobian()) {
    // Row k of sample i's Jacobian is (∂P/∂x)ᵀ e_k for that sample: one jacobian() per sample,
    // worker t taking the samples i ≡ t (mod threads), each writing only its own columns.
    for (Matrix& c : cotangents) c.resize(x.rows(), batch);
    on_threads(std::min<Index>(jacobian_threads(), batch), [&](Index first, Index stride) {
      for (Index i = first; i < batch; i += stride) {
        const Matrix j = physics.jacobian(x.col(i), context.size() == 0 ? Vector()
                                                                        : Vector(context.col(i)));
        for (Index k = 0; k < outputs; ++k) {
          cotangents[static_cast<std::size_t>(k)].col(i) = j.row(k).transpose();
        }
      }
    });
    return cotangents;
  }
  // Worker t takes the outputs k ≡ t (mod threads).
  on_threads(std::min<Index>(jacobian_threads(), outputs), [&](Index first, Index stride) {
    Matrix unit(outputs, batch);
    for (Index k = first; k < outputs; k += stride) {
      unit.setZero();
      unit.row(k).setOnes();
      cotangents[static_cast<std::size_t>(k)] = physics.vjp_batch(x, context, unit);
    }
  });
  return cotangents;
}

std::vector<Matrix> weighted_output_cotangents(const Simulator& physics, const Matrix& x,
                                               const Matrix& context,
                                               const std::vector<Matrix>& weights) {
  for (const Matrix& w : weights) {
    if (w.rows() != physics.output_dim() || w.cols() != x.cols()) {
      throw Error("output weights of " + std::to_string(w.rows()) + "×" +
                  std::to_string(w.cols()) + ", the batch has " +
                  std::to_string(physics.output_dim()) + " outputs × " +
                  std::to_string(x.cols()) + " samples");
    }
  }
  const auto count = static_cast<Index>(weights.size());
  std::vector<Matrix> cotangents(weights.size());
  // Worker t takes the matrices c ≡ t (mod threads).
  on_threads(std::min<Index>(jacobian_threads(), count), [&](Index first, Index stride) {
    for (Index c = first; c < count; c += stride) {
      const auto k = static_cast<std::size_t>(c);
      cotangents[k] = physics.vjp_batch(x, context, weights[k]);
    }
  });
  return cotangents;
}

LocalJacobian::LocalJacobian(const Network& network, const NetworkCache& cache,
                             const Simulator& physics, Matrix x, Matrix context)
    : LocalJacobian(network, cache, physics, x, output_cotangents(physics, x, context)) {}

LocalJacobian::LocalJacobian(const Network& network, const NetworkCache& cache,
                             const Simulator& physics, Matrix x, std::vector<Matrix> cotangents)
    : network_(&network),
      cache_(&cache),
      x_(std::move(x)),
      output_cotangents_(std::move(cotangents)) {
  if (outputs() != physics.output_dim()) {
    throw Error("LocalJacobian: " + std::to_string(outputs()) +
                " output cotangents for a simulator with " +
                std::to_string(physics.output_dim()) + " outputs");
  }
  for (const Matrix& c : output_cotangents_) {
    if (c.rows() != x_.rows() || c.cols() != x_.cols()) {
      throw Error("LocalJacobian: an output cotangent is " + std::to_string(c.rows()) + "×" +
                  std::to_string(c.cols()) + ", the network outputs are " +
                  std::to_string(x_.rows()) + "×" + std::to_string(x_.cols()));
    }
  }
}

Matrix LocalJacobian::gram() const { return network_->per_sample_gram(*cache_, output_cotangents_); }

Matrix LocalJacobian::gram_columns(const std::vector<Index>& columns) const {
  return network_->per_sample_gram_columns(*cache_, output_cotangents_, columns);
}

Matrix weighted_cotangents(const std::vector<Matrix>& cotangents, const Matrix& weights) {
  if (cotangents.empty()) return Matrix(0, weights.cols());
  Matrix gx = Matrix::Zero(cotangents.front().rows(), weights.cols());
  for (std::size_t k = 0; k < cotangents.size(); ++k) {
    gx += cotangents[k] * weights.row(static_cast<Index>(k)).asDiagonal();
  }
  return gx;
}

Vector LocalJacobian::apply_transpose(const Vector& c) const {
  // Σ_{i,k} c_{k·B+i} ∂y_ik/∂θ = ∇θ of Σ_i C_iᵀ y_i with C (m × B) holding c output by output.
  const Matrix weights = c.reshaped(batch(), outputs()).transpose();
  return network_->backward(*cache_, weighted_cotangents(output_cotangents_, weights));
}

Vector LocalJacobian::apply(const Vector& w) const {
  if (w.size() != cols()) {
    throw Error("LocalJacobian::apply: a vector of " + std::to_string(w.size()) +
                " entries, J has " + std::to_string(cols()) + " columns");
  }
  const Matrix tangent = network_->jvp(*cache_, batch(), w);  // n × B
  Vector out(rows());
  // Entry k·B + i: the dot product of sample i's cotangent of output k with its tangent, summed
  // in one fixed order (the same bits whichever matrix holds the columns).
  for (Index k = 0; k < outputs(); ++k) {
    const Matrix& c = output_cotangents_[static_cast<std::size_t>(k)];
    for (Index i = 0; i < batch(); ++i) {
      double sum = 0;
      for (Index e = 0; e < c.rows(); ++e) sum += c(e, i) * tangent(e, i);
      out(k * batch() + i) = sum;
    }
  }
  return out;
}

std::vector<DenseLayerFactors> LocalJacobian::dense_layer_factors() const {
  return network_->dense_layer_factors(*cache_, output_cotangents_);
}

std::vector<DenseLayerFactors> StackedJacobian::dense_layer_factors() const {
  throw Error("this stacked Jacobian knows no network layers (a formed J): the "
              "Kronecker-factored rules need the network's own Jacobian");
}

Matrix LocalJacobian::materialize() const {
  Matrix j(rows(), cols());
  for (Index k = 0; k < outputs(); ++k) {
    network_->per_sample_gradients(*cache_, output_cotangents_[static_cast<std::size_t>(k)],
                                   j.middleRows(k * batch(), batch()));
  }
  return j;
}

JacobianOperator::Normal LocalJacobian::normal(const Vector& g) const {
  const Matrix j = materialize();
  return DenseJacobian(j).normal(g);
}

}  // namespace physgrad
