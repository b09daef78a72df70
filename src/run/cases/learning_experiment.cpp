#include "physgrad/run/cases/learning_experiment.hpp"

#include <algorithm>
#include <cmath>

#include "physgrad/catalogue.hpp"
#include "physgrad/error.hpp"
#include "physgrad/memory.hpp"
#include "physgrad/text.hpp"

namespace physgrad::run {

namespace {

// Throws Error unless --iters, --epochs or --time limits the training.
void require_training_limit(const Settings& settings, const std::string& experiment) {
  if (!settings.has("iters") && !settings.has("epochs") && !settings.has("time")) {
    throw Error(experiment + ": give at least one of --iters, --epochs, --time");
  }
}

// |θ| and the multiply-adds of one J Jᵀ entry of the network `shape` describes: from the widths
// of a dense network (nn/dense_layer_gram.hpp: Σ_l (w_l + w_{l+1} + 1) per entry), as given for
// another.
std::pair<double, double> network_size(const LearningExperiment::Shape& shape) {
  if (shape.widths.empty()) return {shape.parameters, shape.gram_entry};
  double parameters = 0, entry = 0;
  const std::vector<Index>& widths = shape.widths;
  for (std::size_t i = 0; i + 1 < widths.size(); ++i) {
    parameters += static_cast<double>(widths[i] + 1) * static_cast<double>(widths[i + 1]);
    entry += static_cast<double>(widths[i] + widths[i + 1] + 1);
  }
  return {parameters, entry};
}

// Throws Error naming --batch when a Gauss-Newton or HIG step (when one is selected) on the
// given batch with `outputs` physics outputs per sample and the network of `shape` would not fit
// in memory or would take more than kMaxStepMultiplyAdds, and naming --eval-every when the
// evaluations an iteration or epoch limit allows would not fit in memory.
void require_learning_sizes(const Settings& settings, const LearningExperiment::Shape& shape) {
  const Index outputs = shape.outputs;
  const auto [parameters, entry] = network_size(shape);
  const double train_size = static_cast<double>(settings.integer("train-size"));
  bool jacobian = !settings.has("optimizers");  // the default rules may include gn or hig
  for (const std::string& id : settings.has("optimizers") ? settings.texts("optimizers")
                                                          : std::vector<std::string>{}) {
    jacobian = jacobian ||
               find_rule(RuleKind::kLearning, id).derivative == RuleDerivative::kJacobian;
  }
  if (jacobian && settings.has("batch")) {
    const long long given = settings.integer("batch");
    const double rows =
        static_cast<double>(outputs) * std::min(static_cast<double>(given), train_size);
    const double k = std::min(rows, parameters);
    const auto whole = [](double value) { return std::to_string(static_cast<long long>(value)); };
    const std::string what = "--batch: " + std::to_string(given) + " (a gn or hig step forms a " +
                             whole(k) + "² matrix from " + whole(rows) + " Jacobian rows of " +
                             whole(parameters) + " weights)";
    // The matrix with the eigendecomposition's copy and workspace; the rows when they are
    // formed (the normal path, rows > weights).
    require_memory(8 * (3 * k * k + (rows > parameters ? rows * parameters : 0)), what);
    // The Gram path (rows ≤ weights) forms J Jᵀ, `entry` multiply-adds an entry; the normal
    // path forms J and Jᵀ J (rows·weights² multiply-adds). Then the k × k eigendecomposition.
    const double work = (rows <= parameters ? rows * rows * entry : rows * parameters * k) + k * k * k;
    if (work > kMaxStepMultiplyAdds) {
      throw Error(what + " takes " + format_value(work) + " multiply-adds, more than the " +
                  format_value(kMaxStepMultiplyAdds) + " (a few minutes on one core) a step may take");
    }
  }
  // Each evaluation keeps a record and a metrics row per run (about 1 KiB).
  if (settings.has("eval-every") && (settings.has("iters") || settings.has("epochs"))) {
    // The fewest iterations the limit allows: a batch of every sample unless one is given.
    const double batch = settings.has("batch")
                             ? std::min(static_cast<double>(settings.integer("batch")), train_size)
                             : train_size;
    const double iterations =
        settings.has("iters")
            ? static_cast<double>(settings.integer("iters"))
            : static_cast<double>(settings.integer("epochs")) * std::ceil(train_size / batch);
    // A pretrained run (--pretrain) next to each rule that needs the stacked Jacobian.
    double runs = 1;
    if (settings.has("optimizers")) {
      const std::vector<std::string> ids = settings.texts("optimizers");
      const bool pretrained = settings.has("pretrain") && settings.text("pretrain") != "0";
      const bool alone = !(settings.has("alone") && settings.text("alone") == "off");
      runs = static_cast<double>(ids.size());
      bool twins = false;
      for (const std::string& id : ids) {
        const bool twin =
            pretrained && make_learning_update(id)->need() == UpdateNeed::kStackedJacobian;
        runs += twin && alone;  // with --alone off the twin takes the rule's place
        twins = twins || twin;
      }
      // The control arm beside the twins, unless it is off.
      const bool control = !(settings.has("control") && settings.text("control") == "off") &&
                           !(settings.has("control-lr-factor") &&
                             settings.real("control-lr-factor") == 0);
      runs += control && twins;
    }
    const long long every = settings.integer("eval-every");
    require_memory(1024 * runs * (iterations / static_cast<double>(every) + 2),
                   "--eval-every: " + std::to_string(every) + " (" + format_value(iterations) +
                       " iterations, each run keeping every evaluation)");
  }
}

// The flags of the learning rules' options of `group`, each offered for every learning rule
// that has it (rule_option_spec), in the catalogue's order (grouped_rule_options).
std::vector<OptionSpec> learning_rule_flags(OptionGroup group) {
  const std::vector<std::string> ids = rule_ids(RuleKind::kLearning);
  std::vector<OptionSpec> flags;
  for (const std::string& name : grouped_rule_options(RuleKind::kLearning, group)) {
    flags.push_back(rule_option_spec(name, RuleKind::kLearning, ids));
  }
  return flags;
}

// The options of the Adam part of the Adam→ twins and of the control, one for each option of
// Adam's table (its moments and its step-size schedule): --pretrain-lr, --pretrain-schedule, …,
// unset by default (the Adam run's value); and the control arm.
std::vector<OptionSpec> pretraining_options() {
  std::vector<OptionSpec> flags;
  for (const OptionDescription& option :
       rule_options(find_rule(RuleKind::kLearning, kPretrainingRule))) {
    flags.push_back(option_in_range(
        "pretrain-" + flag_name(option.name), option.range,
        "with --pretrain, the Adam part of the Adam→ twins and of the control: " + option.help +
            " (default: the Adam run's)"));
  }
  flags.push_back(
      text_option("control", "",
                  "on or off: with --pretrain, beside the twins a control run Adam→Adam that "
                  "switches where they do and continues with a fresh Adam at the step "
                  "--control-lr-factor × the Adam part's (default: on where a twin runs)")
          .one_of({"on", "off"}));
  flags.push_back(real_option("control-lr-factor", "",
                              "the control's step over the Adam part's (default 0.1; 0: no "
                              "control)")
                      .at_least(0)
                      .at_most(1));
  flags.push_back(text_option("alone", "",
                              "on or off: with --pretrain, each rule that gets an Adam→ twin also "
                              "runs alone from the start (default on; off: only its twin, e.g. "
                              "for a long run where the rule alone would take hours)")
                      .one_of({"on", "off"}));
  return flags;
}

// The options every learning experiment has, after the common ones: optional, so that each rule
// keeps its own defaults unless one is given; an experiment may give time and eval-every
// defaults.
std::vector<OptionSpec> learning_options(const LearningDefaults& defaults) {
  std::vector<OptionSpec> options = {
      integer_option("batch", "",
                     "mini-batch size for every rule (default: each rule's own); with gn or hig "
                     "one step may take at most 10¹² multiply-adds (docs/cli.md, forming J Jᵀ "
                     "and its eigendecomposition; a few minutes)")
          .at_least(1),
      integer_option("epochs", "", "epochs per run (at most 10⁹, as --iters)")
          .at_least(1)
          .at_most(1e9),
      real_option("time", defaults.time,
                  "wall-time budget per run in seconds, evaluations and checkpoints included; a "
                  "step that would overrun it is not started (the first of --iters, --epochs, "
                  "--time reached ends a run; a run limited by --time alone is also evaluated "
                  "every 1/40 of its training time)")
          .above(0),
      integer_option("eval-every", defaults.eval_every,
                     defaults.eval_every_help.empty()
                         ? "evaluate every N iterations (default: every epoch)"
                         : defaults.eval_every_help)
          .at_least(1),
      integer_option("checkpoint-every", "",
                     "also save a checkpoint every N iterations (physgrad resume continues it)")
          .at_least(1),
      real_option("checkpoint-seconds", "60",
                  "save a checkpoint of the run in progress at least this often (wall seconds)")
          .above(0),
      text_option("pretrain", defaults.pretrain,
                  "auto or N: each rule that needs the stacked Jacobian (gn, hig, …) gets a twin "
                  "that Adam trains first (Adam→GN, Adam→HIG; Adam with the settings and batch "
                  "of the Adam run, or --pretrain-<option>) before the rule continues from that "
                  "network, and a control Adam→Adam runs beside them (--control) — auto: once "
                  "Adam's evaluated training loss has levelled off (--plateau-window, "
                  "--plateau-fraction), N: after N updates (with --iters ≤ N there is no such "
                  "run); a twin that never switched reads as Adam; --iters, --epochs and --time "
                  "count the whole run; 0: none" +
                      std::string(defaults.pretrain.empty() ? " (default)" : ""))
          .quick("1"),
      integer_option("plateau-window", "10",
                     "--pretrain auto: the evaluations over which Adam's loss is compared")
          .at_least(1)
          .at_most(1e6),
      real_option("plateau-fraction", "0.02",
                  "--pretrain auto: Adam has levelled off when the best loss of the last "
                  "--plateau-window evaluations is less than this fraction below the best before "
                  "them")
          .above(0)
          .below(1),
  };
  // After --batch, the inverses' options; after the pretraining options, the Adam part's and
  // the control's, then the schedule's.
  const std::vector<OptionSpec> inverses = learning_rule_flags(OptionGroup::kInversion);
  options.insert(options.begin() + 1, inverses.begin(), inverses.end());
  const std::vector<OptionSpec> pretraining = pretraining_options();
  options.insert(options.end(), pretraining.begin(), pretraining.end());
  const std::vector<OptionSpec> schedule = learning_rule_flags(OptionGroup::kSchedule);
  options.insert(options.end(), schedule.begin(), schedule.end());
  if (!defaults.data.empty()) {
    options.push_back(text_option("data", defaults.data,
                                  "training samples: fixed (the --train-size samples, in shuffled "
                                  "epochs) or fresh (every mini-batch drawn anew from the same "
                                  "distribution; --train-size then sets the epoch's length and "
                                  "the set the training loss is evaluated on)")
                          .one_of({"fixed", "fresh"}));
  }
  return options;
}

// --seeds with the experiment's default: every rule runs on the same seeds, so that seed s gives
// each the same initial network and data and the verdict compares them seed by seed.
OptionSpec seeds_option(const LearningDefaults& defaults) {
  return integer_option("seeds", defaults.seeds,
                        "number of paired seeds per configuration (seed, seed+1, …; every rule "
                        "starts from the same network and data of a seed)" +
                            (defaults.seeds_why.empty() ? "" : "; " + defaults.seeds_why))
      .at_least(1)
      .at_most(1000)
      .quick("2");
}

}  // namespace

std::vector<std::uint64_t> paired_seeds(const Settings& settings) {
  std::vector<std::uint64_t> seeds;
  const auto first = static_cast<std::uint64_t>(settings.integer("seed"));
  for (long long s = 0; s < settings.integer("seeds"); ++s) {
    seeds.push_back(first + static_cast<std::uint64_t>(s));
  }
  return seeds;
}

long long pretrain_iterations(const std::string& text) {
  if (text == "auto") return 0;
  OptionSpec spec = integer_option("pretrain", "", "").at_least(0).at_most(1e9);
  try {
    return parse_option(spec, text).get<long long>();
  } catch (const Error&) {
    throw Error("--pretrain: " + in_quotes(text) + " is neither auto nor a whole number from 0 "
                "to 10⁹");
  }
}

std::unique_ptr<LearningUpdate> ReferenceCase::update(const std::string& id) const {
  const RuleDefaults* own = experiment_setting(defaults, id);
  return make_learning_update(id, own == nullptr ? RuleSettings{} : own->settings);
}

Index ReferenceCase::batch_size(const std::string& id) const {
  const RuleDefaults* own = experiment_setting(defaults, id);
  return (own == nullptr ? std::nullopt : own->batch).value_or(TrainerOptions{}.batch_size);
}

std::vector<OptionSpec> LearningExperiment::options() const {
  std::vector<OptionSpec> options = own_options();
  options.push_back(seeds_option(defaults_));
  for (OptionSpec& spec : learning_options(defaults_)) options.push_back(std::move(spec));
  return options;
}

std::vector<std::string> LearningExperiment::optimizer_choices() const {
  return rule_ids(RuleKind::kLearning);
}

void LearningExperiment::validate(const Settings& settings) const {
  if (settings.has("pretrain")) pretrain_iterations(settings.text("pretrain"));
  // The options of the twins' Adam part and of the control mean nothing without twins.
  if (!settings.has("pretrain") || settings.text("pretrain") == "0") {
    for (const OptionSpec& spec : pretraining_options()) {
      if (settings.has(spec.name)) {
        throw Error(spec.flag() + ": " + settings.json().at(spec.name).dump() +
                    " is for the Adam→ twins, which need --pretrain auto or N");
      }
    }
  }
  check(settings);
  require_training_limit(settings, name());
  require_learning_sizes(settings, shape(settings));
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

}  // namespace physgrad::run
