// heat-inverse: a U-net (or, as an option, a fully connected network) reconstructs the initial
// state x* of periodic heat diffusion from the diffused field y* = P(x*), trained on
// L = ½‖P(f(y*)) − y*‖² as the book's heat notebook does (docs/reference_experiments.md): 64×64
// cells, fresh batches of 128, Adam 10⁻³ for SIP (towards the regularised inverse diffusion)
// and for Adam backpropagating through the diffusion.
#include <algorithm>
#include <cmath>
#include <optional>

#include "heat_inverse_figures.hpp"
#include "framework.hpp"
#include "registry.hpp"
#include "unet_case.hpp"
#include "physgrad/run/cases/learning_experiment.hpp"
#include "physgrad/error.hpp"
#include "physgrad/loss/loss.hpp"
#include "physgrad/memory.hpp"
#include "physgrad/nn/mean_matched_network.hpp"
#include "physgrad/physics/heat_diffusion.hpp"
#include "physgrad/run/cases/sampling.hpp"

namespace physgrad::experiments {
namespace {
namespace heat_inverse_case {

constexpr int kMaxBoxes = 10;
constexpr double kWeightCopies = 6;  // θ, ∇θ, the rule's state, checkpoints: vectors of |θ|
constexpr Index kShownSamples = 3;  // test samples in the reconstruction figures

// Network inputs and targets y*, and the true initial states x* (one sample per column).
struct HeatData {
  Dataset set;
  Matrix truth;
};

bool uses_unet(const Settings& settings) { return settings.text("network") == "unet"; }

// Cells per axis: --n, or its default (64; 16 for the fully connected network in 2-D).
Index axis_cells(const Settings& settings) {
  if (settings.has("n")) return settings.integer("n");
  return uses_unet(settings) || settings.integer("dims") == 1 ? 64 : 16;
}

// Cells per sample: n^dims.
Index cells(const Settings& settings) {
  const Index n = axis_cells(settings);
  return settings.integer("dims") == 1 ? n : n * n;
}

// The fully connected network's widths for `size` cells.
std::vector<Index> widths(Index size) { return {size, 2 * size, 2 * size, size}; }

// The network a run with `seed` starts from, the same for every rule: the U-net with the
// reference's mean correction (its output takes the mean of y*, which diffusion keeps); or the
// tanh network with Glorot weights — after 10 s its test x loss was ~1.3 (SIP) and ~1.8 (Adam),
// against ~8 and ~21 with ReLU and He weights, whose larger start leaves more error in the modes
// diffusion erases and L cannot see.
std::shared_ptr<Network> make_heat_network(const Settings& settings, std::uint64_t seed) {
  const int dims = static_cast<int>(settings.integer("dims"));
  if (uses_unet(settings)) {
    auto unet = std::make_unique<ConvNetwork>(
        ConvNetwork::unet(unet_of(settings, dims, axis_cells(settings))));
    unet->initialize(seed);
    return std::make_shared<MeanMatchedNetwork>(std::move(unet));
  }
  auto mlp = std::make_shared<Mlp>(widths(cells(settings)), Activation::kTanh);
  mlp->initialize(seed);
  return mlp;
}

// Fraction of the cell [i, i + 1) covered by [lo, hi): boxes get a linear edge one cell wide.
std::vector<double> coverage(Index n, double lo, double hi) {
  std::vector<double> c(static_cast<std::size_t>(n));
  for (Index i = 0; i < n; ++i) {
    const double a = static_cast<double>(i);
    c[static_cast<std::size_t>(i)] = std::max(0.0, std::min(a + 1, hi) - std::max(a, lo));
  }
  return c;
}

// The published hot boxes (docs/reference_experiments.md), scaled from 64 cells to n: 4–10
// boxes with strength U(0, 1), centre (u − ½)·0.8n + n/2 per axis, half size U(0, h)·n/64 per
// axis (h = 10 in 2-D as published, 5 in 1-D so that widths stay below ~10 cells), centre
// clipped to keep the box inside the domain.
HeatData make_data(const HeatDiffusion& physics, Index count, std::uint64_t seed) {
  const Index n = physics.config().n;
  const int dims = physics.config().dims;
  const double max_half = (dims == 1 ? 5.0 : 10.0) * static_cast<double>(n) / 64.0;
  Sampler sampler(seed);
  Matrix truth = Matrix::Zero(physics.input_dim(), count);
  for (Index s = 0; s < count; ++s) {
    const int boxes = 4 + static_cast<int>(7 * sampler.uniform());
    for (int b = 0; b < kMaxBoxes; ++b) {
      std::vector<double> cover[2] = {std::vector<double>(1, 1.0), std::vector<double>(1, 1.0)};
      for (int axis = 0; axis < dims; ++axis) {
        double centre =
            (sampler.uniform() - 0.5) * 0.8 * static_cast<double>(n) + 0.5 * static_cast<double>(n);
        const double half = sampler.uniform() * max_half;
        centre = std::clamp(centre, half, static_cast<double>(n) - half);
        cover[axis] = coverage(n, centre - half, centre + half);
      }
      const double strength = sampler.uniform() * (b < boxes ? 1.0 : 0.0);
      for (std::size_t j = 0; j < cover[1].size(); ++j) {
        for (std::size_t i = 0; i < cover[0].size(); ++i) {
          truth(static_cast<Index>(i + cover[0].size() * j), s) +=
              strength * cover[0][i] * cover[1][j];
        }
      }
    }
  }
  const Matrix y = physics.forward_batch(truth, Matrix());
  return {{y, y, Matrix()}, truth};
}

class HeatInverse final : public LearningExperiment {
 public:
  HeatInverse()
      : LearningExperiment({.eval_every_help = "evaluate every N iterations (default: 1 with the "
                                               "U-net; 250 in 1-D, 40 in 2-D otherwise)",
                            .data = "fresh",
                            .seeds = "1",
                            .seeds_why = "default 1: one run of the 64×64 U-net took about half "
                                         "an hour on this 2-core machine under load"}) {}
  std::string name() const override { return "heat-inverse"; }
  std::string description() const override {
    return "U-net reconstructs hot boxes x* from their periodic heat diffusion y* = P(x*) on "
           "64x64 cells, fresh batches of 128: SIP (regularised inverse diffusion) vs Adam "
           "through the diffusion";
  }
  // The notebook's 50 steps.
  long long default_iterations() const override { return 50; }
  std::vector<OptionSpec> own_options() const override {
    // A sample: its true field, input and target, and the network's activations on it.
    const auto bytes_each = [](const Settings& settings) {
      const Index size = cells(settings);
      if (!uses_unet(settings)) return sample_bytes(widths(size), 3 * size);
      const int dims = static_cast<int>(settings.integer("dims"));
      return unet_sample_bytes(unet_of(settings, dims, axis_cells(settings)), 3 * size);
    };
    std::vector<OptionSpec> options = {
        text_option("network", "unet",
                    "unet (phiml's u_net, as the notebook) or mlp (a fully connected tanh "
                    "network of widths cells-2·cells-2·cells)")
            .one_of({"unet", "mlp"}),
        integer_option("dims", "2", "1: a line of n cells; 2: an n×n grid").at_least(1).at_most(2),
        integer_option("n", "", "cells per axis (default: 64; 16 for --network mlp in 2-D)")
            .at_least(8)
            .quick("8"),
        real_option("amount", "",
                    "diffusion ν·t in cell units (default: 8·(n/64)², the published 8 "
                    "at 64 cells, the same blur relative to the domain)")
            .above(0),
    };
    for (OptionSpec& spec : unet_option_specs("zero")) options.push_back(std::move(spec));
    options.push_back(sample_count_option("train-size", "128",
                                          "training samples (with --data fresh: an epoch's "
                                          "length and the set the training loss is evaluated on)",
                                          "4", bytes_each));
    options.push_back(sample_count_option("test-size", "128", "test samples (also the x losses)",
                                          "4", bytes_each));
    return options;
  }
  std::vector<std::string> default_optimizers() const override { return {"sip", "adam"}; }

  Shape shape(const Settings& settings) const override {
    const Index size = cells(settings);
    if (!uses_unet(settings)) return {size, widths(size)};
    const int dims = static_cast<int>(settings.integer("dims"));
    return unet_shape(unet_of(settings, dims, axis_cells(settings)), size);
  }

  // The U-net's grid must halve level by level; the fully connected network has about
  // 8·cells² weights (8n⁴ in 2-D), and a rule keeps a few vectors that long.
  void check(const Settings& settings) const override {
    if (uses_unet(settings)) {
      check_unet(settings, static_cast<int>(settings.integer("dims")), axis_cells(settings));
      return;
    }
    if (settings.integer("dims") == 2 && settings.has("n") && settings.integer("n") > 32) {
      throw Error("--n: at most 32 in 2-D with --network mlp (the network has ~8n⁴ weights), "
                  "got " + std::to_string(settings.integer("n")));
    }
    const Index size = cells(settings);
    require_memory(kWeightCopies * 8 * static_cast<double>(size) * static_cast<double>(size) *
                       sizeof(double),
                   "--n: " + std::to_string(size) + " cells (a network of ~8·" +
                       std::to_string(size) + "² weights)");
  }

  void run(const Settings& given, RunContext& context) const override {
    if (uses_unet(given)) check_unet_ranks(given, context);
    const int dims = static_cast<int>(given.integer("dims"));
    nlohmann::json values = given.json();
    values["n"] = axis_cells(given);
    if (values["amount"].is_null()) {
      values["amount"] = 8 * std::pow(values["n"].get<double>() / 64, 2);
    }
    if (values["eval-every"].is_null()) {
      values["eval-every"] = uses_unet(given) ? 1 : dims == 1 ? 250 : 40;
    }
    const Settings settings(values);

    const Index n = settings.integer("n");
    const HeatDiffusion physics(HeatConfig{n, dims, settings.real("amount")});
    const L2Loss loss(1.0);
    const LearningProblem problem{&physics, &loss};
    const std::string tag = std::to_string(dims) + "-D, n=" + std::to_string(n) +
                            (uses_unet(settings) ? ", U-net" : ", MLP");
    LearningSweep sweep(settings, context, kDefaults);
    sweep.draw_from([&physics](std::uint64_t stream, Index count) {
      return make_data(physics, count, stream).set;
    });
    // Every rule on each paired seed; the reconstruction figures and the table show the first.
    std::optional<HeatData> first_test;
    TrainedNetworks trained;
    for (const std::uint64_t seed : paired_seeds(settings)) {
      const HeatData train = make_data(physics, settings.integer("train-size"), 2 * seed);
      const HeatData test = make_data(physics, settings.integer("test-size"), 2 * seed + 1);
      const auto observe = [&test](const Network& network, TrainingRecord& record) {
        const Matrix error = network.forward(test.set.inputs) - test.truth;
        const double samples = static_cast<double>(error.cols());
        record.extras["x_loss"] = 0.5 * error.colwise().squaredNorm().sum() / samples;
        record.extras["x_l1"] = error.cwiseAbs().sum() / samples;
      };
      for (const std::string& id : sweep.run_ids(settings.texts("optimizers"))) {
        std::shared_ptr<Network> network = make_heat_network(settings, seed);
        const LearningResult& r = sweep.run(id, tag, {{"dims", dims}, {"n", n}, {"seed", seed}},
                                            *network, problem, train.set, &test.set, observe);
        if (!first_test) trained.emplace_back(&r, std::move(network));
      }
      if (!first_test) first_test = test;
    }
    const HeatData& test = *first_test;
    report(settings, context, sweep, tag, test, trained);
  }

 private:
  // Adam and SIP: lr 1e-3 and batch 128 as published. HIG/GN (optional, slow: the Jacobian has
  // B·n² rows): batch 4, lr 1, τ 1e-6 as in the HIG paper. SGD (optional): lr 0.1.
  inline static const std::map<std::string, RuleDefaults> kDefaults = {
      {"sgd", {{{"lr", 0.1}}, 128}},
      {"adam", {{{"lr", 1e-3}}, 128}},
      {"gn", {{{"lr", 1.0}}, 4}},
      {"hig", {{{"lr", 1.0}}, 4}},
      {"sip", {{{"lr", 1e-3}}, 128}}};

  static void report(const Settings& settings, RunContext& context, const LearningSweep& sweep,
                     const std::string& tag, const HeatData& test, const TrainedNetworks& trained) {
    const int dims = static_cast<int>(settings.integer("dims"));
    const Index n = settings.integer("n");
    std::vector<const LearningResult*> runs;
    for (const auto& entry : trained) runs.push_back(entry.first);
    sweep.add_loss_figures(context, tag, std::to_string(dims) + "d");
    const std::string x_loss_file = "x_loss_" + std::to_string(dims) + "d.svg";
    context.add_figure(sweep.progress_figure(tag, x_loss_file, LearningSweep::extra("x_loss"),
                                             "Reconstruction error ½‖x − x*‖²",
                                             "mean x loss on the test set"));
    sweep.set_metric_message(tag, x_loss_file, "x_loss",
                             "final reconstruction error ½‖x − x*‖² on the test set",
                             "Lowest y loss (what the rules train on)", "final y loss");
    if (dims == 1) {
      add_line_reconstructions(context, test.truth, test.set.inputs, trained, kShownSamples);
    } else {
      add_field_reconstructions(context, n, test.truth, test.set.inputs, trained, kShownSamples,
                                {"diffused", "temperature"});
    }
    add_table(context, runs);
    sweep.add_tables();
    context.add_note(reference_note(settings, tag));
  }

  static std::string reference_note(const Settings& settings, const std::string& tag) {
    std::string network;
    if (uses_unet(settings)) {
      network = "a U-net (" + std::to_string(settings.integer("levels")) + " levels, " +
                std::to_string(settings.integer("filters")) + " filters, batch norm " +
                settings.text("batch-norm") + ", " + settings.text("padding") +
                " padding; its output takes the mean of y* as the reference's does)";
    } else {
      const Index size = cells(settings);
      network = "a " + std::to_string(size) + "-" + std::to_string(2 * size) + "-" +
                std::to_string(2 * size) + "-" + std::to_string(size) +
                " tanh network without the reference's mean correction";
    }
    return "The reference (docs/reference_experiments.md) trains a U-net (~38k weights) on 2-D "
           "64×64 fields with fresh batches of 128 and Adam 10⁻³: after 50 steps the x loss is "
           "SIP ~21 vs Adam ~30 (book notebook, ratio ~0.7), and the SIP paper's networks "
           "trained for 6000 s on a GPU reach a test L1 of SIP ~50 vs Adam ~125 (ratio ~0.4). "
           "This run: " + tag + ", amount " + format_value(settings.real("amount")) + ", " +
           network + ", " +
           (settings.text("data") == "fresh" ? "batches drawn afresh every step"
                                             : "a fixed training set") +
           ". The absolute losses scale with the number of cells, so compare the SIP/Adam "
           "ratios where the setups differ.";
  }

  static void add_table(RunContext& context, const std::vector<const LearningResult*>& runs) {
    RunContext::Table table{
        "Final test losses, means over the test samples after training: the y loss the rules "
        "train on, and the x losses against the true initial state x*; the last column is each "
        "rule's x loss over the lowest (best: the rule that reconstructs x best)",
        {"rule", "iterations", "training s", "y loss ½‖P(x) − y*‖²", "x loss ½‖x − x*‖²",
         "x L1 Σ|x − x*|", "x loss / lowest"},
        {}};
    double lowest = INFINITY;
    for (const LearningResult* run : runs) {
      const double x_loss = run->summary.history.back().extras["x_loss"];
      if (std::isfinite(x_loss)) lowest = std::min(lowest, x_loss);
    }
    for (const LearningResult* run : runs) {
      const TrainingRecord& last = run->summary.history.back();
      const double x_loss = last.extras["x_loss"];
      table.rows.push_back({run->label, std::to_string(run->summary.iterations),
                            format_value(run->summary.train_seconds), format_value(last.test_loss),
                            format_value(x_loss), format_value(last.extras["x_l1"]),
                            x_loss == lowest ? "best" : "×" + format_value(x_loss / lowest)});
    }
    context.add_table(std::move(table));
    context.add_table(reference_table(runs));
  }

  // The published values beside this run's: x loss at iteration 49 (the notebook's step 49)
  // and the final x L1, with the SIP/Adam ratios.
  static RunContext::Table reference_table(const std::vector<const LearningResult*>& runs) {
    const auto at_49 = [](const LearningResult* run) {
      for (const TrainingRecord& r : run->summary.history) {
        if (r.iteration == 49) return r.extras["x_loss"].get<double>();
      }
      return std::nan("");
    };
    const LearningResult* sip = nullptr;
    const LearningResult* adam = nullptr;
    for (const LearningResult* run : runs) {
      if (run->id == "sip" && sip == nullptr) sip = run;
      if (run->id == "adam" && adam == nullptr) adam = run;
    }
    const auto shown = [](double v) { return std::isfinite(v) ? format_value(v) : "–"; };
    const auto final_l1 = [](const LearningResult* run) {
      if (run == nullptr) return std::nan("");
      return run->summary.history.back().extras["x_l1"].get<double>();
    };
    const double sip_49 = sip ? at_49(sip) : std::nan(""), adam_49 = adam ? at_49(adam) : std::nan("");
    return {"Published values (docs/reference_experiments.md: the book's notebook at step 49, "
            "the SIP paper's networks after 6000 s on a GPU) beside this run's: the x loss "
            "½‖x − x*‖² after 49 updates and the final x L1 Σ|x − x*| (means over test samples)",
            {"rule", "book: x loss, step 49", "this run: x loss, update 49",
             "paper: trained x L1", "this run: final x L1"},
            {{"SIP", "~21", shown(sip_49), "~50", shown(final_l1(sip))},
             {"Adam", "~30", shown(adam_49), "~125", shown(final_l1(adam))},
             {"SIP / Adam", "~0.7", shown(sip_49 / adam_49), "~0.4",
              shown(final_l1(sip) / final_l1(adam))}}};
  }
};

}  // namespace heat_inverse_case
}  // namespace

std::unique_ptr<Experiment> make_heat_inverse() {
  return std::make_unique<heat_inverse_case::HeatInverse>();
}

} // namespace physgrad::experiments
