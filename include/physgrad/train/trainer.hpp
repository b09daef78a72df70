// Trainer — minimizes mean_i L(P(f(inᵢ; θ); cᵢ), yᵢ*) over mini-batches with a LearningUpdate:
// epochs of shuffled batches, one train_step() each, evaluations, limits and checkpoints.
#pragma once

#include <atomic>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "physgrad/parallel/communicator.hpp"
#include "physgrad/train/step.hpp"

namespace physgrad {

// Why training ended.
enum class TrainingTermination {
  kMaxIterations,     // TrainerOptions::max_iterations updates were made
  kMaxEpochs,         // max_epochs epochs were completed
  kTimeBudget,        // time_budget_seconds of training time were spent
  kNumericalFailure,  // a step or an evaluation was not finite (see train())
  kInterrupted,       // a stop was requested (TrainerOptions::stop); continue with `resume`
};
// "max_iterations", "max_epochs", "time_budget", "numerical_failure", "interrupted".
std::string to_string(TrainingTermination termination);
// Inverse of to_string; throws Error naming the text otherwise.
TrainingTermination parse_training_termination(const std::string& text);

struct TrainingRecord {
  long long iteration = 0;   // updates made so far
  double epoch = 0;          // iteration·B / N (fractional)
  double train_seconds = 0;  // training time so far, evaluations excluded
  double train_loss = 0;     // mean loss over the training set
  double test_loss = 0;      // mean loss over the test set (NaN without one)
  nlohmann::json extras = nlohmann::json::object();  // filled by TrainerOptions::on_evaluate
  // What the rule's last step did (LearningUpdate::step_info(): hig's inversion path, kept
  // directions, …); empty before the first step and for rules that report nothing.
  nlohmann::json step = nlohmann::json::object();
};

// What train() did, shaped like minimize()'s MinimizeSummary (optim/minimize.hpp).
struct TrainingSummary {
  std::vector<TrainingRecord> history;  // history[0] is the untrained network
  std::optional<TrainingTermination> termination;  // unset while training goes on
  std::string message;
  long long iterations = 0;             // updates made
  double train_seconds = 0;
  // Time per part of all steps: network+physics forward and loss, the stacked Jacobian or
  // gradient, the inversion inside the update, and the rest of the update.
  double forward_seconds = 0;
  double derivative_seconds = 0;
  double inversion_seconds = 0;
  double update_seconds = 0;
  long long step_halvings = 0;  // steps retried at half length after a non-finite batch
  SimulatorCounts counts;  // this process's simulator work in the steps (evaluations excluded)

  // What ran, set by train(): the rule and its settings, the weights |θ|, the training samples,
  // the batch size and the limits set (name, value); with a pretraining
  // (TrainerOptions::pretraining) its rule, settings, batch size and the iteration after which
  // `update` took over.
  std::string update;
  nlohmann::json params;
  Index parameters = 0;
  Index samples = 0;
  Index batch_size = 0;
  std::vector<std::pair<std::string, double>> limits;
  struct Pretraining {
    std::string update;
    nlohmann::json params;
    Index batch_size = 0;
    long long iterations = 0;
  };
  std::optional<Pretraining> pretraining;
};

// Everything a run needs to continue exactly where it was, taken between two iterations. The
// shuffling order of an epoch follows from the seed and the epoch, so (epoch, batch_start) is
// the whole random state.
struct TrainerState {
  long long epoch = 0;       // the epoch in progress
  Index batch_start = 0;     // where the next mini-batch starts in that epoch's order
  Vector parameters;         // θ
  Vector last_step;          // the last applied Δθ (empty before the first update)
  Vector before_last_step;   // θ − last_step as it was before that update
  Vector last_evaluated;     // θ at the last evaluation (whose losses were finite)
  nlohmann::json update_state;  // LearningUpdate::state()
  TrainingSummary summary;      // the history and timings so far
};

// The first part of a run made by another rule, as the HIG paper trains with Adam before HIG
// (TrainerOptions::pretraining).
struct Pretraining {
  LearningUpdate* update = nullptr;  // not the run's rule
  Index batch_size = 32;
  long long iterations = 1;  // the updates it makes, ≥ 1 and below max_iterations
};

struct TrainerOptions {
  Index batch_size = 32;
  // Stop after any of these; at least one must be set.
  std::optional<long long> max_iterations;
  std::optional<long long> max_epochs;
  std::optional<double> time_budget_seconds;  // training time, evaluations excluded
  // Evaluate every this many iterations; unset: at the start and after every epoch.
  std::optional<long long> eval_every;
  // Also evaluate once this much training time has passed since the last evaluation (all
  // ranks of a data-parallel run agree on it). Leave it unset in runs limited by iterations or
  // epochs: which evaluations such a run makes then does not depend on timing, so a resumed or
  // data-parallel run reproduces them exactly.
  std::optional<double> eval_seconds;
  bool shuffle = true;
  std::uint64_t seed = 0;  // shuffling order
  // Data-parallel training: the ranks of this communicator share every mini-batch (Shard,
  // evaluate_batch()); none, or one rank: this process alone.
  std::shared_ptr<Communicator> communicator;
  // Adds experiment-specific figures to a record at each evaluation.
  std::function<void(const Network&, TrainingRecord&)> on_evaluate;
  // Progress line after each evaluation.
  std::function<void(const TrainingRecord&)> on_progress;

  // Checkpoints: on_checkpoint receives the state every checkpoint_every iterations and/or
  // every checkpoint_seconds of wall time, and on a stop request; training then ends with
  // termination kInterrupted (no final evaluation), to be continued with `resume`. A stop
  // request is *stop becoming true or request_stop() (physgrad/stop.hpp): seen between
  // iterations, and inside a step when the simulator polls for it, whose step is then dropped
  // (θ as before it). A data-parallel run defers the simulators' polls (DeferStopPolls): its
  // ranks stop together between iterations.
  std::function<void(const TrainerState&)> on_checkpoint;
  std::optional<long long> checkpoint_every;
  std::optional<double> checkpoint_seconds;
  const std::atomic<bool>* stop = nullptr;
  // Continue from this state (same network shape, update rule, data and options) instead of
  // starting afresh; the continuation is bit-identical to a run that was never interrupted.
  const TrainerState* resume = nullptr;
  // For rules whose steps can be halved (gn, hig): how often a step that led to a non-finite
  // batch is retried at half its length before training stops.
  int max_step_halvings = 10;
  // The first pretraining->iterations updates are made by pretraining->update on batches of its
  // batch size; the network is evaluated there and the run's rule takes over from that θ, with
  // a state of its own (reset) and its batch size, at the start of a new epoch. The iteration
  // count, the training time, the history and the limits run on across the switch, which
  // depends on the iteration count alone: a resumed or data-parallel run switches where an
  // uninterrupted one does. A checkpoint holds the state of the rule making the updates then.
  // max_epochs counts the pretraining's epochs too, its last (perhaps partial) one whole.
  std::optional<Pretraining> pretraining;
};

// Trains `network` in place. Throws Error on mismatched dimensions, invalid options, a
// resume state that does not fit, or an untrained network whose loss is not finite.
// Numerical guard (train_step()): a non-finite loss, derivative or step, or a NumericalError
// below the rule, never reaches θ; a failed step ends training with kNumericalFailure and a
// message naming the rule, the iteration and the place. An evaluation whose train or test loss
// is not finite also stops training, with θ restored to the last evaluated parameters, so
// neither θ nor the history ever holds a non-finite loss. A StopRequested thrown during an
// evaluation is not caught: training ends without a checkpoint of its own (the last one stays).
TrainingSummary train(Network& network, LearningUpdate& update, const LearningProblem& problem,
                      const Dataset& train_set, const Dataset* test_set,
                      const TrainerOptions& options);

// One line: "hig: 120 iterations (3.75 epochs), 4800 simulator passes, train loss 1.2 → 0.045,
// max_iterations".
std::string brief_report(const TrainingSummary& summary);
// A multi-line report like minimize()'s full_report: the problem (weights, samples, batch), the
// rule and its options, the limits, the train and test loss at the start and the end, the work
// (iterations, epochs, evaluations, halvings, the simulator's work by kind), the times per part,
// and the termination with its message.
std::string full_report(const TrainingSummary& summary);

// A summary as JSON and back (checked like the state below); the checkpoint keeps the history,
// counts and timings, train() sets what ran.
nlohmann::json training_summary_to_json(const TrainingSummary& summary);
TrainingSummary training_summary_from_json(const nlohmann::json& document);

// The state as JSON for a checkpoint, and back; trainer_state_from_json checks every field
// (θ and the step vectors of `parameter_count` entries, finite numbers, a consistent history)
// and throws Error naming the first bad one.
nlohmann::json trainer_state_to_json(const TrainerState& state);
TrainerState trainer_state_from_json(const nlohmann::json& document, Index parameter_count);

}  // namespace physgrad
