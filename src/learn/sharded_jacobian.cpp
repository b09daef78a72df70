#include "physgrad/learn/sharded_jacobian.hpp"

#include <algorithm>
#include <chrono>
#include <memory>
#include <string>

#include "physgrad/error.hpp"
#include "physgrad/inversion/power_pinv.hpp"
#include "physgrad/parallel/distributed_eigen.hpp"
#include "physgrad/timing.hpp"

namespace physgrad {

ShardedJacobian::ShardedJacobian(const Network& network, const NetworkCache& cache,
                                 const Simulator& physics, Shard shard, Index batch,
                                 Matrix own_inputs, Matrix own_x,
                                 std::vector<Matrix> own_cotangents, Matrix whole_x)
    : network_(&network),
      cache_(&cache),
      physics_(&physics),
      shard_(std::move(shard)),
      batch_(batch),
      own_(shard_.columns(batch)),
      own_inputs_(std::move(own_inputs)),
      own_x_(std::move(own_x)),
      own_cotangents_(std::move(own_cotangents)),
      whole_x_(std::move(whole_x)) {}

const LocalJacobian& ShardedJacobian::whole() const {
  if (!whole_) {
    whole_.emplace(*network_, *cache_, *physics_, whole_x_,
                   shard_.gather_columns(own_cotangents_, network_->output_dim(), batch_));
  }
  return *whole_;
}

Vector ShardedJacobian::apply_transpose(const Vector& c) const {
  const Matrix weights = c.reshaped(batch_, outputs()).transpose();
  const Matrix gx = own_.count > 0
                        ? weighted_cotangents(own_cotangents_,
                                              weights.middleCols(own_.begin, own_.count))
                        : Matrix(network_->output_dim(), 0);
  return network_->backward(*cache_,
                            shard_.gather_columns({gx}, network_->output_dim(), batch_).front());
}

std::optional<Vector> ShardedJacobian::shared_gram_apply(const Vector& g,
                                                         const PowerPinvOptions& options,
                                                         PowerPinvInfo* info,
                                                         PowerPinvTiming* timing) const {
  DistributedEigensolver* solver =
      shard_.active() ? shard_.communicator()->eigensolver() : nullptr;
  const Index n = rows(), threshold = distributed_gram_rows();
  if (solver == nullptr || threshold == 0 || n < threshold) return std::nullopt;
  if (g.size() != n) {
    throw Error("power_pinv_apply: J has " + std::to_string(n) + " rows but the vector has " +
                std::to_string(g.size()) + " entries");
  }
  using Clock = std::chrono::steady_clock;
  auto start = Clock::now();
  Matrix columns =
      whole().gram_columns(block_cyclic_columns(n, solver->block(), solver->rank(), solver->size()));
  const double forming = seconds_since(start);
  start = Clock::now();
  PowerPinvInfo out;
  out.backend = PinvBackend::kGram;
  const SpectralCut cut = pinv_cut(PinvBackend::kGram, options);
  out.rcond_used = cut.cutoff();
  // As the one-process tridiagonal eigensolver: J Jᵀ reduced, no eigenvector of it formed.
  out.eigensolver = PinvEigensolver::kTridiagonal;
  DistributedPowerInfo power;
  // U Σ^{−1−κ} Uᵀ g, the same bits on every rank.
  const Vector x = distributed_truncated_power(*solver, std::move(columns), n, g, cut, &power);
  out.rank = power.kept;
  out.sigma_max = power.sigma_max;
  out.sigma_min_kept = power.sigma_min_kept;
  Vector result = apply_transpose(x);
  if (timing != nullptr) {
    timing->forming_seconds += forming;
    timing->inversion_seconds += seconds_since(start);
  }
  if (info != nullptr) *info = out;
  return result;
}

JacobianOperator::Normal ShardedJacobian::normal(const Vector& g) const {
  const Index params = cols();
  if (!sums_normal_equations(batch_, outputs(), network_->output_dim(), params)) {
    return whole().normal(g);
  }
  // Σ_r J_rᵀ J_r and Σ_r J_rᵀ g_r over this rank's rows of J.
  Normal own{Matrix::Zero(params, params), Vector::Zero(params)};
  if (own_.count > 0) {
    const std::unique_ptr<NetworkCache> cache = network_->new_cache();  // own samples only
    network_->forward(own_inputs_, *cache);
    Vector own_g(own_.count * outputs());
    for (Index k = 0; k < outputs(); ++k) {
      own_g.segment(k * own_.count, own_.count) = g.segment(k * batch_ + own_.begin, own_.count);
    }
    own = LocalJacobian(*network_, *cache, *physics_, own_x_, own_cotangents_)
              .normal(own_g);
  }
  std::vector<double> packed;
  packed.reserve(static_cast<std::size_t>(params * (params + 1) / 2 + params));
  for (Index c = 0; c < params; ++c) {
    for (Index r = c; r < params; ++r) packed.push_back(own.matrix(r, c));
  }
  packed.insert(packed.end(), own.rhs.data(), own.rhs.data() + own.rhs.size());
  shard_.sum(packed.data(), packed.size());
  std::size_t at = 0;
  for (Index c = 0; c < params; ++c) {
    for (Index r = c; r < params; ++r) own.matrix(r, c) = packed[at++];
  }
  for (Index i = 0; i < params; ++i) own.rhs(i) = packed[at++];
  return own;
}

bool sums_normal_equations(Index batch, Index outputs, Index network_outputs, Index parameters) {
  const double gathered = static_cast<double>(batch * outputs) * static_cast<double>(network_outputs);
  const auto p = static_cast<double>(parameters);
  return 2 * (p * (p + 1) / 2 + p) < gathered;
}

}  // namespace physgrad
