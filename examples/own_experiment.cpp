// A program's own experiment through the experiment framework (physgrad::run): a network learns
// the inverse of P(y) = (y₁, λ·y₂), trained through P with L = ½‖P(f(x)) − x‖², registered in
// the program's own Registry and run into a run folder with checkpoints, resume and an index.
//
//   own_experiment run DIR [--NAME VALUE …]   a new run (options as `physgrad run`)
//   own_experiment resume DIR                 continues an unfinished run from its checkpoint
//   own_experiment report DIR                 DIR/index.html over the run folders in DIR
// Ctrl-C (SIGINT, or SIGTERM) stops a run in order: its checkpoint is kept, the folder and the
// command that resumes it are printed, and the program exits with 128 + the signal's number.
#include <cmath>
#include <cstdio>
#include <exception>
#include <iostream>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "physgrad/error.hpp"
#include "physgrad/loss/loss.hpp"
#include "physgrad/physics/diagonal_scale.hpp"
#include "physgrad/run/life/interrupt.hpp"
#include "physgrad/run/cases/learning_experiment.hpp"
#include "physgrad/run/cases/registry.hpp"
#include "physgrad/run/run.hpp"
#include "physgrad/run/pages/run_index.hpp"
#include "physgrad/run/cases/sampling.hpp"

namespace {

namespace run = physgrad::run;
using physgrad::Index;

// Points x uniform in [−1, 1]²: the network's inputs and the targets P(f(x)) should reach.
physgrad::Dataset inverse_scale_points(Index count, std::uint64_t seed) {
  run::Sampler sampler(seed);
  physgrad::Matrix x(2, count);
  for (Index i = 0; i < count; ++i) x.col(i) << sampler.uniform(-1, 1), sampler.uniform(-1, 1);
  return {x, x, physgrad::Matrix()};
}

class InverseScale final : public run::LearningExperiment {
 public:
  InverseScale() : LearningExperiment({.eval_every = "20"}) {}
  std::string name() const override { return "inverse-scale"; }
  std::string description() const override {
    return "a 2 -> 16 -> 2 network learns the inverse of P(y) = (y1, lambda*y2)";
  }
  std::vector<std::string> default_optimizers() const override { return {"adam", "hig"}; }
  long long default_iterations() const override { return 200; }

  void run(const run::Settings& settings, run::RunContext& context) const override {
    const physgrad::DiagonalScale physics(physgrad::Vector{{1.0, settings.real("lambda")}});
    const physgrad::L2Loss loss;
    const physgrad::LearningProblem problem{&physics, &loss};
    const auto seed = static_cast<std::uint64_t>(settings.integer("seed"));
    const physgrad::Dataset train_set = inverse_scale_points(settings.integer("train-size"), seed);
    const physgrad::Dataset test_set = inverse_scale_points(64, seed + 1);
    // Each rule's step size and batch where the catalogue's defaults do not fit this problem.
    run::LearningSweep sweep(settings, context,
                             {{"adam", {{{"lr", 0.01}}, 64}}, {"hig", {{{"lr", 1.0}}, 64}}});
    const std::string tag = "λ=" + run::format_value(settings.real("lambda"));
    for (const std::string& id : sweep.run_ids(settings.texts("optimizers"))) {
      physgrad::Mlp network({2, 16, 2}, physgrad::Activation::kTanh);
      network.initialize(seed);
      sweep.run(id, tag, {{"seed", seed}}, network, problem, train_set, &test_set);
    }
    sweep.add_loss_figures(context, tag, "inverse_scale");
    sweep.set_time_message(tag, "inverse_scale");
    sweep.add_tables();
  }

 protected:
  std::vector<run::OptionSpec> own_options() const override {
    return {run::real_option("lambda", "0.01", "scale of the second output").above(0),
            run::integer_option("train-size", "256", "training points").at_least(1).at_most(1e6)};
  }
  Shape shape(const run::Settings& /*settings*/) const override { return {2, {2, 16, 2}}; }
};

// The final mean test loss of every run of the outcome, one line each; for a run stopped on
// request, why and how to continue it (this program's resume, which knows its experiment, in
// place of `physgrad resume`, which does not). Returns the exit status.
int print_finals(const run::RunOutcome& outcome) {
  if (!outcome.finished) {
    std::string stopped = outcome.stopped;
    const std::string cli = "physgrad resume ";
    for (std::size_t at = stopped.find(cli); at != std::string::npos; at = stopped.find(cli)) {
      stopped.replace(at, cli.size(), "own_experiment resume ");
    }
    std::cout << stopped << '\n';
    return outcome.signal > 0 ? 128 + outcome.signal : 1;
  }
  for (const physgrad::run::RunEntry& run : outcome.summary->runs) {
    std::printf("%-6s final test loss %.6e\n", run.label.c_str(), run.final.test_loss.value());
  }
  std::cout << "report: " << outcome.report.string() << '\n';
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  if (args.size() < 2 || args.size() % 2 != 0) {
    std::cerr << "usage: own_experiment run|resume|report DIR [--NAME VALUE …]\n";
    return 2;
  }
  // The program's experiments: its own only. A program built with physgrad's reference
  // experiments would start from their list and add its own to it.
  std::vector<std::unique_ptr<run::Experiment>> list;
  list.push_back(std::make_unique<InverseScale>());
  const run::Registry experiments(std::move(list));

  run::install_interrupt_handlers();
  run::RunHooks hooks;
  hooks.log = [](const std::string& line) { std::cerr << line << '\n'; };
  try {
    if (args[0] == "run") {
      const run::Experiment& experiment = experiments.find("inverse-scale");
      std::vector<std::pair<std::string, std::string>> given;
      for (std::size_t i = 2; i + 1 < args.size(); i += 2) {
        if (args[i].rfind("--", 0) != 0) throw physgrad::Error("not an option: " + args[i]);
        given.emplace_back(args[i].substr(2), args[i + 1]);
      }
      return print_finals(
          run::Run::start(experiment, run::resolve_settings(experiment, given), args[1], hooks));
    } else if (args[0] == "resume") {
      return print_finals(run::Run::resume(experiments, args[1], hooks));
    } else if (args[0] == "report") {
      const run::RunIndex index = run::write_run_index(experiments, args[1]);
      std::cout << index.folders << " run folders: " << index.page.string() << '\n';
    } else {
      throw physgrad::Error("unknown command '" + args[0] + "' (known: run, resume, report)");
    }
  } catch (const std::exception& e) {
    std::cerr << "own_experiment: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
