// comparison: y = P(x) = (x₀, x₁²), L = ‖y‖² = x₀² + x₁⁴ from (3, 3), as in the book's simple
// optimizer comparison: GD, Adam, Newton, IG and PG (analytic and numerical local inverse).
#include <algorithm>
#include <cmath>
#include <functional>

#include "physgrad/run/cases/direct_runs.hpp"
#include "physgrad/run/pages/learning_verdict.hpp"  // ratio_text, value_text
#include "framework.hpp"
#include "registry.hpp"
#include "physgrad/error.hpp"
#include "physgrad/loss/loss.hpp"
#include "physgrad/physics/comparison_toy.hpp"

namespace physgrad::experiments {
namespace {
namespace comparison_case {

// "(x₀, x₁)" with 4 significant digits.
std::string point(const Vector& x) {
  std::string text = "(";
  text += format_value(x(0));
  text += ", ";
  text += format_value(x(1));
  text += ")";
  return text;
}

using Kind = OptionSpec::Kind;

class Comparison final : public Experiment {
 public:
  std::string name() const override { return "comparison"; }
  std::string description() const override {
    return "y = (x0, x1^2), L = |y|^2 from (3,3): GD, Adam, Newton, IG, PG side by side";
  }
  std::vector<OptionSpec> options() const override {
    return {
        real_list_option("start", "3,3", "starting point x₀ (two values)").coordinates(),
        text_list_option("pg-inverse", "analytic,lbfgs", "local inverses PG runs with, one run each")
            .one_of({"analytic", "lbfgs", "ig"}),
    };
  }
  std::vector<std::string> optimizer_choices() const override {
    return rule_ids(RuleKind::kDirect);
  }
  std::vector<std::string> default_optimizers() const override {
    return {"gd", "adam", "newton", "ig", "pg"};
  }
  long long default_iterations() const override { return 10; }

  void validate(const Settings& settings) const override {
    const std::size_t n = settings.reals("start").size();
    if (n != 2) throw Error("--start: needs exactly 2 values, got " + std::to_string(n));
    const std::vector<double> start = settings.reals("start");
    const ComparisonToy physics;
    require_start(Objective(physics, L2Loss(2.0), Vector::Zero(2)), Vector{{start[0], start[1]}});
    const std::vector<std::string> ids = settings.texts("optimizers");
    const bool pg = std::find(ids.begin(), ids.end(), "pg") != ids.end();
    require_iterate_memory(settings,
                           ids.size() + (pg ? settings.texts("pg-inverse").size() - 1 : 0));
  }

  void run(const Settings& settings, RunContext& context) const override {
    const std::vector<double> start = settings.reals("start");
    const Vector x0{{start[0], start[1]}};
    const auto iterations = static_cast<int>(settings.integer("iters"));

    const std::vector<RuleSetup> rules =
        with_pg_inverses(selected_rules(settings, kDefaultLr), settings.texts("pg-inverse"));

    const ComparisonToy physics;
    const L2Loss squares(2.0);  // L = y₀² + y₁², the notebook's loss
    const Objective objective(physics, squares, Vector::Zero(2));
    std::vector<DirectResult> results;
    for (const RuleSetup& rule : rules) {
      context.progress("comparison: " + rule.label);
      results.push_back(run_direct(context, rule, objective, x0, iterations, 0.0,
                                   nlohmann::json::object(), [](const IterationRecord& record) {
                                     return nlohmann::json{{"x_distance", record.x.norm()}};
                                   }));
    }
    context.finish_progress();

    RunContext::Table table{"After " + std::to_string(iterations) + " steps from (" +
                                format_value(x0(0)) + ", " + format_value(x0(1)) + ")",
                            {"rule", "step size", "final x", "distance to 0", "loss",
                             "diagonal score of step 1"},
                            {}};
    for (const DirectResult& r : results) {
      const auto& h = r.summary.history;
      std::string diagonal = "–";
      if (h.size() > 1) {
        const Vector u = h[0].x - h[1].x;
        diagonal = format_value(u.normalized().sum());
      }
      table.rows.push_back({r.rule.label,
                            step_size_text(r.rule),
                            point(r.summary.x),
                            format_value(r.summary.x.norm()), format_value(r.summary.loss),
                            diagonal});
    }
    context.add_table(std::move(table));
    context.add_note(
        "The last column is the first update's alignment with the diagonal, dot(u/|u|, (1,1)) "
        "with u = x₀ − x₁; √2 ≈ 1.414 means the update points straight at the minimum.");

    add_figures(context, x0, physics, results);
    context.set_message("trajectories_x.svg", closest_sentence(results, iterations),
                        {"x_distance", "final distance ‖x‖ to the minimum"});
  }

 private:
  // Which rules end closest to the minimum x = 0 (all of those within a relative 1e-4 of the
  // smallest distance), and how many times closer than each rule that ends more than 5 % farther (ratios with two significant digits, distances with three).
  static std::string closest_sentence(const std::vector<DirectResult>& results, int iterations) {
    const auto distance = [](const DirectResult& r) { return r.summary.x.norm(); };
    if (results.empty()) return "No rule ran.";
    // The first rule within round-off of the smallest distance (PG's inverses tie to 1e-6).
    double smallest = INFINITY;
    for (const DirectResult& r : results) smallest = std::min(smallest, distance(r));
    const auto best = std::find_if(results.begin(), results.end(), [&](const DirectResult& r) {
      return distance(r) <= smallest * (1 + 1e-4);
    });
    // Every rule level with it is named with it: none of them is the sole best.
    std::string level;
    for (const DirectResult& r : results) {
      if (&r != &*best && distance(r) <= smallest * (1 + 1e-4)) level += " and " + r.rule.label;
    }
    std::string out = "After " + std::to_string(iterations) + " steps " + best->rule.label +
                      level + (level.empty() ? " ends " : " end ") + value_text(distance(*best)) +
                      " from the minimum" +
                      (level.empty() ? "" : " (level within a relative 1e-4)");
    std::string closer;
    for (const DirectResult& r : results) {
      const double ratio = distance(r) / distance(*best);
      if (!(ratio > 1.05)) continue;  // itself, and rules level with it
      closer += (closer.empty() ? ": " : ", ") + ratio_text(ratio) + " closer than " +
                r.rule.label + " (" + value_text(distance(r)) + ")";
    }
    return out + closer + ".";
  }

  inline static const std::map<std::string, double> kDefaultLr = {
      {"gd", 0.01}, {"momentum", 0.01}, {"adam", 0.3}, {"newton", 1.0 / 3.0},
      {"gn", 0.3},  {"ig", 0.3},        {"pg", 0.3}};

  // Trajectories over the isolines of f on [−0.2, 1.15]·reach² with the minimum at 0 marked.
  static void add_landscape(RunContext& context, const std::string& file,
                            const std::string& caption, const std::string& title,
                            const std::string& axis, const std::function<double(double, double)>& f,
                            double reach, const std::vector<Trajectory>& paths) {
    LandscapeOptions options;
    options.title = title;
    options.x_label = axis + "₀";
    options.y_label = axis + "₁";
    options.markers = {{0.0, 0.0, "minimum"}};
    options.value_label = "loss L";
    const Grid2D grid = sample_grid(f, -0.2 * reach, 1.15 * reach, -0.2 * reach, 1.15 * reach, 81);
    context.add_figure({file, caption, landscape_svg(grid, paths, options)});
  }

  static void add_figures(RunContext& context, const Vector& x0, const ComparisonToy& physics,
                          const std::vector<DirectResult>& results) {
    add_landscape(context, "trajectories_x.svg", "Trajectories in x space over the isolines of L.",
                  "x space: L = x₀² + x₁⁴", "x",
                  [](double a, double b) { return a * a + b * b * b * b; },
                  x0.cwiseAbs().maxCoeff(), trajectories(results));

    // The same runs seen in y = P(x): PG moves along the straight line to the minimum.
    std::vector<Trajectory> in_y = trajectories(results);
    for (std::size_t r = 0; r < results.size(); ++r) {
      for (std::size_t k = 0; k < in_y[r].x.size(); ++k) {
        const Vector y = physics.forward(results[r].summary.history[k].x);
        in_y[r].x[k] = y(0);
        in_y[r].y[k] = y(1);
      }
    }
    add_landscape(context, "trajectories_y.svg", "The same trajectories mapped to y = P(x).",
                  "y space: L = y₀² + y₁²", "y", [](double a, double b) { return a * a + b * b; },
                  physics.forward(x0).cwiseAbs().maxCoeff(), in_y);
    context.add_figure({"loss.svg", "Loss per iteration.",
                        loss_curves_svg(results, "Loss vs iteration")});
  }
};

}  // namespace comparison_case
}  // namespace

std::unique_ptr<Experiment> make_comparison() {
  return std::make_unique<comparison_case::Comparison>();
}

} // namespace physgrad::experiments
