#include "learning_runs.hpp"

#include <algorithm>
#include <cmath>
#include <new>

#include "checkpoint.hpp"
#include "direct_runs.hpp"
#include "interrupt.hpp"
#include "physgrad/error.hpp"
#include "physgrad/report/colors.hpp"
#include "physgrad/report/line_plot.hpp"
#include "physgrad/report/seed_band.hpp"
#include "physgrad/serialize.hpp"

namespace physgrad::experiments {

namespace {

std::string rule_label(const std::string& id) {
  return find_rule(RuleKind::kLearning, id).label;
}

// Evaluations by time in a run limited by --time alone: this many over the budget.
constexpr double kEvaluationsOverTime = 40;

double final_test_loss(const LearningResult& r) { return r.summary.history.back().test_loss; }

std::string milliseconds(double seconds, long long steps) {
  return steps > 0 ? format_value(1e3 * seconds / static_cast<double>(steps)) : "–";
}

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

Series held_controls(const std::string& label, const Vector& u, double dt,
                     const std::string& color) {
  Series s{label, {}, std::vector<double>(u.data(), u.data() + u.size()), color};
  for (Index k = 0; k <= u.size(); ++k) s.x.push_back(dt * static_cast<double>(k));
  if (u.size() > 0) s.y.push_back(s.y.back());
  s.steps = true;
  return s;
}

OptionSpec sample_count_option(std::string name, std::string default_text, std::string help,
                               std::string quick,
                               std::function<double(const Settings&)> bytes_each) {
  return integer_option(std::move(name), std::move(default_text), std::move(help))
      .at_least(1)
      .needs_bytes_each(std::move(bytes_each))
      .quick(std::move(quick));
}

double sample_bytes(const std::vector<Index>& widths, Index data_values) {
  double values = static_cast<double>(data_values);
  for (const Index width : widths) values += 2.0 * static_cast<double>(width);
  return values * sizeof(double);
}

void require_training_limit(const Settings& settings, const std::string& experiment) {
  if (!settings.has("iters") && !settings.has("epochs") && !settings.has("time")) {
    throw Error(experiment + ": give at least one of --iters, --epochs, --time");
  }
}

std::vector<OptionSpec> learning_options(const std::string& default_time,
                                         const std::string& default_eval_every) {
  return {
      integer_option("batch", "", "mini-batch size for every rule (default: each rule's own)")
          .at_least(1),
      real_option("rcond", "", "relative truncation τ of gn and hig (default: each rule's own)")
          .at_least(0)
          .at_most(0.5),
      integer_option("epochs", "", "epochs per run").at_least(1),
      real_option("time", default_time,
                  "training-time budget per run in seconds, evaluations excluded (the first of "
                  "--iters, --epochs, --time reached ends a run; a run limited by --time alone is "
                  "also evaluated every 1/40 of it)")
          .above(0),
      integer_option("eval-every", default_eval_every,
                     "evaluate every N iterations (default: every epoch)")
          .at_least(1),
      integer_option("checkpoint-every", "",
                     "also save a checkpoint every N iterations (physgrad resume continues it)")
          .at_least(1),
      real_option("checkpoint-seconds", "60",
                  "save a checkpoint of the run in progress at least this often (wall seconds)")
          .above(0),
  };
}

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
  result.label = rule_label(id) + " (" + tag + ")";
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
      // Every epoch takes the same number of batches, so the position follows from the count.
      const Index batch = std::min(options.batch_size, train_set.size());
      const long long batches = (train_set.size() + batch - 1) / batch;
      if (state->batch_start % batch != 0 ||
          state->epoch != state->summary.iterations / batches ||
          state->batch_start / batch != state->summary.iterations % batches) {
        throw Error("checkpoint: " + key.describe() + ": epoch " + std::to_string(state->epoch) +
                    " and batch start " + std::to_string(state->batch_start) +
                    " do not follow from its " + std::to_string(state->summary.iterations) +
                    " iterations (" + std::to_string(batches) + " batches per epoch)");
      }
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

std::vector<const LearningResult*> LearningSweep::first_seed_runs(const std::string& tag) const {
  std::vector<const LearningResult*> runs;
  for (const LearningResult& r : results_) {
    const bool seen = std::any_of(runs.begin(), runs.end(),
                                  [&](const LearningResult* other) { return other->id == r.id; });
    if (r.tag == tag && !seen) runs.push_back(&r);
  }
  return runs;
}

std::vector<std::vector<const LearningResult*>> LearningSweep::rule_groups(
    const std::string& tag) const {
  std::vector<std::vector<const LearningResult*>> groups;
  for (const LearningResult& r : results_) {
    if (r.tag != tag) continue;
    const auto group = std::find_if(groups.begin(), groups.end(), [&](const auto& g) {
      return g.front()->id == r.id;
    });
    if (group == groups.end()) {
      groups.push_back({&r});
    } else {
      group->push_back(&r);
    }
  }
  return groups;
}

void LearningSweep::add_metric_figure(RunContext& context,
                                      const std::vector<std::vector<const LearningResult*>>& groups,
                                      const std::string& file, const std::string& title,
                                      const std::string& y_label,
                                      const std::function<double(const TrainingRecord&)>& value,
                                      Progress progress, bool log_y) {
  std::vector<Series> series;
  bool several_seeds = false;
  for (const auto& group : groups) {
    std::vector<Curve> curves;
    long long stopped = 0;
    for (const LearningResult* run : group) {
      Curve& c = curves.emplace_back();
      for (const TrainingRecord& r : run->summary.history) {
        c.x.push_back(progress == Progress::kTime    ? r.train_seconds
                      : progress == Progress::kEpoch ? r.epoch
                                                     : static_cast<double>(r.iteration));
        c.y.push_back(value(r));
      }
      stopped += run->summary.termination == TrainingTermination::kNumericalFailure ? 1 : 0;
    }
    const std::size_t n = group.size();
    several_seeds = several_seeds || n > 1;
    const LearningResult& first = *group.front();
    Series s = median_band(first.label + (n > 1 ? ", median of " + std::to_string(n) : ""),
                           curves, color_for(first.id), log_y);
    s.markers = true;
    // Over time the seeds are evaluated at different moments: each holds its last value, so
    // median and band change in steps.
    s.steps = n > 1 && progress == Progress::kTime;
    // A loss that ends above where it started (a diverging rule) does not set the axis range.
    if (log_y && s.y.size() > 1 && s.y.back() > s.y.front()) {
      s.sets_range = false;
      s.end_label = "diverging: ends at ×" + format_value(s.y.back() / s.y.front()) + " its start";
    }
    if (stopped > 0) {
      s.end_label = n > 1 ? std::to_string(stopped) + " of " + std::to_string(n) +
                                " runs stopped: not finite"
                          : "stopped: not finite after iteration " +
                                std::to_string(first.summary.iterations);
    }
    series.push_back(std::move(s));
  }
  LinePlotOptions options;
  options.title = title;
  options.x_label = progress == Progress::kTime    ? "training time (s, evaluations excluded)"
                    : progress == Progress::kEpoch ? "epoch"
                                                   : "iteration";
  options.y_label = y_label;
  options.log_y = log_y;
  // Rules that run for one time budget can end hundreds of iterations apart (HIG's step costs
  // what hundreds of Adam steps do): a log x axis keeps the shorter runs visible.
  double shortest = 0, longest = 0;
  for (const Series& s : series) {
    if (s.x.empty()) continue;
    shortest = shortest == 0 ? s.x.back() : std::min(shortest, s.x.back());
    longest = std::max(longest, s.x.back());
  }
  options.log_x = progress != Progress::kTime && shortest > 0 && longest >= 30 * shortest;
  const std::string caption =
      title + ". " +
      (several_seeds ? "Line: median over the seeds; band: their minimum to maximum. " : "") +
      "Dots: evaluations." +
      (options.log_x ? " Log x axis (the start is not drawn): the rules ran " +
                           format_value(shortest) + " to " + format_value(longest) + " " +
                           options.x_label + "s in the same budget."
                     : "");
  context.add_figure({file, caption, line_plot_svg(series, options)});
}

void LearningSweep::add_loss_figures(RunContext& context, const std::string& tag,
                                     const std::string& file_tag, bool by_epoch,
                                     const std::string& loss_label) const {
  const auto test_loss = [](const TrainingRecord& r) { return r.test_loss; };
  const auto groups = rule_groups(tag);
  for (const Progress progress :
       {by_epoch ? Progress::kEpoch : Progress::kIteration, Progress::kTime}) {
    const std::string axis = progress == Progress::kTime    ? "time"
                             : progress == Progress::kEpoch ? "epoch"
                                                            : "iteration";
    add_metric_figure(context, groups, "loss_vs_" + axis + "_" + file_tag + ".svg",
                      "Test loss vs " +
                          std::string(progress == Progress::kTime ? "training time" : axis) +
                          " (" + tag + ")",
                      loss_label, test_loss, progress);
  }
}

void LearningSweep::add_tables() const {
  std::vector<std::string> tags, ids;
  std::vector<long long> seeds;
  for (const LearningResult& r : results_) {
    if (std::find(tags.begin(), tags.end(), r.tag) == tags.end()) tags.push_back(r.tag);
    if (std::find(ids.begin(), ids.end(), r.id) == ids.end()) ids.push_back(r.id);
    if (std::find(seeds.begin(), seeds.end(), r.seed) == seeds.end()) seeds.push_back(r.seed);
  }
  const auto find = [&](const std::string& tag, const std::string& id, long long seed) {
    const auto it = std::find_if(results_.begin(), results_.end(), [&](const LearningResult& r) {
      return r.tag == tag && r.id == id && r.seed == seed;
    });
    return it == results_.end() ? nullptr : &*it;
  };
  const bool has_saturation =
      !results_.empty() && results_.front().summary.history.back().extras.contains(
                               "saturated_fraction");

  for (const std::string& tag : tags) {
    RunContext::Table losses{"Final test loss per seed (" + tag +
                                 "): the mean loss over the test set after the last iteration, "
                                 "with the median and the worst over the seeds",
                             {"rule"}, {}};
    RunContext::Table saturation{"Saturated hidden neurons at the end, per seed (" + tag +
                                     "): the fraction (0 to 1) of hidden neurons with |tanh| > "
                                     "0.99 on every test input",
                                 {"rule"}, {}};
    for (const long long seed : seeds) {
      losses.header.push_back("seed " + std::to_string(seed));
      saturation.header.push_back("seed " + std::to_string(seed));
    }
    losses.header.insert(losses.header.end(), {"median", "worst"});
    for (const std::string& id : ids) {
      std::vector<std::string> row = {rule_label(id)}, saturated = {rule_label(id)};
      std::vector<double> values;
      for (const long long seed : seeds) {
        const LearningResult* r = find(tag, id, seed);
        if (r == nullptr) {
          row.push_back("–");
          saturated.push_back("–");
          continue;
        }
        values.push_back(final_test_loss(*r));
        row.push_back(format_value(values.back()) +
                      (r->summary.termination == TrainingTermination::kNumericalFailure ? " (NaN stop)"
                                                                                   : ""));
        if (has_saturation) {
          saturated.push_back(format_value(r->summary.history.back().extras["saturated_fraction"]));
        }
      }
      std::sort(values.begin(), values.end());
      const std::size_t n = values.size();
      const double median = n == 0 ? NAN
                            : n % 2 ? values[n / 2]
                                    : 0.5 * (values[n / 2 - 1] + values[n / 2]);
      row.push_back(format_value(median));
      row.push_back(n == 0 ? "–" : format_value(values.back()));
      losses.rows.push_back(std::move(row));
      saturation.rows.push_back(std::move(saturated));
    }
    context_.add_table(std::move(losses));
    if (has_saturation) context_.add_table(std::move(saturation));
  }

  RunContext::Table timing{"Time per training step in milliseconds, mean over seeds: the "
                           "forward pass of network, physics and loss; the gradient or stacked "
                           "Jacobian; the inversion inside gn/hig; the rest of the update",
                           {"rule", "setting", "forward (ms)", "gradient or Jacobian (ms)",
                            "inversion (ms)", "update (ms)", "total (ms)"},
                           {}};
  for (const std::string& tag : tags) {
    for (const std::string& id : ids) {
      TrainingSummary total;
      for (const LearningResult& r : results_) {
        if (r.tag != tag || r.id != id) continue;
        total.iterations += r.summary.iterations;
        total.forward_seconds += r.summary.forward_seconds;
        total.derivative_seconds += r.summary.derivative_seconds;
        total.inversion_seconds += r.summary.inversion_seconds;
        total.update_seconds += r.summary.update_seconds;
        total.train_seconds += r.summary.train_seconds;
      }
      const long long steps = total.iterations;
      timing.rows.push_back({rule_label(id), tag, milliseconds(total.forward_seconds, steps),
                             milliseconds(total.derivative_seconds, steps),
                             milliseconds(total.inversion_seconds, steps),
                             milliseconds(total.update_seconds, steps),
                             milliseconds(total.train_seconds, steps)});
    }
  }
  context_.add_table(std::move(timing));
}

}  // namespace physgrad::experiments
