// LearningSweep's training with checkpoints: a run finished in a resumed checkpoint is taken
// from it, one in progress continues from its saved state, any other trains, saving as it goes.
#include <cmath>
#include <new>

#include "physgrad/error.hpp"
#include "physgrad/run/cases/learning_runs.hpp"
#include "physgrad/run/life/checkpoint.hpp"
#include "physgrad/run/life/interrupt.hpp"

namespace physgrad::run {

namespace {

// Refuses the history of a run read from a checkpoint unless this experiment could have written
// it: no more iterations than the run's limit (and than 2⁵³), every test loss finite when the
// run has a test set, and each record's extras exactly the finite numbers the experiment's
// on_evaluate records (found by letting it fill one record for `network` as it is).
void check_saved_history(const RunKey& key, const TrainingSummary& summary,
                         const Network& network, bool has_test_set,
                         const TrainerOptions& options) {
  const long long limit = options.max_iterations.value_or(1LL << 53);
  if (summary.iterations > limit) {
    throw Error("checkpoint: " + key.describe() + " has " + std::to_string(summary.iterations) +
                " iterations, more than the run's " + std::to_string(limit));
  }
  TrainingRecord probe;
  if (options.on_evaluate) options.on_evaluate(network, probe);
  for (const TrainingRecord& record : summary.history) {
    std::string problem;
    if (has_test_set && !std::isfinite(record.test_loss)) problem = "has no finite test loss";
    for (const auto& item : probe.extras.items()) {
      const std::string& name = item.key();
      if (problem.empty() && !(record.extras.contains(name) &&
                               record.extras.at(name).is_number() &&
                               std::isfinite(record.extras.at(name).get<double>()))) {
        problem = "has no finite '" + name + "'";
      }
    }
    if (problem.empty() && record.extras.size() != probe.extras.size()) {
      problem = "has values this experiment does not record";
    }
    if (!problem.empty()) {
      throw Error("checkpoint: " + key.describe() + ": the record of iteration " +
                  std::to_string(record.iteration) + " " + problem);
    }
  }
}

}  // namespace

TrainingSummary LearningSweep::train_or_resume(const RunKey& key, Network& network,
                                               LearningUpdate& update,
                                               const LearningProblem& problem,
                                               const Dataset& train_set, const Dataset* test_set,
                                               TrainerOptions options) {
  options.stop = context_.stop_flag();
  ExperimentCheckpoint* checkpoint = context_.checkpoint();
  std::optional<TrainerState> state;
  if (checkpoint != nullptr) {
    const Index count = network.num_parameters();
    if (std::optional<FinishedRun> done = checkpoint->finished(key, count)) {
      check_saved_history(key, done->summary, network, test_set != nullptr, options);
      network.set_parameters(done->parameters);
      return std::move(done->summary);
    }
    state = checkpoint->in_progress(key, count);
    if (state) {
      check_saved_history(key, state->summary, network, test_set != nullptr, options);
      options.resume = &*state;
    }
    if (settings_.has("checkpoint-every")) {
      options.checkpoint_every = settings_.integer("checkpoint-every");
    }
    options.checkpoint_seconds = settings_.real("checkpoint-seconds");
    options.on_checkpoint = [checkpoint, &key, stop = options.stop](const TrainerState& s) {
      if (stop != nullptr && stop->load()) stop_point_reached();  // saving, then ending
      checkpoint->save_progress(key, s);
    };
  }
  TrainingSummary summary;
  try {
    summary = train(network, update, problem, train_set, test_set, options);
  } catch (const Error& e) {
    throw Error(key.describe() + ": " + e.what());  // names the setting (λ=…, ξ=…) and seed
  } catch (const std::bad_alloc&) {
    throw Error(key.describe() + ": out of memory while training (--batch, --train-size or the "
                "network need more than this process may use)");
  }
  if (summary.termination == TrainingTermination::kInterrupted) {
    stop_point_reached();
    throw Interrupted(context_.experiment_name() + ": " + key.describe() + " " + summary.message);
  }
  if (checkpoint != nullptr) checkpoint->record_finished(key, summary, network.parameters());
  return summary;
}

}  // namespace physgrad::run
