#include "physgrad/train/data_parallel.hpp"

#include <cblas.h>

#include <chrono>
#include <cmath>
#include <string>

#include "physgrad/error.hpp"

namespace physgrad {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

Index share_begin(Index count, int rank, int size) {
  return static_cast<Index>(share_of(static_cast<std::size_t>(count), rank, size).begin);
}
Index share_length(Index count, int rank, int size) {
  return static_cast<Index>(share_of(static_cast<std::size_t>(count), rank, size).length);
}

}  // namespace

struct DataParallel::Shard {
  const Mlp* network = nullptr;
  const MlpCache* cache = nullptr;  // the network on the whole batch
  const Simulator* physics = nullptr;
  Index batch = 0;    // B, the whole mini-batch
  Index begin = 0;    // this rank's columns [begin, begin + count)
  Index count = 0;
  Index outputs = 0;  // m
  Matrix x, context;  // this rank's network outputs and physics context
  Matrix whole_x, whole_context;          // the same for the whole batch
  std::vector<Matrix> output_cotangents;  // [k]: n × count, (∂P/∂x)ᵀ e_k per sample
  Vector loss_gradient_y;                 // the whole batch's, entry k·B + i
};

DataParallel::DataParallel(std::shared_ptr<Communicator> communicator)
    : communicator_(std::move(communicator)) {}

std::vector<double> DataParallel::gather(const double* data, std::size_t count) {
  const auto start = Clock::now();
  std::vector<double> all = communicator_->allgather(data, count);
  exchange_seconds_ += seconds_since(start);
  exchanged_doubles_ += static_cast<double>(all.size());
  return all;
}

void DataParallel::sum(double* data, std::size_t count) {
  const auto start = Clock::now();
  communicator_->allreduce_sum(data, count);
  exchange_seconds_ += seconds_since(start);
  exchanged_doubles_ += static_cast<double>(count);
}

// Every rank's n × count blocks of `local` (one block per matrix) assembled into n × B matrices
// in the one-process column order.
std::vector<Matrix> DataParallel::gather_columns(const std::vector<Matrix>& local, Index rows,
                                                 Index batch) {
  std::vector<double> packed;
  for (const Matrix& m : local) packed.insert(packed.end(), m.data(), m.data() + m.size());
  const std::vector<double> all = gather(packed.data(), packed.size());
  const int size = communicator_->size();
  std::vector<Matrix> full(local.size(), Matrix(rows, batch));
  std::size_t at = 0;
  for (int r = 0; r < size; ++r) {
    const Index begin = share_begin(batch, r, size), count = share_length(batch, r, size);
    for (Matrix& m : full) {
      m.middleCols(begin, count) = Eigen::Map<const Matrix>(all.data() + at, rows, count);
      at += static_cast<std::size_t>(rows * count);
    }
  }
  return full;
}

double DataParallel::mean_loss(const Mlp& network, const LearningProblem& problem,
                               const Dataset& data) {
  if (!active()) return physgrad::mean_loss(network, problem, data);
  const Index n = data.size();
  const Index begin = share_begin(n, communicator_->rank(), communicator_->size());
  const Index count = share_length(n, communicator_->rank(), communicator_->size());
  double total = 0;
  if (count > 0) {
    const Matrix x = network.forward(data.inputs.middleCols(begin, count));
    const Matrix context =
        data.context.size() == 0 ? Matrix() : Matrix(data.context.middleCols(begin, count));
    const Matrix y = problem.physics->forward_batch(x, context);
    for (Index i = 0; i < count; ++i) {
      total += problem.loss->value(y.col(i), data.targets.col(begin + i));
    }
  }
  sum(&total, 1);
  // Every evaluation also checks that the ranks still hold bit-identical parameters.
  const Vector& theta = network.parameters();
  const std::uint64_t hash = hash_doubles(theta.data(), static_cast<std::size_t>(theta.size()));
  if (!same_on_all_ranks(*communicator_, hash)) {
    throw Error("data-parallel training: the parameters differ between ranks");
  }
  return total / static_cast<double>(n);
}

BatchState DataParallel::evaluate(const Mlp& network, const LearningProblem& problem,
                                  const Dataset& data, const std::vector<Index>& indices,
                                  UpdateNeed need, MlpCache& cache, BatchTiming* timing) {
  if (!active()) return evaluate_batch(network, problem, data.select(indices), need, cache, timing);
  const Simulator& physics = *problem.physics;
  const int rank = communicator_->rank(), size = communicator_->size();
  const auto global = static_cast<Index>(indices.size());
  const Index begin = share_begin(global, rank, size);
  const Index count = share_length(global, rank, size);
  const bool jacobian = need == UpdateNeed::kStackedJacobian;
  // The stacked-Jacobian rules run the (cheap) network on the whole batch on every rank, so
  // each rank holds the one-process cache; the physics runs on this rank's share only.
  const std::vector<Index> mine(indices.begin() + begin, indices.begin() + begin + count);
  const Dataset batch = data.select(mine);

  auto mark = Clock::now();
  const auto lap = [&mark, timing](double BatchTiming::*part) {
    const auto now = Clock::now();
    if (timing != nullptr) timing->*part += std::chrono::duration<double>(now - mark).count();
    mark = now;
  };

  BatchState state;
  state.batch_size = global;
  const Index outputs = physics.output_dim();
  Matrix x(network.output_dim(), 0), y(outputs, 0), gradient_y(outputs, 0);
  Dataset whole;
  Matrix whole_x;
  if (jacobian) {
    whole = data.select(indices);
    whole_x = network.forward(whole.inputs, cache);
    x = whole_x.middleCols(begin, count);
  } else if (count > 0) {
    x = network.forward(batch.inputs, cache);
  }
  double total = 0;
  if (count > 0) {
    y = physics.forward_batch(x, batch.context);
    gradient_y.resize(outputs, count);
    for (Index i = 0; i < count; ++i) {
      const Vector yi = y.col(i), ti = batch.targets.col(i);
      total += problem.loss->value(yi, ti);
      gradient_y.col(i) = problem.loss->gradient(yi, ti) / static_cast<double>(global);
    }
  }
  sum(&total, 1);
  state.loss = total / static_cast<double>(global);
  lap(&BatchTiming::forward);

  shard_.reset();
  if (need == UpdateNeed::kGradient) {
    state.gradient = count > 0
                         ? network.backward(cache, physics.vjp_batch(x, batch.context, gradient_y))
                         : Vector::Zero(network.num_parameters());
    sum(state.gradient.data(), static_cast<std::size_t>(state.gradient.size()));
  } else if (need == UpdateNeed::kNetworkOutputs) {
    state.physics = &physics;
    state.loss_function = problem.loss;
    state.x = x;
    state.y = y;
    state.targets = count > 0 ? batch.targets : Matrix(outputs, 0);
    state.context = batch.context;
    state.backprop = [this, &network, &cache, count](const Matrix& gx) {
      Vector g = count > 0 ? network.backward(cache, gx) : Vector::Zero(network.num_parameters());
      sum(g.data(), static_cast<std::size_t>(g.size()));
      return g;
    };
  } else {
    auto shard = std::make_shared<Shard>();
    shard->network = &network;
    shard->cache = &cache;
    shard->physics = &physics;
    shard->batch = global;
    shard->begin = begin;
    shard->count = count;
    shard->outputs = outputs;
    shard->x = x;
    shard->context = batch.context;
    shard->whole_x = std::move(whole_x);
    shard->whole_context = std::move(whole.context);
    Matrix unit(outputs, count);
    for (Index k = 0; k < outputs; ++k) {
      unit.setZero();
      unit.row(k).setOnes();
      shard->output_cotangents.push_back(count > 0 ? physics.vjp_batch(x, batch.context, unit)
                                                   : Matrix(x.rows(), 0));
    }
    // ∂L/∂y of the whole batch in the one-process order k·B + i (gathered as m × B columns).
    const Matrix all = gather_columns({gradient_y}, outputs, global).front();
    state.loss_gradient_y = all.transpose().reshaped();
    shard->loss_gradient_y = state.loss_gradient_y;
    shard_ = std::move(shard);
  }
  lap(&BatchTiming::derivatives);
  return state;
}

UpdateStep DataParallel::step(LearningUpdate& update, const BatchState& batch) {
  if (!active() || update.need() != UpdateNeed::kStackedJacobian) return update.step(batch);
  auto* rule = dynamic_cast<JacobianInverseUpdate*>(&update);
  if (rule == nullptr) {
    throw Error(update.id() + ": data-parallel training knows the stacked-Jacobian rules gn and "
                              "hig only");
  }
  if (shard_ == nullptr) throw Error(update.id() + ": step() without a batch from evaluate()");
  const Shard& s = *shard_;
  const Mlp& network = *s.network;
  const PowerPinvOptions& pinv = rule->pinv_options();
  const Index params = network.num_parameters();
  const Index n = network.output_dim();
  const JacobianExchange exchange = choose_exchange(s.batch, s.outputs, n, params, pinv);

  UpdateStep step;
  PowerPinvInfo info;
  const auto start = Clock::now();
  Vector direction;
  if (exchange == JacobianExchange::kSumNormal) {
    // Σ_r J_rᵀ J_r (lower triangle) and Σ_r J_rᵀ g_r over this rank's rows of J.
    Matrix normal = Matrix::Zero(params, params);
    Vector jt_g = Vector::Zero(params);
    if (s.count > 0) {
      MlpCache own;  // the network on this rank's samples only
      network.forward(s.cache->activations.front().middleCols(s.begin, s.count), own);
      const Matrix j =
          StackedJacobian(network, own, *s.physics, s.x, s.context, s.output_cotangents)
              .materialize();
      cblas_dsyrk(CblasColMajor, CblasLower, CblasTrans, static_cast<int>(params),
                  static_cast<int>(j.rows()), 1.0, j.data(), static_cast<int>(j.rows()), 0.0,
                  normal.data(), static_cast<int>(params));
      Vector local_g(s.count * s.outputs);
      for (Index k = 0; k < s.outputs; ++k) {
        local_g.segment(k * s.count, s.count) =
            s.loss_gradient_y.segment(k * s.batch + s.begin, s.count);
      }
      jt_g.noalias() = j.transpose() * local_g;
    }
    std::vector<double> packed;
    packed.reserve(static_cast<std::size_t>(params * (params + 1) / 2 + params));
    for (Index c = 0; c < params; ++c) {
      for (Index r = c; r < params; ++r) packed.push_back(normal(r, c));
    }
    packed.insert(packed.end(), jt_g.data(), jt_g.data() + jt_g.size());
    sum(packed.data(), packed.size());
    std::size_t at = 0;
    for (Index c = 0; c < params; ++c) {
      for (Index r = c; r < params; ++r) normal(r, c) = packed[at++];
    }
    for (Index i = 0; i < params; ++i) jt_g(i) = packed[at++];
    const auto formed_at = Clock::now();
    step.jacobian_seconds = std::chrono::duration<double>(formed_at - start).count();
    if (!all_finite(normal) || !all_finite(jt_g)) {
      step.delta = Vector::Constant(params, NAN);
      return step;
    }
    direction = power_pinv_apply_normal(std::move(normal), jt_g, pinv, &info);
    step.inversion_seconds = seconds_since(formed_at);
  } else {
    // Every rank's output cotangents: each rank then forms the one-process J Jᵀ (or J) with
    // the one-process code (its apply_transpose() would rerun the physics on the whole batch,
    // so Jᵀc is done below).
    const StackedJacobian whole(network, *s.cache, *s.physics, s.whole_x, s.whole_context,
                                gather_columns(s.output_cotangents, n, s.batch));
    const bool gram = exchange == JacobianExchange::kGatherGram;
    Matrix formed = gram ? whole.gram() : whole.materialize();
    const auto formed_at = Clock::now();
    step.jacobian_seconds = std::chrono::duration<double>(formed_at - start).count();
    if (!all_finite(formed)) {
      step.delta = Vector::Constant(params, NAN);
      return step;
    }
    if (gram) {
      // Jᵀc: each rank's physics VJP with its share of c, gathered, then one backward pass
      // through the network on the whole batch (as StackedJacobian::apply_transpose).
      const auto apply_transpose = [&](const Vector& c) {
        const Matrix weights = c.reshaped(s.batch, s.outputs).transpose();
        const Matrix mine = weights.middleCols(s.begin, s.count);
        const Matrix gx = s.count > 0 ? s.physics->vjp_batch(s.x, s.context, mine)
                                      : Matrix(n, 0);
        return network.backward(*s.cache, gather_columns({gx}, n, s.batch).front());
      };
      direction = power_pinv_apply_gram(std::move(formed), s.loss_gradient_y, apply_transpose,
                                        pinv, &info);
    } else {
      direction = power_pinv_apply(formed, s.loss_gradient_y, pinv, &info);
    }
    step.inversion_seconds = seconds_since(formed_at);
  }
  step.delta = -rule->lr() * direction;
  return step;
}

JacobianExchange choose_exchange(Index batch, Index outputs, Index network_outputs,
                                 Index parameters, const PowerPinvOptions& pinv) {
  const Index rows = batch * outputs;
  switch (resolve_pinv_backend(rows, parameters, pinv)) {
    case PinvBackend::kGram: return JacobianExchange::kGatherGram;
    case PinvBackend::kNormal: {
      // Gathering the cotangents (B·m·n doubles) reproduces the one-process result; summing
      // Jᵀ J and Jᵀ g (|θ|(|θ|+1)/2 + |θ|) splits the O(B·m·|θ|²) product over the ranks but
      // rounds differently, which the squared spectrum amplifies. Sum only when that moves
      // less than half the data.
      const double gathered = static_cast<double>(rows) * static_cast<double>(network_outputs);
      const double p = static_cast<double>(parameters);
      return 2 * (p * (p + 1) / 2 + p) < gathered ? JacobianExchange::kSumNormal
                                                  : JacobianExchange::kGatherJacobian;
    }
    default: return JacobianExchange::kGatherJacobian;
  }
}

}  // namespace physgrad
