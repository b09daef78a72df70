// hig-toy: a 1 → 7 tanh → 2 network learns ŷ(x) = (sin 6x, cos 9x) on [−1, 1] through the
// "physics" P(y) = (y₁, λy₂) with L = ½‖P(y) − ŷ‖². For λ ≪ 1 the Jacobian is badly
// conditioned: Adam and Gauss-Newton stall, half-inverse gradients do not.
#include <algorithm>
#include <cmath>

#include "framework.hpp"
#include "registry.hpp"
#include "physgrad/run/cases/learning_experiment.hpp"
#include "physgrad/error.hpp"
#include "physgrad/loss/loss.hpp"
#include "physgrad/physics/diagonal_scale.hpp"
#include "physgrad/run/cases/rule_colors.hpp"
#include "physgrad/report/line_plot.hpp"
#include "physgrad/report/svg_document.hpp"
#include "physgrad/run/pages/learning_verdict.hpp"
#include "physgrad/run/cases/sampling.hpp"

namespace physgrad::experiments {
namespace {
namespace hig_toy_case {

constexpr double kTrackedInput = 0.354;  // the validation sample whose y-path is drawn
constexpr Index kHidden = 7;

// Step sizes chosen once on the well-conditioned case λ = 1 (5 seeds, 10 000 iterations) and
// kept for every λ: Adam 1e-2 (1e-3 stays near 0.25), Gauss-Newton 0.1 (the best median of
// 0.03, 0.1, 0.3, 1), HIG 1 as in the HIG paper. docs/results.md lists the sweep.
const std::map<std::string, RuleDefaults>& rule_defaults() {
  static const std::map<std::string, RuleDefaults> defaults = {
      {"sgd", {{{"lr", 0.1}}, 128}}, {"adam", {{{"lr", 0.01}}, 128}}, {"gn", {{{"lr", 0.1}}, 128}},
      {"hig", {{{"lr", 1.0}}, 128}}, {"sip", {{{"lr", 0.01}}, 128}}};
  return defaults;
}

Mlp make_network(std::uint64_t seed) {
  Mlp network({1, kHidden, 2}, Activation::kTanh);
  network.initialize(seed);
  return network;
}

Dataset make_data(Index n, std::uint64_t seed) {
  Sampler sampler(seed);
  Dataset data{Matrix(1, n), Matrix(2, n), Matrix()};
  for (Index i = 0; i < n; ++i) {
    const double x = sampler.uniform(-1.0, 1.0);
    data.inputs(0, i) = x;
    data.targets.col(i) << std::sin(6 * x), std::cos(9 * x);
  }
  return data;
}

// The case at scale λ: P(y) = (y₁, λy₂), L = ½‖P(y) − ŷ‖², the 1-7-2 tanh network, inputs
// uniform on [−1, 1]; the samples and rule defaults are the same for every λ.
LearningCase learning_case(double lambda) {
  return {std::make_shared<DiagonalScale>(Vector{{1.0, lambda}}), std::make_shared<L2Loss>(),
          make_network,
          [](std::uint64_t stream, Index count) { return make_data(count, stream); },
          rule_defaults()};
}

// A hidden neuron counts as saturated when |tanh| > 0.99 for every validation input: it then
// passes (almost) no gradient and produces the same value whatever the input.
struct ActivationStats {
  double mean = 0, std = 0, saturated_fraction = 0;
};

ActivationStats activation_stats(const Mlp& network, const Matrix& inputs) {
  MlpCache cache;
  network.forward(inputs, cache);
  const Matrix& a = cache.activations[1];  // hidden layer, 7 × N
  ActivationStats stats;
  stats.mean = a.mean();
  stats.std = std::sqrt((a.array() - stats.mean).square().mean());
  Index saturated = 0;
  for (Index j = 0; j < a.rows(); ++j) saturated += a.row(j).cwiseAbs().minCoeff() > 0.99 ? 1 : 0;
  stats.saturated_fraction = static_cast<double>(saturated) / static_cast<double>(a.rows());
  return stats;
}

class HigToy final : public LearningExperiment {
 public:
  HigToy() : LearningExperiment({.eval_every = "200", .data = "fixed", .seeds = "5"}) {}
  std::string name() const override { return "hig-toy"; }
  std::string description() const override {
    return "1-7-2 tanh net learns (sin 6x, cos 9x) through P(y) = (y1, lambda*y2): "
           "Adam vs Gauss-Newton vs HIG";
  }
  std::vector<OptionSpec> own_options() const override {
    // A sample: its input and target, and the network's activations on it.
    const auto bytes_each = [](const Settings&) { return sample_bytes({1, kHidden, 2}, 3); };
    return {
        real_list_option("lambda", "1,0.01", "scale λ of the second output").above(0),
        sample_count_option("train-size", "512", "training samples", "16", bytes_each),
        sample_count_option("test-size", "256",
                            "test samples (also the activation statistics)", "8", bytes_each),
    };
  }
  std::vector<std::string> default_optimizers() const override { return {"adam", "gn", "hig"}; }
  long long default_iterations() const override { return 10000; }

  Shape shape(const Settings& /*settings*/) const override { return {2, {1, kHidden, 2}}; }

  // The badly conditioned case λ = 0.01.
  std::optional<ReferenceCase> reference(Index batch, std::uint64_t seed) const override {
    return learning_case(0.01).reference(batch, seed);
  }

  void run(const Settings& settings, RunContext& context) const override {
    LearningSweep sweep(settings, context, learning_case(settings.reals("lambda").front()));
    for (const double lambda : settings.reals("lambda")) {
      const LearningCase learning = learning_case(lambda);
      const Simulator& physics = *learning.physics;
      const std::string tag = "λ=" + format_value(lambda);
      for (long long s = 0; s < settings.integer("seeds"); ++s) {
        const auto seed = static_cast<std::uint64_t>(settings.integer("seed") + s);
        const Dataset train_set = learning.training_set(settings.integer("train-size"), seed);
        const Dataset test_set = learning.test_set(settings.integer("test-size"), seed);

        const auto observe = [&](const Network& network, TrainingRecord& record) {
          // The sweep trains the Mlp made below, so the network observed is that one.
          const ActivationStats stats =
              activation_stats(dynamic_cast<const Mlp&>(network), test_set.inputs);
          record.extras["act_mean"] = stats.mean;
          record.extras["act_std"] = stats.std;
          record.extras["saturated_fraction"] = stats.saturated_fraction;
          const Vector y =
              physics.forward(network.forward(Matrix::Constant(1, 1, kTrackedInput)).col(0));
          record.extras["y1"] = y(0);
          record.extras["y2"] = y(1);
        };
        for (const std::string& id : sweep.run_ids(settings.texts("optimizers"))) {
          Mlp network = learning.network(seed);
          sweep.run(id, tag, {{"lambda", lambda}, {"seed", seed}}, network, learning.problem(),
                    train_set, &test_set, observe);
        }
      }
    }
    add_message_figure(context, sweep, settings.reals("lambda"));
    for (const double lambda : settings.reals("lambda")) {
      add_figures(context, sweep, lambda, "λ=" + format_value(lambda));
    }
    sweep.add_tables();
  }

 private:
  // Test loss vs iteration for every λ side by side on one y axis, and the ratio of the best
  // rule's median final test loss to the next rule's at each λ, the last (the hardest) first.
  static void add_message_figure(RunContext& context, const LearningSweep& sweep,
                                 const std::vector<double>& lambdas) {
    const auto test_loss = [](const TrainingRecord& r) { return r.test_loss; };
    double lo = INFINITY, hi = 0;
    for (const double lambda : lambdas) {
      for (const auto& group : sweep.rule_groups("λ=" + format_value(lambda))) {
        for (const LearningResult* run : group) {
          for (const TrainingRecord& r : run->summary.history) {
            if (std::isfinite(r.test_loss) && r.test_loss > 0) {
              lo = std::min(lo, r.test_loss);
              hi = std::max(hi, r.test_loss);
            }
          }
        }
      }
    }
    const auto range = lo <= hi ? std::optional(std::pair(lo, hi)) : std::nullopt;
    std::vector<std::vector<std::string>> rows;  // one per λ: per update, per second
    std::string sentence;
    for (auto lambda = lambdas.rbegin(); lambda != lambdas.rend(); ++lambda) {
      const std::string tag = "λ=" + format_value(*lambda);
      const std::string ratio =
          verdict_sentence({sweep.rule_groups(tag), test_loss, "median final test loss"});
      sentence += sentence.empty() ? "At λ = " + format_value(*lambda) + ", " + ratio
                                   : " At λ = " + format_value(*lambda) + ": " + ratio;
    }
    for (auto lambda = lambdas.rbegin(); lambda != lambdas.rend(); ++lambda) {
      const std::string tag = "λ=" + format_value(*lambda);
      rows.emplace_back();
      for (const auto progress :
           {LearningSweep::Progress::kIteration, LearningSweep::Progress::kTime}) {
        const bool by_time = progress == LearningSweep::Progress::kTime;
        rows.back().push_back(LearningSweep::metric_figure(
                             sweep.rule_groups(tag), "",
                             "Test loss (" + tag + ") per " + (by_time ? "second" : "update"),
                             "mean test loss", test_loss, progress, true, range)
                             .svg);
      }
    }
    const std::string file = "loss_by_lambda.svg";
    context.add_figure({file,
                        "Test loss per update (left) and per second of training (right), one "
                        "row per λ (the hardest first), one y axis. Line: median over the seeds; "
                        "band: their minimum to maximum. Dots: evaluations.",
                        svg::grid(rows)});
    // The index compares run folders at the hardest λ (the smallest: the most ill-conditioned).
    const double hardest = *std::min_element(lambdas.begin(), lambdas.end());
    context.set_message(file, sentence,
                        {"test_loss", "median final test loss at λ = " + format_value(hardest),
                         sweep.labels("λ=" + format_value(hardest))});
  }

  static void add_figures(RunContext& context, const LearningSweep& sweep, double lambda,
                          const std::string& tag) {
    const std::vector<const LearningResult*> runs = sweep.first_seed_runs(tag);
    const std::string file_tag = format_value(lambda);
    sweep.add_loss_figures(context, tag, "lambda_" + file_tag);
    LearningSweep::add_metric_figure(
        context, sweep.rule_groups(tag), "saturation_lambda_" + file_tag + ".svg",
        "Saturated hidden neurons vs iteration (" + tag + ")",
        "fraction with |tanh| > 0.99 on every test input",
        [](const TrainingRecord& r) { return r.extras["saturated_fraction"].get<double>(); },
        LearningSweep::Progress::kIteration, false);

    std::vector<Series> bands;
    for (const LearningResult* run : runs) {
      Series s{run->label, {}, {}, color_for(run->id), false, false, {}, {}};
      for (const TrainingRecord& r : run->summary.history) {
        const double mean = r.extras["act_mean"], std = r.extras["act_std"];
        s.x.push_back(static_cast<double>(r.iteration));
        s.y.push_back(mean);
        s.band_low.push_back(mean - std);
        s.band_high.push_back(mean + std);
      }
      bands.push_back(std::move(s));
    }
    LinePlotOptions band_options;
    band_options.title = "Hidden activations, mean ± std over test inputs (" + tag + ")";
    band_options.x_label = "iteration";
    band_options.y_label = "tanh activation";
    context.add_figure({"activations_lambda_" + file_tag + ".svg",
                        "Neuron saturation: a band collapsing onto ±1 means saturated neurons (" +
                            tag + ", first seed).",
                        line_plot_svg(bands, band_options), tag});

    std::vector<Series> paths;
    // P(f(x)) is compared with ŷ(x) directly, so the target dot is ŷ of the tracked input.
    const Vector target_y{{std::sin(6 * kTrackedInput), std::cos(9 * kTrackedInput)}};
    for (const LearningResult* run : runs) {
      Series s{run->label, {}, {}, color_for(run->id), true, false, {}, {}};
      for (const TrainingRecord& r : run->summary.history) {
        s.x.push_back(r.extras["y1"]);
        s.y.push_back(r.extras["y2"]);
      }
      paths.push_back(std::move(s));
    }
    paths.push_back({"start", {paths.front().x.front()}, {paths.front().y.front()}, "#9e9e9e",
                     true, false, {}, {}});
    paths.push_back({"target", {target_y(0)}, {target_y(1)}, "#000000", true, false, {}, {}});
    LinePlotOptions path_options;
    path_options.title = "Output of x = 0.354 during training (" + tag + ")";
    path_options.x_label = "P(f(x))₁ = y₁";
    path_options.y_label = "P(f(x))₂ = λ·y₂";
    context.add_figure({"trajectory_lambda_" + file_tag + ".svg",
                        "Path of one validation sample in physics output space (" + tag +
                            ", first seed).",
                        line_plot_svg(paths, path_options), tag});
  }
};

}  // namespace hig_toy_case
}  // namespace

std::unique_ptr<Experiment> make_hig_toy() {
  return std::make_unique<hig_toy_case::HigToy>();
}

} // namespace physgrad::experiments
