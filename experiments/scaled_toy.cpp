// scaled-toy: P(x) = (x₁, αx₂), L = ½‖P(x)‖². For every α of the sweep, every selected rule
// runs from the same start with one fixed step size; the iterations it needs to reduce the
// loss by the tolerance show which rules are scale-invariant (independent of α).
#include <cmath>

#include "physgrad/run/cases/direct_runs.hpp"
#include "physgrad/run/pages/learning_verdict.hpp"  // ratio_text
#include "physgrad/run/cases/rule_colors.hpp"
#include "framework.hpp"
#include "registry.hpp"
#include "physgrad/error.hpp"
#include "physgrad/loss/loss.hpp"
#include "physgrad/physics/diagonal_scale.hpp"

namespace physgrad::experiments {
namespace {
namespace scaled_toy_case {

using Kind = OptionSpec::Kind;

class ScaledToy final : public Experiment {
 public:
  std::string name() const override { return "scaled-toy"; }
  std::string description() const override {
    return "P(x) = (x1, alpha*x2), L = 1/2 |P(x)|^2: iterations to converge per rule and alpha";
  }
  std::vector<OptionSpec> options() const override {
    return {
        real_list_option("alpha", "1,10,100,1000", "scales α of the second component").above(0),
        real_list_option("start", "0.48,0.84", "starting point x₀ (two values)").coordinates(),
        real_option("tol", "1e-6", "convergence level of the loss (see --tol-mode)")
            .above(0)
            .at_most(1),
        text_option("tol-mode", "relative",
                    "relative: stop at L(x) ≤ tol·L(x₀); absolute: at L(x) ≤ tol")
            .one_of({"relative", "absolute"}),
    };
  }
  std::vector<std::string> optimizer_choices() const override {
    return rule_ids(RuleKind::kDirect);
  }
  std::vector<std::string> default_optimizers() const override {
    return rule_ids(RuleKind::kDirect);
  }
  long long default_iterations() const override { return 1000; }

  void validate(const Settings& settings) const override {
    const std::size_t n = settings.reals("start").size();
    if (n != 2) throw Error("--start: needs exactly 2 values, got " + std::to_string(n));
    const std::vector<double> start = settings.reals("start");
    const L2Loss loss;
    for (const double alpha : settings.reals("alpha")) {
      const DiagonalScale physics(Vector{{1.0, alpha}});
      require_start(Objective(physics, loss, Vector::Zero(2)), Vector{{start[0], start[1]}},
                    " with α = " + format_value(alpha));
    }
    require_iterate_memory(settings,
                           settings.reals("alpha").size() * settings.texts("optimizers").size());
  }

  void run(const Settings& settings, RunContext& context) const override {
    const std::vector<double> alphas = settings.reals("alpha");
    const std::vector<double> start = settings.reals("start");
    const Vector x0{{start[0], start[1]}};
    const double tol = settings.real("tol");
    const bool relative = settings.text("tol-mode") == "relative";
    const auto iterations = static_cast<int>(settings.integer("iters"));
    const std::vector<RuleSetup> rules = selected_rules(settings, kDefaultLr);

    const L2Loss loss;
    std::vector<std::vector<DirectResult>> by_alpha;
    for (const double alpha : alphas) {
      const DiagonalScale physics(Vector{{1.0, alpha}});
      const Objective objective(physics, loss, Vector::Zero(2));
      const double level = relative ? tol * objective.value(x0) : tol;
      std::vector<DirectResult> results;
      for (const RuleSetup& rule : rules) {
        context.progress("scaled-toy: alpha = " + format_value(alpha) + ", " + rule.label);
        results.push_back(run_direct(context, rule, objective, x0, iterations, level,
                                     {{"alpha", alpha}}));
      }
      by_alpha.push_back(std::move(results));
    }
    context.finish_progress();

    add_iteration_table(context, alphas, by_alpha, tol, relative);
    add_iteration_figure(context, alphas, by_alpha);
    context.set_message("iterations_vs_alpha.svg", invariance_sentence(alphas, by_alpha),
                        {"iterations", "iterations to the tolerance, over every α"});
    for (std::size_t a = 0; a < alphas.size(); ++a) {
      add_alpha_figures(context, alphas[a], x0, by_alpha[a]);
    }
  }

 private:
  // The rules that need the same iterations at every α, and how far the first other rule's
  // count moves (ratio to the first invariant rule at the first α).
  static std::string invariance_sentence(const std::vector<double>& alphas,
                                         const std::vector<std::vector<DirectResult>>& by_alpha) {
    const auto converged = [](const DirectResult& r) {
      return r.summary.termination == Termination::kConverged;
    };
    std::vector<std::size_t> invariant, varying;
    for (std::size_t r = 0; r < by_alpha.front().size(); ++r) {
      bool same = true;
      for (const auto& results : by_alpha) {
        same = same && converged(results[r]) &&
               results[r].summary.iterations == by_alpha.front()[r].summary.iterations;
      }
      (same ? invariant : varying).push_back(r);
    }
    const auto& first = by_alpha.front();
    std::string out;
    for (const std::size_t r : invariant) {
      out += (out.empty() ? "" : ", ") + first[r].rule.label + " (" +
             std::to_string(first[r].summary.iterations) + ")";
    }
    out = invariant.empty() ? "No rule needs the same iterations at every α"
                            : out + (invariant.size() == 1 ? " needs" : " need") +
                                  " the same iterations at every α from " +
                                  format_value(alphas.front()) + " to " +
                                  format_value(alphas.back());
    if (varying.empty()) return out + ".";
    const DirectResult& moved = first[varying.front()];
    out += "; " + moved.rule.label + " " + outcome_phrase(moved) + " at α = " +
           format_value(alphas.front());
    if (!invariant.empty() && converged(moved) && first[invariant.front()].summary.iterations > 0) {
      out += " (" +
             ratio_text(static_cast<double>(moved.summary.iterations) /
                        static_cast<double>(first[invariant.front()].summary.iterations)) +
             " " + first[invariant.front()].rule.label + "'s)";
    }
    return out + " and " + outcome_phrase(by_alpha.back()[varying.front()]) + " at α = " +
           format_value(alphas.back()) + ".";
  }

  inline static const std::map<std::string, double> kDefaultLr = {
      {"gd", 0.01},     {"momentum", 0.01}, {"adam", 0.01}, {"newton", 0.5},
      {"gn", 0.5},      {"ig", 0.5},        {"pg", 0.5}};

  static void add_iteration_table(RunContext& context, const std::vector<double>& alphas,
                                  const std::vector<std::vector<DirectResult>>& by_alpha,
                                  double tol, bool relative) {
    RunContext::Table table;
    table.title = std::string("Iterations until L(x) ≤ ") + format_value(tol) +
                  (relative ? "·L(x₀)" : "") + " (same start and step size for every α)";
    table.header = {"rule", "step size"};
    for (const double alpha : alphas) table.header.push_back("α = " + format_value(alpha));
    for (std::size_t r = 0; r < by_alpha.front().size(); ++r) {
      const RuleSetup& rule = by_alpha.front()[r].rule;
      std::vector<std::string> row = {rule.label, step_size_text(rule)};
      for (const auto& results : by_alpha) row.push_back(iterations_cell(results[r]));
      table.rows.push_back(std::move(row));
    }
    context.add_table(std::move(table));
  }

  static void add_iteration_figure(RunContext& context, const std::vector<double>& alphas,
                                   const std::vector<std::vector<DirectResult>>& by_alpha) {
    std::vector<Series> series;
    for (std::size_t r = 0; r < by_alpha.front().size(); ++r) {
      const RuleSetup& rule = by_alpha.front()[r].rule;
      Series line{rule.label, {}, {}, color_for(rule.id), true, false};
      for (std::size_t a = 0; a < alphas.size(); ++a) {
        const MinimizeSummary& s = by_alpha[a][r].summary;
        line.x.push_back(alphas[a]);
        const bool converged = s.termination == Termination::kConverged;
        line.y.push_back(converged ? static_cast<double>(s.iterations) : NAN);
        if (!converged && line.end_label.empty()) {
          line.end_label = "α = " + format_value(alphas[a]) + ": " + iterations_cell(by_alpha[a][r]);
        }
      }
      series.push_back(std::move(line));
    }
    LinePlotOptions options;
    options.title = "Iterations to converge vs α";
    options.x_label = "α";
    options.y_label = "iterations";
    options.log_x = true;
    options.log_y = true;
    context.add_figure({"iterations_vs_alpha.svg",
                        "Iterations to converge per α. Flat lines are scale-invariant rules; a line "
                        "that ends in × did not converge at the next α (labelled).",
                        line_plot_svg(series, options)});
  }

  static void add_alpha_figures(RunContext& context, double alpha, const Vector& x0,
                                const std::vector<DirectResult>& results) {
    const std::string tag = format_value(alpha);
    const double margin = 0.15 * x0.cwiseAbs().maxCoeff();
    const double x_lo = std::min(0.0, x0(0)) - margin, x_hi = std::max(0.0, x0(0)) + margin;
    const double y_lo = std::min(0.0, x0(1)) - margin, y_hi = std::max(0.0, x0(1)) + margin;
    const Grid2D grid = sample_grid(
        [alpha](double a, double b) { return 0.5 * (a * a + alpha * alpha * b * b); }, x_lo, x_hi,
        y_lo, y_hi, 81);
    LandscapeOptions options;
    options.title = "Loss landscape and trajectories, α = " + tag;
    options.x_label = "x₁";
    options.y_label = "x₂";
    options.markers = {{0.0, 0.0, "minimum"}};
    options.value_label = "L = ½(x₁² + α²x₂²)";
    context.add_figure({"landscape_alpha_" + tag + ".svg",
                        "x-space trajectories for α = " + tag +
                            " over the isolines of L (log-spaced levels).",
                        landscape_svg(grid, trajectories(results), options), tag});
    context.add_figure({"loss_alpha_" + tag + ".svg", "Loss per iteration for α = " + tag + ".",
                        loss_curves_svg(results, "Loss vs iteration, α = " + tag), tag});
  }
};

}  // namespace scaled_toy_case
}  // namespace

std::unique_ptr<Experiment> make_scaled_toy() {
  return std::make_unique<scaled_toy_case::ScaledToy>();
}

} // namespace physgrad::experiments
