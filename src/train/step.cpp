#include "physgrad/train/step.hpp"

#include <chrono>
#include <cmath>
#include <optional>
#include <sstream>

#include "physgrad/error.hpp"
#include "physgrad/learn/sharded_jacobian.hpp"
#include "physgrad/nn/checked_network.hpp"
#include "physgrad/physics/checked_simulator.hpp"
#include "physgrad/timing.hpp"

namespace physgrad {

namespace {

using StepClock = std::chrono::steady_clock;

const Simulator& require_models(const LearningProblem& problem) {
  if (problem.physics == nullptr || problem.loss == nullptr) {
    throw Error("learning problem needs a simulator and a loss");
  }
  return *problem.physics;
}

// The network and the problem as training uses them: the network through a CheckedNetwork, the
// simulator through a CheckedSimulator (each the given one when it is checked already), so
// every size they return is checked where it enters the library.
class CheckedModels {
 public:
  CheckedModels(const Network& network, const LearningProblem& problem)
      : network_(CheckedNetwork::around(network, own_network_)),
        physics_(CheckedSimulator::around(require_models(problem), own_physics_)),
        problem_{&physics_, problem.loss} {}

  const CheckedNetwork& network() const { return network_; }
  const CheckedSimulator& physics() const { return physics_; }
  const LearningProblem& problem() const { return problem_; }

 private:
  std::optional<CheckedNetwork> own_network_;
  std::optional<CheckedSimulator> own_physics_;
  const CheckedNetwork& network_;
  const CheckedSimulator& physics_;
  LearningProblem problem_;
};

// Dimension checks of check_problem() without reading the values.
void check_batch_shapes(const CheckedModels& models, const Dataset& data, const char* name) {
  const Network& network = models.network();
  const Simulator& physics = models.physics();
  std::ostringstream msg;
  if (data.targets.cols() != data.inputs.cols() ||
      (data.context.size() != 0 && data.context.cols() != data.inputs.cols())) {
    msg << name << ": " << data.inputs.cols() << " inputs, " << data.targets.cols()
        << " targets and " << data.context.cols() << " context columns";
  } else if (data.inputs.rows() != network.input_dim()) {
    msg << name << ": inputs have " << data.inputs.rows() << " rows, the network takes "
        << network.input_dim();
  } else if (network.output_dim() != physics.input_dim()) {
    msg << "the network outputs " << network.output_dim() << " values, simulator '"
        << physics.name() << "' takes " << physics.input_dim();
  } else if (data.targets.rows() != physics.output_dim()) {
    msg << name << ": targets have " << data.targets.rows() << " rows, simulator '"
        << physics.name() << "' outputs " << physics.output_dim();
  } else if (data.context.size() != 0 && data.context.rows() != physics.context_dim()) {
    msg << name << ": context has " << data.context.rows() << " rows, simulator '"
        << physics.name() << "' expects " << physics.context_dim();
  } else {
    return;
  }
  throw Error(msg.str());
}

// Σ of per-sample losses of the columns of y, and ∂L/∂y of each divided by `batch`.
double loss_sum(const Loss& loss, const Matrix& y, const Matrix& targets, double batch,
                Matrix* gradient_y) {
  double total = 0;
  if (gradient_y != nullptr) gradient_y->resize(y.rows(), y.cols());
  for (Index i = 0; i < y.cols(); ++i) {
    const Vector yi = y.col(i), ti = targets.col(i);
    total += loss.value(yi, ti);
    if (gradient_y != nullptr) gradient_y->col(i) = loss.gradient(yi, ti) / batch;
  }
  return total;
}

}  // namespace

void check_problem(const Network& network, const LearningProblem& problem, const Dataset& data,
                   const char* name) {
  data.validate(name);
  check_batch_shapes(CheckedModels(network, problem), data, name);
}

double mean_loss(const Network& user_network, const LearningProblem& problem, const Dataset& data,
                 const Shard& shard) {
  const CheckedModels models(user_network, problem);
  data.validate("data set");
  check_batch_shapes(models, data, "data set");
  const Network& network = models.network();
  const ColumnRange own = shard.columns(data.size());
  double total = 0;
  if (own.count > 0) {
    const Dataset part = shard.active() ? data.columns(own.begin, own.count) : Dataset();
    const Dataset& mine = shard.active() ? part : data;
    const Matrix y = models.physics().forward_batch(network.forward(mine.inputs), mine.context);
    total = loss_sum(*problem.loss, y, mine.targets, 1.0, nullptr);
  }
  total = shard.sum(total);
  // Every evaluation also checks that the ranks still hold bit-identical parameters.
  shard.check_identical(network.parameters());
  return total / static_cast<double>(data.size());
}

namespace {

// The batch's stacked Jacobian: the network and physics of one process, or (with ranks) this
// rank's share `x` of the physics with the whole batch's network outputs `whole_x`.
std::shared_ptr<StackedJacobian> stacked_jacobian(const Network& network, NetworkCache& cache,
                                                  const Simulator& physics, const Shard& shard,
                                                  Index global, const Dataset& mine, Matrix x,
                                                  Matrix whole_x) {
  if (!shard.active()) {
    return std::make_shared<LocalJacobian>(network, cache, physics, std::move(x), mine.context);
  }
  std::vector<Matrix> cotangents =
      mine.size() > 0 ? output_cotangents(physics, x, mine.context)
                      : std::vector<Matrix>(static_cast<std::size_t>(physics.output_dim()),
                                            Matrix(network.output_dim(), 0));
  return std::make_shared<ShardedJacobian>(network, cache, physics, shard, global, mine.inputs,
                                           std::move(x), std::move(cotangents),
                                           std::move(whole_x));
}

// The sampled Kronecker factors' hook (UpdateNeed::kWeightedFactors): the layer factors of the
// output cotangents Jphysᵀ·weights the rule draws, one process only.
void attach_weighted_factors(BatchState& state, const Network& network, NetworkCache& cache,
                             const Simulator& physics, const Matrix& x, const Matrix& context,
                             const Shard& shard) {
  if (shard.active()) {
    throw Error("the sampled Kronecker factors (a rule's samples > 0) run in one process only, "
                "this run has ranks");
  }
  state.outputs = physics.output_dim();
  state.weighted_factors = [&network, &cache, &physics, x, context](
                               const std::vector<Matrix>& weights) {
    return network.dense_layer_factors(cache,
                                       weighted_output_cotangents(physics, x, context, weights));
  };
}

}  // namespace

BatchState evaluate_batch(const Network& network, const LearningProblem& problem,
                          const Dataset& batch, UpdateNeed need, NetworkCache& cache,
                          const Shard& shard, BatchTiming* timing) {
  const Simulator& physics = *problem.physics;
  auto mark = StepClock::now();
  const auto lap = [&mark, timing](double BatchTiming::*part) {
    const auto now = StepClock::now();
    if (timing != nullptr) timing->*part += std::chrono::duration<double>(now - mark).count();
    mark = now;
  };
  const Index global = batch.size(), outputs = physics.output_dim();
  const ColumnRange own = shard.columns(global);
  const Dataset part = shard.active() ? batch.columns(own.begin, own.count) : Dataset();
  const Dataset& mine = shard.active() ? part : batch;  // this rank's samples
  const bool jacobian = need == UpdateNeed::kStackedJacobian;

  BatchState state;
  state.batch_size = global;
  // The Jacobian rules run the (cheap) network on the whole batch on every rank, so each rank
  // holds the one-process cache; the physics runs on this rank's share only.
  Matrix whole_x, x(network.output_dim(), 0), y(outputs, 0), gradient_y(outputs, 0);
  if (jacobian) {
    whole_x = network.forward(batch.inputs, cache);
    x = shard.active() ? Matrix(whole_x.middleCols(own.begin, own.count)) : std::move(whole_x);
  } else if (own.count > 0) {
    x = network.forward(mine.inputs, cache);
  }
  double total = 0;
  if (own.count > 0) {
    y = physics.forward_batch(x, mine.context);
    total = loss_sum(*problem.loss, y, mine.targets, static_cast<double>(global), &gradient_y);
  }
  state.loss = shard.sum(total) / static_cast<double>(global);
  lap(&BatchTiming::forward);

  switch (need) {
    case UpdateNeed::kGradient:
    case UpdateNeed::kWeightedFactors:
      state.gradient = own.count > 0
                           ? network.backward(cache, physics.vjp_batch(x, mine.context, gradient_y))
                           : Vector::Zero(network.num_parameters());
      shard.sum(state.gradient);
      if (need == UpdateNeed::kWeightedFactors) {
        attach_weighted_factors(state, network, cache, physics, x, mine.context, shard);
      }
      break;
    case UpdateNeed::kNetworkOutputs:
      state.physics = &physics;
      state.loss_function = problem.loss;
      state.targets = own.count > 0 ? mine.targets : Matrix(outputs, 0);
      state.context = mine.context;
      state.backprop = [&network, &cache, shard, count = own.count](const Matrix& gx) {
        Vector g = count > 0 ? network.backward(cache, gx) : Vector::Zero(network.num_parameters());
        shard.sum(g);
        return g;
      };
      state.x = std::move(x);
      state.y = std::move(y);
      break;
    case UpdateNeed::kStackedJacobian:
      // ∂L/∂y of the whole batch in the one-process order k·B + i (gathered as m × B columns).
      state.loss_gradient_y =
          shard.gather_columns({gradient_y}, outputs, global).front().transpose().reshaped();
      state.jacobian = stacked_jacobian(network, cache, physics, shard, global, mine, std::move(x),
                                        std::move(whole_x));
      break;
  }
  lap(&BatchTiming::derivatives);
  return state;
}

std::string to_string(StepReport::Failure failure) {
  switch (failure) {
    case StepReport::Failure::kNone: return "";
    case StepReport::Failure::kLoss: return "loss";
    case StepReport::Failure::kGradient: return "gradient";
    case StepReport::Failure::kLossGradient: return "loss gradient";
    case StepReport::Failure::kUpdate: return "update";
  }
  return "unknown";
}

namespace {

// The first non-finite part of an evaluated batch: the loss, ∇θ or ∂L/∂y (kNone: all finite).
StepReport::Failure batch_failure(const BatchState& evaluated) {
  return !std::isfinite(evaluated.loss)           ? StepReport::Failure::kLoss
         : !all_finite(evaluated.gradient)        ? StepReport::Failure::kGradient
         : !all_finite(evaluated.loss_gradient_y) ? StepReport::Failure::kLossGradient
                                                  : StepReport::Failure::kNone;
}

// The rule's Δθ for a finite batch, its time in `report`; a NumericalError inside the rule or a
// non-finite Δθ is a failure of the update, a Δθ of another size an Error.
Step propose_learning_update(LearningUpdate& update, const BatchState& evaluated, Index parameters,
                    StepReport& report) {
  const auto update_start = StepClock::now();
  Step step;
  try {
    step = update.step(evaluated);
    if (step.delta.size() != parameters) {
      throw Error("learning update '" + update.id() + "': step returned " +
                  std::to_string(step.delta.size()) + " entries, expected " +
                  std::to_string(parameters));
    }
    if (!all_finite(step.delta)) {
      report.failure = StepReport::Failure::kUpdate;
      report.detail = step.message;
    }
  } catch (const NumericalError& e) {
    step = {};
    report.failure = StepReport::Failure::kUpdate;
    report.detail = e.what();
  }
  report.inversion_seconds += step.inversion_seconds;
  report.derivative_seconds += step.jacobian_seconds;
  report.update_seconds +=
      seconds_since(update_start) - step.inversion_seconds - step.jacobian_seconds;
  return step;
}

// One try at the current θ: the batch evaluated and, where all of it is finite, the rule's Δθ
// (`halvable`: whether the part of the rule making it allows halving it).
Step try_train_step(const CheckedModels& models, LearningUpdate& update, const Dataset& batch,
              StepState& state, StepReport& report, bool& halvable) {
  BatchTiming timing;
  const BatchState evaluated = evaluate_batch(models.network(), models.problem(), batch,
                                              update.need(), *state.cache, state.shard, &timing);
  report.forward_seconds += timing.forward;
  report.derivative_seconds += timing.derivatives;
  report.loss = evaluated.loss;
  report.failure = batch_failure(evaluated);
  if (!report.applied()) return {};
  halvable = update.steps_can_be_halved();
  return propose_learning_update(update, evaluated, models.network().num_parameters(), report);
}

// The batch at θ is broken: if θ came from a step that can be halved and halvings remain, θ
// moves back by half that step (the whole one kept in `whole_last_step` at the first halving).
bool halve_last_step(Network& network, StepState& state, StepReport& report,
                     Vector& whole_last_step) {
  if (!state.last_step_halvable || state.last_step.size() == 0 ||
      report.halvings == state.max_step_halvings) {
    return false;
  }
  if (report.halvings == 0) whole_last_step = state.last_step;
  state.last_step *= 0.5;
  network.parameters() = state.before_last_step + state.last_step;
  ++report.halvings;
  return true;
}

// A non-finite Δθ is never applied. A non-finite loss or derivative means the last applied step
// already broke θ: it is undone, back to the θ whose batch was finite.
void undo_broken_step(Network& network, StepState& state, StepReport& report) {
  report.loss = NAN;
  report.undone = state.last_step.size() != 0 &&
                  (report.failure != StepReport::Failure::kUpdate || report.halvings > 0);
  if (report.undone) {
    network.set_parameters(state.before_last_step);
    state.last_step.resize(0);
    state.before_last_step.resize(0);
  }
}

}  // namespace

StepReport train_step(Network& network, LearningUpdate& update, const LearningProblem& problem,
                      const Dataset& batch, StepState& state) {
  // The rule and evaluate_batch() see the network and the simulator only through the checked
  // models; θ is updated on `network` itself.
  const CheckedModels models(network, problem);
  check_batch_shapes(models, batch, "batch");
  if (batch.size() == 0) throw Error("train_step: the batch has no samples");
  if (!state.cache) state.cache = models.network().new_cache();
  const auto start = StepClock::now();
  const SimulatorCounts counts_at_start = models.physics().counts();
  StepReport report;
  Step step;
  bool halvable = false;
  // Halving moves θ before the next evaluation; an exception there (a StopRequested from the
  // simulator, say) puts θ and the step back, so the step leaves no trace but the cache.
  Vector whole_last_step;
  try {
    do {
      step = try_train_step(models, update, batch, state, report, halvable);
    } while (!report.applied() && halve_last_step(network, state, report, whole_last_step));
  } catch (...) {
    if (report.halvings > 0) {
      state.last_step = std::move(whole_last_step);
      network.parameters() = state.before_last_step + state.last_step;
    }
    throw;
  }
  report.total_seconds = seconds_since(start);
  report.counts = models.physics().counts() - counts_at_start;
  if (!report.applied()) {
    undo_broken_step(network, state, report);
    return report;
  }
  state.before_last_step = network.parameters();
  state.last_step = std::move(step.delta);
  state.last_step_halvable = halvable;
  network.parameters() += state.last_step;
  return report;
}

std::string describe_failure(const StepReport& report, long long iteration) {
  if (report.applied()) return {};
  const std::string previous = std::to_string(iteration);
  std::string text = "non-finite " + to_string(report.failure) + " at iteration " +
                     std::to_string(iteration + 1);
  if (!report.detail.empty()) text += " (" + report.detail + ")";
  if (report.halvings > 0) {
    text += ", also after halving update " + previous + " " + std::to_string(report.halvings) +
            " times";
  }
  text += report.undone
              ? "; update " + previous + " undone, parameters restored to those before it"
              : std::string("; the step was not applied");
  return text;
}

}  // namespace physgrad
