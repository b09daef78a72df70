#include "physgrad/run/learning_runs.hpp"

#include <algorithm>
#include <cmath>
#include <new>

#include "physgrad/run/checkpoint.hpp"
#include "physgrad/run/direct_runs.hpp"
#include "physgrad/run/interrupt.hpp"
#include "physgrad/error.hpp"
#include "physgrad/memory.hpp"
#include "physgrad/io/serialize.hpp"

namespace physgrad::experiments {

namespace {

// Evaluations by time in a run limited by --time alone: this many over the budget.
constexpr double kEvaluationsOverTime = 40;

// Refuses the history of a run read from a checkpoint unless this experiment could have written
// it: no more iterations than the run's limit (and than 2⁵³), every test loss finite when the
// run has a test set, and each record's extras exactly the finite numbers the experiment's
// on_evaluate records (found by letting it fill one record for `network` as it is).
void check_saved_history(const RunKey& key, const TrainingSummary& summary, const Mlp& network,
                         bool has_test_set, const TrainerOptions& options) {
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

LearningSweep::LearningSweep(const Settings& settings, RunContext& context,
                             std::map<std::string, RuleDefaults> defaults)
    : settings_(settings), context_(context), defaults_(std::move(defaults)) {}

const LearningResult& LearningSweep::run(const std::string& id, const std::string& tag,
                                         const nlohmann::json& params, Mlp& network,
                                         const LearningProblem& problem,
                                         const Dataset& train_set, const Dataset* test_set,
                                         std::function<void(const Mlp&, TrainingRecord&)> observe) {
  const auto found = defaults_.find(id);
  const RuleDefaults defaults = found == defaults_.end() ? RuleDefaults{} : found->second;
  RuleSettings rule = defaults.settings;
  if (settings_.has("lr")) rule.lr = settings_.real("lr");
  if (settings_.has("rcond")) rule.rcond = settings_.real("rcond");
  const std::unique_ptr<LearningUpdate> update = make_learning_update(id, rule);

  LearningResult result;
  result.id = id;
  result.tag = tag;
  result.label = find_rule(RuleKind::kLearning, id).label + " (" + tag + ")";
  result.seed = params.value("seed", 0LL);

  TrainerOptions options;
  options.batch_size = settings_.has("batch") ? settings_.integer("batch")
                                               : defaults.batch.value_or(options.batch_size);
  if (settings_.has("iters")) options.max_iterations = settings_.integer("iters");
  if (settings_.has("epochs")) options.max_epochs = settings_.integer("epochs");
  if (settings_.has("time")) options.time_budget_seconds = settings_.real("time");
  // A run limited by time alone is also evaluated by time, so that slow rules get as many
  // points as fast ones; runs with an iteration or epoch limit keep the iteration schedule
  // alone, which a resumed or data-parallel run reproduces exactly.
  if (settings_.has("time") && !settings_.has("iters") && !settings_.has("epochs")) {
    options.eval_seconds = settings_.real("time") / kEvaluationsOverTime;
  }
  if (settings_.has("eval-every")) options.eval_every = settings_.integer("eval-every");
  options.seed = static_cast<std::uint64_t>(result.seed);
  options.communicator = context_.communicator();
  if (observe) {
    options.on_evaluate = [&network, observe](const Network&, TrainingRecord& record) {
      observe(network, record);
    };
  }
  options.on_progress = [&](const TrainingRecord& r) {
    context_.progress(context_.experiment_name() + ": " + result.label + " seed " +
                      std::to_string(result.seed) + ", iteration " +
                      std::to_string(r.iteration) + ", test loss " + format_value(r.test_loss));
  };
  result.summary = train_or_resume(RunKey{context_.next_learning_run(), id, tag, result.seed},
                                   network, *update, problem, train_set, test_set, options);
  context_.finish_progress();
  context_.add_network({{"label", result.label},
                        {"seed", result.seed},
                        {"widths", network.widths()},
                        {"parameters", vector_to_json(network.parameters())}});

  nlohmann::json run_params = update->params();
  run_params["batch"] = options.batch_size;
  result.params = run_params;
  for (const auto& [key, value] : params.items()) run_params[key] = value;
  for (const TrainingRecord& r : result.summary.history) {
    nlohmann::json row = {{"label", result.label},  {"optimizer", id},
                          {"iteration", r.iteration}, {"epoch", r.epoch},
                          {"wall_seconds", r.train_seconds}, {"train_loss", r.train_loss},
                          {"test_loss", r.test_loss}};
    for (const auto& [key, value] : params.items()) row[key] = value;
    for (const auto& [key, value] : r.extras.items()) row[key] = value;
    context_.add_metrics_row(std::move(row));
  }
  const TrainingSummary& s = result.summary;
  nlohmann::json final_figures = {{"loss", s.history.back().train_loss},
                                  {"test_loss", s.history.back().test_loss}};
  for (const auto& [key, value] : s.history.back().extras.items()) final_figures[key] = value;
  context_.add_run({{"label", result.label},
                    {"optimizer", id},
                    {"params", run_params},
                    {"initial", {{"loss", s.history.front().train_loss},
                                 {"test_loss", s.history.front().test_loss}}},
                    {"final", final_figures},
                    {"iterations", s.iterations},
                    {"epochs", s.history.back().epoch},
                    {"wall_seconds", s.train_seconds},
                    {"termination", to_string(*s.termination)},
                    {"message", s.message},
                    {"step_halvings", s.step_halvings},
                    {"seconds_per_part", {{"forward", s.forward_seconds},
                                          {"derivatives", s.derivative_seconds},
                                          {"inversion", s.inversion_seconds},
                                          {"update", s.update_seconds}}}});
  results_.push_back(std::move(result));
  return results_.back();
}

TrainingSummary LearningSweep::train_or_resume(const RunKey& key, Mlp& network,
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

}  // namespace physgrad::experiments
