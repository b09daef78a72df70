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
  kTimeBudget,        // time_budget_seconds of the run's wall time were spent, or the next
                      // step would have overrun them (the message says which)
  kNumericalFailure,  // a step or an evaluation was not finite (see train())
  kInterrupted,       // a stop was requested (TrainerOptions::stop); continue with `resume`
  kDiverged,          // a limit ended the run with its training loss above its start
};
// "max_iterations", "max_epochs", "time_budget", "numerical_failure", "interrupted",
// "diverged".
std::string to_string(TrainingTermination termination);
// Inverse of to_string; throws Error naming the text otherwise.
TrainingTermination parse_training_termination(const std::string& text);
// Whether a run that ended so reached what its limits allowed: a limit, not a failure, a stop
// request or a divergence.
bool ended_by_limit(TrainingTermination termination);

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
  double train_seconds = 0;             // the steps' time, evaluations and checkpoints excluded
  // The run's wall time so far: steps, evaluations and checkpoints (what time_budget_seconds
  // bounds), kept in checkpoints so that a resumed run goes on counting.
  double wall_seconds = 0;
  // Time per part of all steps: network+physics forward and loss, the stacked Jacobian or
  // gradient, the inversion inside the update, and the rest of the update.
  double forward_seconds = 0;
  double derivative_seconds = 0;
  double inversion_seconds = 0;
  double update_seconds = 0;
  long long step_halvings = 0;  // steps retried at half length after a non-finite batch
  SimulatorCounts counts;  // this process's simulator work in the steps (evaluations excluded)

  // The parts of the run: one for a plain rule; a rule made of parts in turn
  // (LearningUpdate::phase(), e.g. SwitchingUpdate's Adam→HIG) adds one each time the next part
  // takes over, with the updates made before it and its batch size. Kept in checkpoints.
  // With TrainerOptions::cost_reference, a part also keeps its cost: the CPU seconds of every one
  // of its steps, and the number and CPU seconds of the reference steps probed beside them.
  struct Phase {
    long long first_iteration = 0;
    Index batch_size = 0;
    long long probes = 0;
    double reference_cpu_seconds = 0;
    long long timed_steps = 0;
    double step_cpu_seconds = 0;
    // The part's cost per update in reference updates (Adam's, say): the mean CPU seconds of its
    // steps over those of the reference steps timed beside them; NaN without probes.
    double reference_updates() const;
  };
  std::vector<Phase> phases;

  // What ran, set by train(): the rule and its settings, the weights |θ|, the training samples
  // (of an epoch, with fresh samples: TrainerOptions::fresh_samples), whether each batch was drawn
  // afresh, and the limits set (name, value).
  std::string update;
  nlohmann::json params;
  Index parameters = 0;
  Index samples = 0;
  bool fresh_samples = false;
  std::vector<std::pair<std::string, double>> limits;
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

// Samples drawn afresh for one mini-batch: `count` samples from random stream `stream`
// (fresh_stream()). Every call with the same stream must give the same samples, so that a
// resumed or data-parallel run trains on what an uninterrupted one does.
using SampleSource = std::function<Dataset(std::uint64_t stream, Index count)>;
// The stream of the mini-batch after `iterations` updates of a run with seed `seed`: distinct for
// every (seed, iteration) (a 64-bit mix of both), so no two batches of a run share a stream.
std::uint64_t fresh_stream(std::uint64_t seed, long long iterations);

struct TrainerOptions {
  // The mini-batch size; a rule made of parts gives each part its own (batch_size()).
  Index batch_size = 32;
  // Stop after any of these; at least one must be set.
  std::optional<long long> max_iterations;
  std::optional<long long> max_epochs;
  // Wall time of the run (TrainingSummary::wall_seconds): steps, evaluations and checkpoints.
  // The run ends once it is spent, or before a step whose cost — the last step's, plus the
  // evaluation and checkpoint due after it, as last measured — would take the run past it;
  // the first step after a start or a resume is taken unmeasured (and the first of a rule's
  // next part is judged by its last part's step), so the run ends within the budget plus one
  // step with its evaluation and checkpoint, and makes at least one update. A run limited by
  // time writes its checkpoints no more often than keeps them to a tenth of its wall time
  // (checkpoint_every and checkpoint_seconds are then the shortest spacing).
  std::optional<double> time_budget_seconds;
  // Evaluate every this many iterations; unset: at the start and after every epoch.
  std::optional<long long> eval_every;
  // Also evaluate once this much training time has passed since the last evaluation (all
  // ranks of a data-parallel run agree on it). Leave it unset in runs limited by iterations or
  // epochs: which evaluations such a run makes then does not depend on timing, so a resumed or
  // data-parallel run reproduces them exactly.
  std::optional<double> eval_seconds;
  bool shuffle = true;
  std::uint64_t seed = 0;  // shuffling order, and the streams of fresh samples
  // When set, every mini-batch is drawn afresh from it (the HIG paper's protocol) instead of
  // taken from the training set, which then only sets the epoch's length (N samples) and gives
  // the evaluated training loss.
  SampleSource fresh_samples;
  // Data-parallel training: the ranks of this communicator share every mini-batch (Shard,
  // evaluate_batch()); none, or one rank: this process alone.
  std::shared_ptr<Communicator> communicator;
  // Adds experiment-specific figures to a record at each evaluation.
  std::function<void(const Network&, TrainingRecord&)> on_evaluate;
  // Progress line after each evaluation.
  std::function<void(const TrainingRecord&)> on_progress;
  // The cost yardstick: when set, beside some of its steps the run also times one step of this
  // rule (made once by the function; Adam, say) at the same θ on the step's batch, cut short or
  // its samples repeated to cost_reference_batch (the reference's own batch size): the forward
  // pass, the derivative it needs and its Δθ, which is never applied, plus its share of the
  // batch's draw (as in a run of its own; the step it stands beside includes its draw). Both are
  // timed in the process's CPU seconds (process_cpu_seconds(), all threads), which time spent
  // waiting for a core does not enter; every step of a part is timed, so a rule whose steps
  // differ in cost (a Kronecker rule refreshing its factors every k steps) is charged its mean,
  // not the cost of the steps a probe happened to follow. So each part's cost per update reads
  // in the reference's updates, whatever else the machine runs (Phase::reference_updates()). The
  // run's θ, data and results do not depend on it; probes are made after the first step of each
  // part and then whenever they have taken at most 2 % of the training time, and count toward the
  // wall time (not train_seconds). A part whose rule has the reference's id is not probed. A stop
  // request inside a probe drops the probe; the run stops at the next iteration boundary. Not in
  // data-parallel runs.
  std::function<std::unique_ptr<LearningUpdate>()> cost_reference;
  Index cost_reference_batch = 0;  // 0: the step's whole batch

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
};

// Trains `network` in place. The rule hears of every evaluation (LearningUpdate::observe()); when
// its phase() changes, the network is evaluated and the next part starts a new epoch with its
// batch size; the iteration count, training time, history and limits run on across parts.
// A run that a limit ends with its training loss above the first evaluation's ends as kDiverged.
// Throws Error on mismatched dimensions, invalid options, a resume state that does not fit, a
// fresh batch of the wrong shape, or an untrained network whose loss is not finite.
// Numerical guard (train_step()): a non-finite loss, derivative or step, or a NumericalError
// below the rule, never reaches θ; a failed step ends training with kNumericalFailure and a
// message naming the rule, the iteration and the place. An evaluation whose train or test loss
// is not finite also stops training, with θ restored to the last evaluated parameters, so
// neither θ nor the history ever holds a non-finite loss. A StopRequested thrown during an
// evaluation is not caught: training ends without a checkpoint of its own (the last one stays).
TrainingSummary train(Network& network, LearningUpdate& update, const LearningProblem& problem,
                      const Dataset& train_set, const Dataset* test_set,
                      const TrainerOptions& options);

// The epochs the updates of `summary` amount to: the samples of their batches (each part's
// iterations at its batch size, TrainingSummary::phases) over the training samples.
double epochs_done(const TrainingSummary& summary);

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
