// Shared pieces of the direct-optimization experiments: build the selected update rules with
// per-experiment step sizes, run them, and record metrics rows and summary entries.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "physgrad/run/life/experiment.hpp"
#include "physgrad/optim/minimize.hpp"
#include "physgrad/catalogue.hpp"
#include "physgrad/report/colors.hpp"
#include "physgrad/report/landscape.hpp"
#include "physgrad/report/line_plot.hpp"

namespace physgrad::run {

// One configured rule of an experiment: id, display label and its settings.
struct RuleSetup {
  std::string id;
  std::string label;
  RuleSettings settings;
  nlohmann::json extra_params = nlohmann::json::object();  // e.g. {"inverse": "lbfgs"}
};

// The rules selected by --optimizers, each with --lr if given, else the experiment's default
// step size for that id (absent from `default_lr`: the library default).
std::vector<RuleSetup> selected_rules(const Settings& settings,
                                      const std::map<std::string, double>& default_lr);

// `rules` with every pg entry replaced by one run per local-inverse method ("analytic",
// "time_reversal", "lbfgs", "gn"), labelled "PG (analytic inverse)", "PG (time reversal)",
// "PG (L-BFGS inverse)", …, with the method in extra_params["inverse"].
std::vector<RuleSetup> with_pg_inverses(const std::vector<RuleSetup>& rules,
                                        const std::vector<std::string>& methods);

struct DirectResult {
  RuleSetup rule;
  MinimizeSummary summary;
  double initial_loss = 0;
};

// Throws Error "--start: the loss at (0, 1e-200) is 0: …" or "… is inf: …" (`where` appended,
// e.g. " with α = 10"): a start at a minimum leaves nothing to compare, and minimize() cannot
// start from a non-finite loss.
void require_start(const Objective& objective, const Vector& x0, const std::string& where = "");

// Throws Error naming --iters when `runs` direct runs of that many iterations cannot keep every
// iterate (its metrics row, point and share of the figures: about 2 KiB, measured) in memory.
void require_iterate_memory(const Settings& settings, std::size_t runs);

// Runs one rule from x0, records one metrics row per iterate (with `row_extras` columns) and
// a summary entry (with `extra_params` merged into params). `tolerance` is the loss level
// counted as converged. `columns`, when given, adds the columns it returns for an iterate (its
// record of the history: loss, time, simulator counts, …) to that iterate's metrics row, and
// those of the last iterate to the run's "final" entry in summary.json.
DirectResult run_direct(RunContext& context, const RuleSetup& rule, const Objective& objective,
                        const Vector& x0, int iterations, double tolerance,
                        const nlohmann::json& row_extras = nlohmann::json::object(),
                        const std::function<nlohmann::json(const IterationRecord&)>& columns =
                            nullptr);

// "12" when converged, "diverged at 7" on numerical failure, "diverging (L ×…)" when the run
// ended (budget, or a stopping rule: Termination::kDiverged) with the loss above its start,
// "> N" otherwise.
std::string iterations_cell(const DirectResult& result);
// The same outcome as a predicate for a sentence after the rule's name: "needs 12 iterations",
// "diverged at iteration 7", "failed at iteration 7", "stalled at iteration 7", "is diverging
// (L ×… after N)", "has not converged after N iterations".
std::string outcome_phrase(const DirectResult& result);
// The step size a rule actually runs with: "0.5", "line search from 1", "adaptive μ from 0.001".
std::string step_size_text(const RuleSetup& rule);

// Loss (log y) of several runs against the iteration, or against x_of(run, iterate) (a NaN
// ends that run's curve; the loss is drawn as steps, held until the next iterate, since the
// work between two iterates changes no iterate); a diverged run is marked at its end and does
// not set the axis range, PG through a numerical local inverse is dashed.
std::string loss_curves_svg(const std::vector<DirectResult>& results, const std::string& title,
                            const std::string& x_label = "iteration",
                            const std::function<double(std::size_t, std::size_t)>& x_of = {},
                            bool log_x = false);

// Samples f on an n×n grid over [x_min, x_max]×[y_min, y_max].
Grid2D sample_grid(const std::function<double(double, double)>& f, double x_min, double x_max,
                   double y_min, double y_max, int n);

// Each run's iterates as a trajectory (first two coordinates).
std::vector<Trajectory> trajectories(const std::vector<DirectResult>& results);

}  // namespace physgrad::run
