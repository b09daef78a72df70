// Learning experiment — the base of the experiments that train a network through a simulator. It
// declares the learning options once (--batch, the learning rules' inversion options, --epochs,
// --time, --eval-every, the checkpoint options, --pretrain, the step-size schedule and --data;
// the rules' flags as the catalogue groups their options), offers every learning rule,
// checks before a run that it is limited and that its Jacobian steps and evaluations fit, and
// gives the experiment's problem at one batch (its reference case) to `physgrad bench` and the
// micro-benchmarks.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "physgrad/run/cases/learning_case.hpp"
#include "physgrad/run/cases/learning_runs.hpp"
#include "physgrad/run/life/experiment.hpp"
#include "physgrad/train/trainer.hpp"

namespace physgrad::run {

// The learning problem of an experiment at one batch (LearningCase::reference): its simulator,
// loss, initial network, the first B training samples and its choices per rule.
struct ReferenceCase {
  std::shared_ptr<const Simulator> physics;
  std::shared_ptr<const Loss> loss;
  Mlp network;    // initialized from the seed, as the experiment's runs start
  Dataset batch;  // the first B samples of the experiment's training set
  std::map<std::string, RuleDefaults> defaults;  // lr, batch and τ of each rule

  LearningProblem problem() const { return {physics.get(), loss.get()}; }
  // Rule `id` with the case's step size, τ and SIP step (the rule's own defaults where the case
  // has none). Throws Error for an unknown id.
  std::unique_ptr<LearningUpdate> update(const std::string& id) const;
  // The case's batch size for rule `id` (TrainerOptions' default where it has none).
  Index batch_size(const std::string& id) const;
};

// The defaults an experiment gives the shared learning options; empty leaves one unset.
struct LearningDefaults {
  std::string time{};        // --time, seconds
  std::string eval_every{};  // --eval-every
  // The help of --eval-every, for an experiment whose default depends on other options.
  std::string eval_every_help{};
  std::string pretrain{};  // --pretrain: auto, or Adam's updates
  // --data's default, fixed or fresh, for an experiment that draws fresh samples
  // (LearningSweep::draw_from); empty: the experiment has no --data.
  std::string data{};
  // --seeds: the paired seeds every rule runs on (seed, seed+1, …), and why the default is what
  // it is when that needs saying (appended to the option's help).
  std::string seeds = "3";
  std::string seeds_why{};
};

// The paired seeds of a run: --seed, --seed + 1, … (--seeds of them), each giving every rule the
// same initial network and data.
std::vector<std::uint64_t> paired_seeds(const Settings& settings);

// The N of --pretrain N (0 for auto, which switches on a plateau); throws Error naming the text
// when it is neither auto nor a whole number from 0 to 10⁹.
long long pretrain_iterations(const std::string& text);

class LearningExperiment : public Experiment {
 public:
  explicit LearningExperiment(LearningDefaults defaults = {}) : defaults_(std::move(defaults)) {}

  // own_options(), then the learning options.
  std::vector<OptionSpec> options() const final;
  // Every learning rule.
  std::vector<std::string> optimizer_choices() const final;
  // Learning runs are limited by --time unless an experiment gives --iters a default.
  long long default_iterations() const override { return 0; }
  // check(), then: some limit (--iters, --epochs, --time) on each run, and a Gauss-Newton or HIG
  // step on the batch and the evaluations the limit allows that fit (in memory, and a step in
  // kMaxStepMultiplyAdds).
  void validate(const Settings& settings) const final;

  // The experiment's problem with a batch of `batch` samples and the network a run with --seed
  // `seed` starts from; none for an experiment without one.
  virtual std::optional<ReferenceCase> reference(Index /*batch*/, std::uint64_t /*seed*/) const {
    return std::nullopt;
  }

  // What the size checks need under `settings`: physics outputs per sample and the network —
  // a dense one by its widths, any other by its parameter count and the multiply-adds of one
  // entry of J Jᵀ (|θ| for a network that forms the gradient rows, as a ConvNetwork does).
  struct Shape {
    Index outputs;
    std::vector<Index> widths;  // a dense network {input, hidden…, output}; empty otherwise
    double parameters = 0;      // |θ| when widths is empty
    double gram_entry = 0;      // multiply-adds per entry of J Jᵀ when widths is empty
  };

 protected:
  // The experiment's own options (its sizes, settings and --train-size/--test-size).
  virtual std::vector<OptionSpec> own_options() const = 0;
  virtual Shape shape(const Settings& settings) const = 0;
  // The experiment's own checks between options; throws Error.
  virtual void check(const Settings& /*settings*/) const {}

 private:
  LearningDefaults defaults_;
};

// An option counting samples (--train-size, --test-size): at least 1, refused when its samples of
// `bytes_each` bytes do not fit in memory, `quick` in the quick check of every experiment.
OptionSpec sample_count_option(std::string name, std::string default_text, std::string help,
                               std::string quick,
                               std::function<double(const Settings&)> bytes_each);
// The bytes one sample needs at least: its `data_values` doubles (inputs, targets, context) and
// the activations of a network of `widths` kept for the backward pass.
double sample_bytes(const std::vector<Index>& widths, Index data_values);
// A Jacobian step forms a k × k matrix, k = min(B·m, |θ|), from B·m rows of |θ| entries — J Jᵀ
// from the layer factors, (B·m)²·Σ_l (w_l + w_{l+1} + 1) multiply-adds, or J and Jᵀ J,
// B·m·|θ|² — and decomposes it (k³): at most this many (a few minutes on one core).
inline constexpr double kMaxStepMultiplyAdds = 1e12;

}  // namespace physgrad::run
