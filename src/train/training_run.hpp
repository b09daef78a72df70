// TrainingRun — one run of train() (trainer.hpp): the loop state between iterations, which a
// checkpoint holds, around train_step(). Private to the library (src/train/).
#pragma once

#include <chrono>
#include <string>
#include <utility>
#include <vector>

#include "physgrad/timing.hpp"
#include "physgrad/train/trainer.hpp"

namespace physgrad::training {

// One training run: the loop state between iterations (what a checkpoint holds) around
// train_step().
class TrainingRun {
 public:
  TrainingRun(Network& network, LearningUpdate& update, const LearningProblem& problem,
              const Dataset& train_set, const Dataset* test_set, const TrainerOptions& options)
      : network_(network),
        update_(update),
        problem_(problem),
        train_set_(train_set),
        test_set_(test_set),
        options_(options),
        n_(train_set.size()) {
    step_state_.shard = Shard(options.communicator);
    step_state_.max_step_halvings = options.max_step_halvings;
  }

  TrainingSummary run();

 private:
  // The batch size the rule asks for now (its part's), at most the training set's size.
  Index batch_size_now() const {
    return std::min(update_.batch_size().value_or(options_.batch_size), n_);
  }
  // Where the data order stands after `iterations` updates: (epoch, start of the next batch).
  // Every epoch of one part takes the same number of batches; each part after the first begins
  // a new epoch (summary_.phases).
  std::pair<long long, Index> position(long long iterations) const;
  // The rule's next part took over: a new phase at a new epoch with its batch size.
  void begin_phase();
  // Whether the rule has moved on to its next part since the last begin_phase().
  bool phase_changed() const { return update_.phase() != phase_; }
  void restore(const TrainerState& state);
  // What happens between two iterations besides the iteration schedule: a stop request, the
  // time budget and an evaluation due by time, agreed by all ranks of a data-parallel run (any
  // rank's counts), so that every rank stops and evaluates at the same iteration.
  struct Requests {
    bool stop = false;
    bool time_out = false;  // the budget is spent
    bool overrun = false;   // the next step would take the run past it (next_step_cost())
    bool evaluate = false;
    double spent = 0;  // the run's wall time when this rank judged the budget
  };
  Requests requests() const;
  // What the next step would add to the run's wall time as last measured: the evaluation and
  // checkpoint due before it (`due_before`), the step, the evaluation after it (by the
  // schedule, or the run's last) and the checkpoint after it when checkpoint_every asks for one.
  double next_step_cost(double due_before) const;
  // The run's wall time so far: the resumed state's and this process's since run() began.
  double wall_now() const { return wall_before_ + seconds_since(started_); }
  // Times the evaluation (evaluation_cost_) and keeps the run's wall time in the summary.
  bool evaluate();
  bool evaluate_now();
  Dataset batch(const std::vector<Index>& order, Index count) const;
  bool step(const Dataset& batch);
  // The next batch of the epoch's `order` drawn and stepped on, its wall time kept as the last
  // step's cost (step_cost_) and its CPU time handed to probe_cost(); false as step().
  bool timed_step(const std::vector<Index>& order);
  // Counts the step rule `part` just made on `batch` (step_cpu CPU seconds, of which draw_cpu drew
  // the batch) toward its part's cost, and times a step of the cost reference beside it when one
  // is due (TrainerOptions::cost_reference).
  void probe_cost(const Dataset& batch, const std::string& part, double step_cpu,
                  double draw_cpu);
  void stop_for_numbers(const std::string& message);
  bool checkpoint_due() const;
  void checkpoint();
  // Sets what ran in the summary: the rule, its settings, the problem's size and the limits.
  void describe_run();
  // A limit ended the run: kDiverged instead when its training loss ended above its start.
  // `why` becomes the message (with the divergence's, when there is one).
  void end_by_limit(TrainingTermination limit, const std::string& why = "");
  // "time limit: next step would overrun (…)", with the budget and the costs it was judged by.
  std::string overrun_message(double spent) const;
  // Saves a checkpoint and ends with kInterrupted and `message`.
  TrainingSummary interrupted(std::string message);
  bool ended() const { return summary_.termination.has_value(); }

  Network& network_;
  LearningUpdate& update_;
  const LearningProblem& problem_;
  const Dataset& train_set_;
  const Dataset* test_set_;
  const TrainerOptions& options_;
  const Index n_;

  int phase_ = 0;         // the rule's phase() the current part began with
  Index batch_size_ = 0;  // of the current part

  TrainingSummary summary_;
  StepState step_state_;
  long long epoch_ = 0;
  Index batch_start_ = 0;
  Vector last_evaluated_;
  bool evaluated_ = false;  // θ is the one of the last history record
  std::chrono::steady_clock::time_point last_checkpoint_time_ = std::chrono::steady_clock::now();
  long long last_checkpoint_iteration_ = 0;
  std::chrono::steady_clock::time_point started_ = std::chrono::steady_clock::now();
  double wall_before_ = 0;  // the resumed state's wall time
  // Wall seconds of the last step, evaluation and checkpoint (0 until one is measured).
  double step_cost_ = 0;
  double evaluation_cost_ = 0;
  double checkpoint_cost_ = 0;
  // The cost reference (TrainerOptions::cost_reference), its own forward cache, and the probes'
  // wall seconds in this process (what keeps them to their share of the training time).
  std::unique_ptr<LearningUpdate> reference_;
  std::unique_ptr<NetworkCache> reference_cache_;
  double probe_seconds_ = 0;
};

// Throws Error naming the first option out of range, or a run without a limit.
void check_trainer_options(const TrainerOptions& options);

}  // namespace physgrad::training
