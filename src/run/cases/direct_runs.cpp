#include "physgrad/run/cases/direct_runs.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "physgrad/error.hpp"
#include "physgrad/memory.hpp"
#include "physgrad/run/cases/rule_colors.hpp"
#include "physgrad/report/landscape.hpp"
#include "physgrad/report/line_plot.hpp"

namespace physgrad::run {

std::vector<RuleSetup> selected_rules(const Settings& settings,
                                      const std::map<std::string, double>& default_lr) {
  std::vector<RuleSetup> rules;
  for (const std::string& id : settings.texts("optimizers")) {
    RuleSetup rule{id, find_rule(RuleKind::kDirect, id).label, {}, nlohmann::json::object()};
    if (const auto it = default_lr.find(id); it != default_lr.end()) rule.settings["lr"] = it->second;
    for (const auto& [name, value] : rule_settings(settings, RuleKind::kDirect)) {
      rule.settings[name] = value;
    }
    rules.push_back(rule);
  }
  return rules;
}

void require_start(const Objective& objective, const Vector& x0, const std::string& where) {
  const double loss = objective.value(x0);
  if (loss > 0 && std::isfinite(loss)) return;
  std::string point;
  for (Index i = 0; i < x0.size(); ++i) point += (i ? ", " : "") + format_value(x0(i));
  if (x0.size() > 1) point = "(" + point + ")";
  throw Error("--start: the loss at " + point + " is " + format_value(loss) + where +
              (loss == 0 ? ": already a minimum, nothing to optimize"
                         : ": give a start where it is finite"));
}

void require_iterate_memory(const Settings& settings, std::size_t runs) {
  constexpr double kIterateBytes = 2048;
  const long long iterations = settings.integer("iters");
  require_memory(static_cast<double>(iterations) * static_cast<double>(runs) * kIterateBytes,
                 "--iters: " + std::to_string(iterations) + " (" + std::to_string(runs) +
                     " runs keeping every iterate)");
}

std::vector<RuleSetup> with_pg_inverses(const std::vector<RuleSetup>& rules,
                                        const std::vector<std::string>& methods) {
  std::vector<RuleSetup> out;
  for (const RuleSetup& rule : rules) {
    if (rule.id != "pg") {
      out.push_back(rule);
      continue;
    }
    for (const std::string& method : methods) {
      RuleSetup pg = rule;
      pg.settings["inverse"] = method;
      if (method == "analytic") {
        pg.label = "PG (analytic inverse)";
      } else if (method == "time_reversal") {
        pg.label = "PG (time reversal)";
      } else {
        pg.label = "PG (" + find_rule(RuleKind::kDirect, method).label + " inverse)";
      }
      pg.extra_params["inverse"] = method;
      out.push_back(pg);
    }
  }
  return out;
}

DirectResult run_direct(RunContext& context, const RuleSetup& rule, const Objective& objective,
                        const Vector& x0, int iterations, double tolerance,
                        const nlohmann::json& row_extras,
                        const std::function<nlohmann::json(const IterationRecord&)>& columns) {
  const std::unique_ptr<Optimizer> optimizer = make_optimizer(rule.id, rule.settings);
  MinimizeOptions options;
  options.max_iterations = iterations;
  options.loss_tolerance = tolerance;
  options.callback = [&context](const IterationRecord&) {
    context.check_interrupt();
    return false;
  };
  DirectResult result{rule, minimize(*optimizer, objective, x0, options), 0};
  result.initial_loss = result.summary.history.front().loss;

  for (const IterationRecord& record : result.summary.history) {
    nlohmann::json row = {{"label", rule.label},
                          {"optimizer", rule.id},
                          {"iteration", record.iteration},
                          {"wall_seconds", record.seconds},
                          {"loss", record.loss},
                          {"step_norm", record.step_norm}};
    for (const auto& [key, value] : row_extras.items()) row[key] = value;
    if (columns) {
      const nlohmann::json extra = columns(record);
      for (const auto& [key, value] : extra.items()) row[key] = value;
    }
    for (Index i = 0; i < record.x.size(); ++i) {
      std::string column = "x";
      column += std::to_string(i);
      row[column] = record.x(i);
    }
    context.add_metrics_row(std::move(row));
  }

  nlohmann::json params = optimizer->params();
  for (const auto& [key, value] : rule.extra_params.items()) params[key] = value;
  for (const auto& [key, value] : row_extras.items()) params[key] = value;
  const MinimizeSummary& s = result.summary;
  // The final entry also holds the iterate and the extra columns of the last one (e.g. its
  // simulator passes).
  RunEntry entry;
  entry.label = rule.label;
  entry.optimizer = rule.id;
  entry.params = params;
  entry.initial.loss = result.initial_loss;
  entry.final.loss = s.loss;
  entry.final.more["x"] = std::vector<double>(s.x.begin(), s.x.end());
  if (columns) {  // with the whole run's work, that of a last step that failed included
    IterationRecord last = s.history.back();
    last.counts = s.counts;
    entry.final.more.update(columns(last));
  }
  entry.iterations = s.iterations;
  entry.wall_seconds = s.wall_seconds;
  entry.termination = to_string(s.termination);
  entry.message = s.message;
  context.add_run(std::move(entry));
  return result;
}

std::string iterations_cell(const DirectResult& result) {
  const MinimizeSummary& s = result.summary;
  switch (s.termination) {
    case Termination::kConverged: return std::to_string(s.iterations);
    case Termination::kNumericalFailure: return "diverged at " + std::to_string(s.iterations + 1);
    case Termination::kFailed: return "failed at " + std::to_string(s.iterations + 1);
    case Termination::kStationary: return "stalled at " + std::to_string(s.iterations);
    default: break;
  }
  if (s.loss > result.initial_loss) {
    return "diverging (L ×" + format_value(s.loss / result.initial_loss) + " after " +
           std::to_string(s.iterations) + ")";
  }
  return "> " + std::to_string(s.iterations);
}

std::string outcome_phrase(const DirectResult& result) {
  const MinimizeSummary& s = result.summary;
  const std::string at = " at iteration " + std::to_string(s.iterations + 1);
  switch (s.termination) {
    case Termination::kConverged:
      return "needs " + std::to_string(s.iterations) + " iterations";
    case Termination::kNumericalFailure: return "diverged" + at;
    case Termination::kFailed: return "failed" + at;
    case Termination::kStationary:
      return "stalled at iteration " + std::to_string(s.iterations);
    default: break;
  }
  if (s.loss > result.initial_loss) return "is " + iterations_cell(result);
  return "has not converged after " + std::to_string(s.iterations) + " iterations";
}

std::string step_size_text(const RuleSetup& rule) {
  const nlohmann::json params = make_optimizer(rule.id, rule.settings)->params();
  if (params.contains("lr")) return format_value(params["lr"].get<double>());
  if (params.contains("initial_step")) {
    return "line search from " + format_value(params["initial_step"].get<double>());
  }
  if (params.contains("initial_damping")) {
    return "adaptive μ from " + format_value(params["initial_damping"].get<double>());
  }
  return "–";
}

std::string loss_curves_svg(const std::vector<DirectResult>& results, const std::string& title,
                            const std::string& x_label,
                            const std::function<double(std::size_t, std::size_t)>& x_of,
                            bool log_x) {
  std::vector<Series> series;
  for (std::size_t r = 0; r < results.size(); ++r) {
    const DirectResult& result = results[r];
    Series line{result.rule.label, {}, {}, color_for(result.rule.id), false, false};
    const auto& history = result.summary.history;
    for (std::size_t k = 0; k < history.size(); ++k) {
      const double x = x_of ? x_of(r, k) : static_cast<double>(history[k].iteration);
      if (std::isnan(x)) break;
      line.x.push_back(x);
      line.y.push_back(history[k].loss);
    }
    line.markers = line.x.size() <= 40;
    line.steps = static_cast<bool>(x_of);
    // Dashed: PG through a numerical local inverse (solid: analytic or time-reversal inverse),
    // each inverse with a marker shape of its own, so that PG's variants differ beyond colour.
    const std::string inverse = result.rule.extra_params.value("inverse", std::string());
    line.dashed = !inverse.empty() && inverse != "analytic" && inverse != "time_reversal";
    if (!inverse.empty()) {
      static const std::vector<std::string> kInverses = {"analytic", "time_reversal", "lbfgs",
                                                         "gn", "ig"};
      const auto at = std::find(kInverses.begin(), kInverses.end(), inverse);
      line.markers = true;
      line.shape = 1 + static_cast<int>(at - kInverses.begin()) % 4;
    }
    // A run that diverged is marked at its end instead of stretching the loss axis.
    const MinimizeSummary& s = result.summary;
    if (s.termination == Termination::kNumericalFailure || s.loss > result.initial_loss) {
      line.sets_range = false;
      line.end_label = iterations_cell(result);
    } else if (s.termination == Termination::kFailed) {
      line.end_label = iterations_cell(result);
    }
    series.push_back(std::move(line));
  }
  LinePlotOptions options;
  options.title = title;
  options.x_label = x_label;
  options.y_label = "loss";
  options.log_y = true;
  options.log_x = log_x;
  return line_plot_svg(series, options);
}

Grid2D sample_grid(const std::function<double(double, double)>& f, double x_min, double x_max,
                   double y_min, double y_max, int n) {
  Grid2D grid{x_min, x_max, y_min, y_max, n, n, std::vector<double>(static_cast<std::size_t>(n * n))};
  for (int j = 0; j < n; ++j) {
    const double y = y_min + (y_max - y_min) * j / (n - 1);
    for (int i = 0; i < n; ++i) {
      const double x = x_min + (x_max - x_min) * i / (n - 1);
      grid.values[static_cast<std::size_t>(j * n + i)] = f(x, y);
    }
  }
  return grid;
}

std::vector<Trajectory> trajectories(const std::vector<DirectResult>& results) {
  std::vector<Trajectory> out;
  for (const DirectResult& result : results) {
    Trajectory t{result.rule.label, {}, {}, color_for(result.rule.id)};
    for (const IterationRecord& record : result.summary.history) {
      t.x.push_back(record.x(0));
      t.y.push_back(record.x.size() > 1 ? record.x(1) : 0.0);
    }
    out.push_back(std::move(t));
  }
  return out;
}


}  // namespace physgrad::run
