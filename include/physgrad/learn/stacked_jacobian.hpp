// StackedJacobian — J = ∂y_ik/∂θ of network + physics over a mini-batch (row k·B + i for sample i,
// output k) as a JacobianOperator (inversion/jacobian_operator.hpp): J Jᵀ, Jᵀc, Jw, J, JᵀJ with
// Jᵀg, and the Kronecker factors Σ āāᵀ, Σ_rows δδᵀ of the network's dense layers.
#pragma once

#include <vector>

#include "physgrad/inversion/jacobian_operator.hpp"
#include "physgrad/nn/network.hpp"
#include "physgrad/physics/simulator.hpp"

namespace physgrad {

// An update rule sees only this interface, so the same rule runs on one process (LocalJacobian)
// and on the ranks of a data-parallel run (ShardedJacobian, sharded_jacobian.hpp); the inversion
// (inversion/power_pinv.hpp) asks it for the one form its path needs.
class StackedJacobian : public JacobianOperator {
 public:
  virtual Index batch() const = 0;    // B
  virtual Index outputs() const = 0;  // m, the physics outputs per sample
  Index rows() const final { return batch() * outputs(); }
  // The factors of each dense layer of the network (nn/network.hpp, DenseLayerFactors) over the
  // B·m rows of J: Σ over the batch of ā āᵀ, Σ over every row of δ δᵀ. The default throws Error
  // (a formed J knows no layers).
  virtual std::vector<DenseLayerFactors> dense_layer_factors() const;
};

// J of one process's batch. For a dense network J Jᵀ comes from the layer factors (the
// network's per_sample_gram) and J is never formed; Jᵀc is one backward of the output
// cotangents weighted by c (weighted_cotangents()), without another physics call.
//
// Holds references to the network and its cache (from forward() on this batch), which must
// outlive it unchanged; the simulator is called only in the constructor.
class LocalJacobian final : public StackedJacobian {
 public:
  // output_cotangents() gives each sample's cotangents at the network output (m batched VJPs
  // through the physics, or one jacobian() per sample), on jacobian_threads() threads
  // (threads.hpp); an exception from the simulator is rethrown here.
  LocalJacobian(const Network& network, const NetworkCache& cache, const Simulator& physics,
                Matrix x, Matrix context);
  // Same, with the m output cotangents (∂P/∂x)ᵀ e_k (n × B each) given, e.g. gathered from the
  // ranks of a data-parallel run. Throws Error on a count or shape that does not fit.
  LocalJacobian(const Network& network, const NetworkCache& cache, const Simulator& physics,
                Matrix x, std::vector<Matrix> output_cotangents);

  Index batch() const override { return x_.cols(); }
  Index outputs() const override { return static_cast<Index>(output_cotangents_.size()); }
  Index cols() const override { return network_->num_parameters(); }
  Matrix gram() const override;
  // The given columns of J Jᵀ (rows × columns.size()) from the layer factors.
  Matrix gram_columns(const std::vector<Index>& columns) const;
  Vector apply_transpose(const Vector& c) const override;
  // J w = (C_k[:, i] · ẋ_i) for row k·B + i, ẋ = the network's jvp along w: one forward-mode
  // pass, no physics call.
  Vector apply(const Vector& w) const override;
  Matrix materialize() const override;
  Normal normal(const Vector& g) const override;
  std::vector<DenseLayerFactors> dense_layer_factors() const override;

 private:
  const Network* network_;
  const NetworkCache* cache_;
  Matrix x_;
  std::vector<Matrix> output_cotangents_;  // [k]: n × B, (∂P/∂x)ᵀ e_k for every sample
};

// (∂P/∂x)ᵀ e_k of every sample for each physics output k (n × B each): m batched VJPs on
// jacobian_threads() threads, or B calls of jacobian() when the simulator has_jacobian(); each
// call writes only its own entries, so the result does not depend on the thread count.
std::vector<Matrix> output_cotangents(const Simulator& physics, const Matrix& x,
                                      const Matrix& context);

// (∂P/∂x_i)ᵀ W_c.col(i) of every sample i for each weight matrix W_c (m × B) of `weights`
// (n × B each): one batched VJP per matrix on jacobian_threads() threads, each writing only its
// own result. Throws Error on a weight matrix of another shape.
std::vector<Matrix> weighted_output_cotangents(const Simulator& physics, const Matrix& x,
                                               const Matrix& context,
                                               const std::vector<Matrix>& weights);

// (∂P/∂x)ᵀ W per sample from the output cotangents: column i is Σ_k W_ki·cotangents[k].col(i)
// (n × B for W m × B); no simulator call.
Matrix weighted_cotangents(const std::vector<Matrix>& cotangents, const Matrix& weights);

}  // namespace physgrad
