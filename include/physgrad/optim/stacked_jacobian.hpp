// StackedJacobian — J = ∂(y_ik)/∂θ of network + physics over a batch (row k·B + i for sample i,
// output k), usable without forming it: J Jᵀ = Σ_l (D_lᵀ D_l) ⊙ (A_lᵀ A_l + 1) and Jᵀc by one backward.
#pragma once

#include <vector>

#include "physgrad/nn/mlp.hpp"
#include "physgrad/physics/simulator.hpp"

namespace physgrad {

// For a dense layer l the per-sample gradient of output (i, k) is the outer product of the
// layer's output cotangent δ_l^(k)[:, i] and its input a_{l−1}[:, i] (plus δ for the bias), so
// an entry of J Jᵀ costs Σ_l width_l multiply-adds instead of |θ|. D_l stacks the δ_l^(k) of
// all outputs k (width_l × B·m, column k·B + i); A_l = a_{l−1} (width_{l−1} × B).
//
// Holds references to the network, its cache (from forward() on this batch) and the simulator,
// which must outlive it unchanged; x and the context are copied.
class StackedJacobian {
 public:
  // m batched VJPs through the physics (one per output k) give each sample's cotangent at the
  // network output, on jacobian_threads() threads (threads.hpp); nothing per-parameter is
  // computed yet. An exception from a VJP is rethrown here.
  StackedJacobian(const Mlp& network, const MlpCache& cache, const Simulator& physics,
                  Matrix x, Matrix context);
  // Same, with the m output cotangents (∂P/∂x)ᵀ e_k (n × B each) given, e.g. gathered from the
  // ranks of a data-parallel run that each ran the physics on their share of the batch.
  StackedJacobian(const Mlp& network, const MlpCache& cache, const Simulator& physics,
                  Matrix x, Matrix context, std::vector<Matrix> output_cotangents);

  Index rows() const { return batch_ * outputs_; }
  Index cols() const { return network_->num_parameters(); }

  // J itself (rows × cols): m batched per-sample backward sweeps.
  Matrix materialize() const;
  // J Jᵀ (rows × rows) from the layer factors, never forming J.
  Matrix gram() const;
  // Jᵀ c for c in row space: one physics VJP with cotangents c and one network backward.
  Vector apply_transpose(const Vector& c) const;

 private:
  const Mlp* network_;
  const MlpCache* cache_;
  const Simulator* physics_;
  Matrix x_;
  Matrix context_;
  Index batch_;
  Index outputs_;
  std::vector<Matrix> output_cotangents_;  // [k]: n × B, (∂P/∂x)ᵀ e_k for every sample
};

}  // namespace physgrad
