// DataParallel — the ranks of a Communicator share every mini-batch: each evaluates network,
// physics and its rows of J on its contiguous share of the batch, and they combine what the rule needs.
#pragma once

#include <memory>
#include <vector>

#include "physgrad/optim/learning_update.hpp"
#include "physgrad/parallel/communicator.hpp"
#include "physgrad/train/trainer.hpp"

namespace physgrad {

// What the ranks exchange per step (B the global batch, m physics outputs, n network outputs,
// |θ| parameters):
//   sgd, adam:  Σ over ranks of ∇θ (|θ| doubles) and of the batch loss.
//   sip:        Σ of the proxy gradient (|θ|) and of the batch loss; each rank inverts its own
//               samples.
//   gn, hig:    ∂L/∂y of every rank (B·m), then by JacobianExchange:
//     kGatherGram / kGatherJacobian: every rank's output cotangents (∂P/∂x)ᵀe_k (B·m·n); with
//               the network run on the whole batch on every rank, each rank then holds the
//               one-process J Jᵀ (or J) and applies J^{−κ} to the same bits; on the Gram path
//               Jᵀc gathers each rank's physics VJP with its share of c (B·n) for one backward.
//     kSumNormal: Σ of J_rᵀJ_r (lower triangle, |θ|(|θ|+1)/2) and J_rᵀg_r (|θ|), then the same
//               eigendecomposition on every rank.
// Sums are reduced on rank 0 and broadcast, so every rank gets the same bits and θ stays
// bit-identical across ranks (checked at every evaluation). Loss means are over the global batch
// (∂L/∂y scaled by 1/B). The physics (forward, m VJPs, the VJP of Jᵀc) runs on each rank's share
// only; the network, the Gram matrix and its eigendecomposition are the same work on every rank.
//
// Without a communicator, or with one rank, every member is the one-process version
// (evaluate_batch, update.step, mean_loss) and nothing is exchanged.
enum class JacobianExchange { kGatherGram, kGatherJacobian, kSumNormal };

// The exchange of gn/hig for a batch shape: the Gram path gathers; the SVD path gathers (it needs
// J); the normal path gathers unless summing moves less than half as much:
// 2·(|θ|(|θ|+1)/2 + |θ|) < B·m·n.
JacobianExchange choose_exchange(Index batch, Index outputs, Index network_outputs,
                                 Index parameters, const PowerPinvOptions& pinv);

class DataParallel {
 public:
  explicit DataParallel(std::shared_ptr<Communicator> communicator);

  // True with a communicator of more than one rank.
  bool active() const { return communicator_ != nullptr && communicator_->size() > 1; }
  const std::shared_ptr<Communicator>& communicator() const { return communicator_; }

  // mean_i L over `data`, each rank evaluating its contiguous share of the samples.
  double mean_loss(const Mlp& network, const LearningProblem& problem, const Dataset& data);

  // evaluate_batch() for the mini-batch `indices` of `data` (B = indices.size()): this rank's
  // share of it, combined so that every rank holds the same loss, ∇θ and ∂L/∂y (the stacked
  // Jacobian stays in per-rank pieces until step()). `cache` must outlive the state and the
  // following step().
  BatchState evaluate(const Mlp& network, const LearningProblem& problem, const Dataset& data,
                      const std::vector<Index>& indices, UpdateNeed need, MlpCache& cache,
                      BatchTiming* timing = nullptr);

  // update.step(batch) for a state from evaluate(); stacked-Jacobian rules must be
  // JacobianInverseUpdate (gn, hig) and are carried out here on the gathered or summed pieces.
  UpdateStep step(LearningUpdate& update, const BatchState& batch);

  // Doubles this rank sent and received in collectives, and the seconds they took, so far.
  double exchanged_doubles() const { return exchanged_doubles_; }
  double exchange_seconds() const { return exchange_seconds_; }

 private:
  struct Shard;  // this rank's part of the last batch
  std::vector<double> gather(const double* data, std::size_t count);
  void sum(double* data, std::size_t count);
  std::vector<Matrix> gather_columns(const std::vector<Matrix>& local, Index rows, Index batch);

  std::shared_ptr<Communicator> communicator_;
  std::shared_ptr<Shard> shard_;
  double exchanged_doubles_ = 0;
  double exchange_seconds_ = 0;
};

}  // namespace physgrad
