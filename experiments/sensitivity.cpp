// sensitivity: the 1-D example y = P(x) = αx with L = ½y². Gradient descent's step grows
// with α² (exploding for sensitive, vanishing for insensitive functions); Newton's and the
// inverse gradient's step does not depend on α at all.
#include <cmath>

#include "physgrad/run/cases/direct_runs.hpp"
#include "physgrad/run/cases/rule_colors.hpp"
#include "framework.hpp"
#include "registry.hpp"
#include "physgrad/error.hpp"
#include "physgrad/loss/loss.hpp"
#include "physgrad/physics/diagonal_scale.hpp"

namespace physgrad::experiments {
namespace {
namespace sensitivity_case {

using Kind = OptionSpec::Kind;

class Sensitivity final : public Experiment {
 public:
  std::string name() const override { return "sensitivity"; }
  std::string description() const override {
    return "y = alpha*x, L = 1/2 y^2: step size and loss change per step vs alpha";
  }
  std::vector<OptionSpec> options() const override {
    return {
        real_list_option("alpha", "0.01,0.1,1,10,100", "sensitivities α").above(0),
        real_option("start", "1", "starting point x₀").not_zero(),
        real_option("tol", "1e-6", "convergence: stop at L(x) ≤ tol·L(x₀)").above(0).at_most(1),
    };
  }
  std::vector<std::string> optimizer_choices() const override {
    return rule_ids(RuleKind::kDirect);
  }
  std::vector<std::string> default_optimizers() const override { return {"gd", "newton", "ig"}; }
  long long default_iterations() const override { return 100; }

  void validate(const Settings& settings) const override {
    const L2Loss loss;
    for (const double alpha : settings.reals("alpha")) {
      const DiagonalScale physics(Vector{{alpha}});
      require_start(Objective(physics, loss, Vector::Zero(1)), Vector{{settings.real("start")}},
                    " with α = " + format_value(alpha));
    }
    require_iterate_memory(settings,
                           settings.reals("alpha").size() * settings.texts("optimizers").size());
  }

  void run(const Settings& settings, RunContext& context) const override {
    const std::vector<double> alphas = settings.reals("alpha");
    const Vector x0{{settings.real("start")}};
    const auto iterations = static_cast<int>(settings.integer("iters"));
    const std::vector<RuleSetup> rules = selected_rules(settings, kDefaultLr);

    const L2Loss loss;
    std::vector<std::vector<DirectResult>> by_alpha;
    for (const double alpha : alphas) {
      const DiagonalScale physics(Vector{{alpha}});
      const Objective objective(physics, loss, Vector::Zero(1));
      std::vector<DirectResult> results;
      for (const RuleSetup& rule : rules) {
        context.progress("sensitivity: alpha = " + format_value(alpha) + ", " + rule.label);
        results.push_back(run_direct(context, rule, objective, x0, iterations,
                                     settings.real("tol") * objective.value(x0),
                                     {{"alpha", alpha}}));
      }
      by_alpha.push_back(std::move(results));
    }
    context.finish_progress();

    // First-step figures per rule and α.
    const auto first_step = [](const DirectResult& r) {
      return r.summary.history.size() > 1 ? r.summary.history[1].step_norm : NAN;
    };
    const auto loss_ratio = [](const DirectResult& r) {
      return r.summary.history.size() > 1 ? r.summary.history[1].loss / r.initial_loss : NAN;
    };
    add_table(context, "First step |Δx| (x₀ = " + format_value(x0(0)) + ")", alphas, by_alpha,
              [&](const DirectResult& r) { return format_value(first_step(r)); });
    add_table(context, "Loss after one step relative to the start, L(x₁)/L(x₀)", alphas, by_alpha,
              [&](const DirectResult& r) { return format_value(loss_ratio(r)); });
    add_table(context, "Iterations until L(x) ≤ tol·L(x₀)", alphas, by_alpha, iterations_cell);
    add_figure(context, "step_vs_alpha.svg", "First step |Δx| vs α", "|Δx₁|",
               " GD's step ηα²x grows with slope 2, the square of the sensitivity; "
               "Newton's and IG's are flat.",
               alphas, by_alpha,
               first_step);
    add_figure(context, "loss_ratio_vs_alpha.svg", "Loss ratio after the first step vs α",
               "L(x₁)/L(x₀)",
               " Once GD overshoots (ηα² > 2), L(x₁)/L(x₀) = (1 − ηα²)² grows with slope 4; "
               "Newton's and IG's ratio (1 − η)² is flat.",
               alphas, by_alpha, loss_ratio);
    // The message: how much each rule's first step changes from the smallest to the largest α.
    std::string sentence;
    for (std::size_t r = 0; r < by_alpha.front().size(); ++r) {
      const double from = first_step(by_alpha.front()[r]), to = first_step(by_alpha.back()[r]);
      const double growth = to / from;
      sentence += (sentence.empty() ? "" : "; ") + by_alpha.front()[r].rule.label + "'s " +
                  (std::abs(growth - 1) < 1e-6
                       ? "stays " + format_value(from)
                       : "goes from " + format_value(from) + " to " + format_value(to) + " (×" +
                             format_value(growth) + ")");
    }
    context.set_message("step_vs_alpha.svg", "From α = " + format_value(alphas.front()) +
                                                 " to " + format_value(alphas.back()) +
                                                 ", the first step |Δx₁|: " + sentence + ".",
                        {"iterations", "iterations to the tolerance, over every α"});
  }

 private:
  inline static const std::map<std::string, double> kDefaultLr = {
      {"gd", 0.1}, {"momentum", 0.1}, {"adam", 0.1}, {"newton", 0.5},
      {"gn", 0.5}, {"ig", 0.5},       {"pg", 0.5}};

  template <typename Cell>
  static void add_table(RunContext& context, const std::string& title,
                        const std::vector<double>& alphas,
                        const std::vector<std::vector<DirectResult>>& by_alpha, Cell cell) {
    RunContext::Table table{title, {"rule"}, {}};
    for (const double alpha : alphas) table.header.push_back("α = " + format_value(alpha));
    for (std::size_t r = 0; r < by_alpha.front().size(); ++r) {
      std::vector<std::string> row = {by_alpha.front()[r].rule.label};
      for (const auto& results : by_alpha) row.push_back(cell(results[r]));
      table.rows.push_back(std::move(row));
    }
    context.add_table(std::move(table));
  }

  template <typename Value>
  static void add_figure(RunContext& context, const std::string& file, const std::string& title,
                         const std::string& y_label, const std::string& slope_note,
                         const std::vector<double>& alphas,
                         const std::vector<std::vector<DirectResult>>& by_alpha, Value value) {
    std::vector<Series> series;
    for (std::size_t r = 0; r < by_alpha.front().size(); ++r) {
      const RuleSetup& rule = by_alpha.front()[r].rule;
      Series line{rule.label, {}, {}, color_for(rule.id), true, false};
      for (std::size_t a = 0; a < alphas.size(); ++a) {
        line.x.push_back(alphas[a]);
        line.y.push_back(value(by_alpha[a][r]));
      }
      series.push_back(std::move(line));
    }
    LinePlotOptions options;
    options.title = title;
    options.x_label = "α";
    options.y_label = y_label;
    options.log_x = true;
    options.log_y = true;
    context.add_figure({file, title + " (log-log)." + slope_note, line_plot_svg(series, options)});
  }
};

}  // namespace sensitivity_case
}  // namespace

std::unique_ptr<Experiment> make_sensitivity() {
  return std::make_unique<sensitivity_case::Sensitivity>();
}

} // namespace physgrad::experiments
