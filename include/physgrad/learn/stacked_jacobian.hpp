// StackedJacobian — J = ∂y_ik/∂θ of network + physics over a mini-batch (row k·B + i for sample i,
// output k) as a JacobianOperator (inversion/jacobian_operator.hpp): J Jᵀ, Jᵀc, J, JᵀJ with Jᵀg.
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
};

// J of one process's batch. For a dense network J Jᵀ comes from the layer factors (the
// network's per_sample_gram) and J is never formed; Jᵀc is one physics VJP and one backward.
//
// Holds references to the network, its cache (from forward() on this batch) and the simulator,
// which must outlive it unchanged; x and the context are copied.
class LocalJacobian final : public StackedJacobian {
 public:
  // m batched VJPs through the physics (one per output k) give each sample's cotangent at the
  // network output, on jacobian_threads() threads (threads.hpp); an exception from a VJP is
  // rethrown here.
  LocalJacobian(const Network& network, const NetworkCache& cache, const Simulator& physics,
                Matrix x, Matrix context);
  // Same, with the m output cotangents (∂P/∂x)ᵀ e_k (n × B each) given, e.g. gathered from the
  // ranks of a data-parallel run. Throws Error on a count or shape that does not fit.
  LocalJacobian(const Network& network, const NetworkCache& cache, const Simulator& physics,
                Matrix x, Matrix context, std::vector<Matrix> output_cotangents);

  Index batch() const override { return x_.cols(); }
  Index outputs() const override { return static_cast<Index>(output_cotangents_.size()); }
  Index cols() const override { return network_->num_parameters(); }
  Matrix gram() const override;
  // The given columns of J Jᵀ (rows × columns.size()) from the layer factors.
  Matrix gram_columns(const std::vector<Index>& columns) const;
  Vector apply_transpose(const Vector& c) const override;
  Matrix materialize() const override;
  Normal normal(const Vector& g) const override;

 private:
  const Network* network_;
  const NetworkCache* cache_;
  const Simulator* physics_;
  Matrix x_;
  Matrix context_;
  std::vector<Matrix> output_cotangents_;  // [k]: n × B, (∂P/∂x)ᵀ e_k for every sample
};

// (∂P/∂x)ᵀ e_k of every sample for each physics output k (n × B each): m batched VJPs on
// jacobian_threads() threads; output k's VJP writes only its own matrix, so the result does
// not depend on the thread count.
std::vector<Matrix> output_cotangents(const Simulator& physics, const Matrix& x,
                                      const Matrix& context);

}  // namespace physgrad
