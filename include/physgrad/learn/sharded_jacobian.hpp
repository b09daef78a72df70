// ShardedJacobian — the stacked Jacobian of a mini-batch shared among the ranks of a data-parallel
// run: each rank ran the physics on its share; J Jᵀ, Jᵀc, J and JᵀJ come out equal on every rank.
#pragma once

#include <optional>
#include <vector>

#include "physgrad/learn/stacked_jacobian.hpp"
#include "physgrad/parallel/shard.hpp"

namespace physgrad {

// What each form exchanges (B the batch, m physics outputs, n network outputs, |θ| parameters):
//   gram(), materialize(), apply(w), dense_layer_factors(): every rank's output cotangents
//     (∂P/∂x)ᵀe_k, B·m·n doubles, once per batch; then every rank forms the one-process J Jᵀ
//     (or J, J w, the layer factors) from the network on the whole batch, so the results are
//     the one-process bits.
//   apply_transpose(c): each rank's physics VJP with its share of c, B·n doubles, then one
//     backward pass through the network on the whole batch.
//   shared_gram_apply(g): from distributed_gram_rows() rows on, when the communicator has a
//     DistributedEigensolver: nothing more to form J Jᵀ — each rank forms its block-cyclic
//     columns of it from the gathered cotangents — the solver's own traffic, a sum of B·m
//     doubles for U Σ^{−1−κ} Uᵀ g, then apply_transpose(). Its eigensolver differs from the one
//     process's, so the result agrees with one process to ~ε·(σ_max/σ_min,kept)², not bit for bit.
//   normal(g): the gathered J's Jᵀ J when that moves less data; otherwise Σ over ranks of
//     J_rᵀ J_r (lower triangle) and J_rᵀ g_r, |θ|(|θ|+1)/2 + |θ| doubles, which splits the
//     O(B·m·|θ|²) product but rounds differently (sums_normal_equations()).
// Every rank must call the same members in the same order (they are collectives).
class ShardedJacobian final : public StackedJacobian {
 public:
  // `cache` is the network on the whole batch (every rank runs the cheap network on all B
  // samples); `own_inputs`, `own_x` and `own_cotangents` ([k]: n × share) are this rank's
  // columns shard.columns(B). References must outlive the Jacobian unchanged.
  ShardedJacobian(const Network& network, const NetworkCache& cache, const Simulator& physics,
                  Shard shard, Index batch, Matrix own_inputs, Matrix own_x,
                  std::vector<Matrix> own_cotangents, Matrix whole_x);

  Index batch() const override { return batch_; }
  Index outputs() const override { return physics_->output_dim(); }
  Index cols() const override { return network_->num_parameters(); }
  Matrix gram() const override { return whole().gram(); }
  Vector apply_transpose(const Vector& c) const override;
  Vector apply(const Vector& w) const override { return whole().apply(w); }
  Matrix materialize() const override { return whole().materialize(); }
  std::vector<DenseLayerFactors> dense_layer_factors() const override {
    return whole().dense_layer_factors();
  }
  Normal normal(const Vector& g) const override;
  std::optional<Vector> shared_gram_apply(const Vector& g, const PowerPinvOptions& options,
                                          PowerPinvInfo* info,
                                          PowerPinvTiming* timing) const override;

 private:
  // The one-process Jacobian of the whole batch from every rank's cotangents (gathered once).
  const LocalJacobian& whole() const;

  const Network* network_;
  const NetworkCache* cache_;
  const Simulator* physics_;
  Shard shard_;
  Index batch_;
  ColumnRange own_;
  Matrix own_inputs_, own_x_;
  std::vector<Matrix> own_cotangents_;
  Matrix whole_x_;
  mutable std::optional<LocalJacobian> whole_;
};

// True when summing the normal equations over ranks, 2·(|θ|(|θ|+1)/2 + |θ|) doubles, moves less
// than half of gathering the output cotangents, B·m·n.
bool sums_normal_equations(Index batch, Index outputs, Index network_outputs, Index parameters);

}  // namespace physgrad
