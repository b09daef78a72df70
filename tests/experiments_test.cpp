// Reference experiments through the experiment API: settings resolution and the qualitative
// outcome each experiment exists to show.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>

#include "registry.hpp"
#include "physgrad/run/life/experiment.hpp"
#include "experiment_runs.hpp"
#include "physgrad/catalogue.hpp"
#include "physgrad/error.hpp"

namespace physgrad::run {
namespace {

using testing::run_experiment;

const RunEntry& find_run(const RunContext& context, const std::string& optimizer,
                               double alpha) {
  for (const RunEntry& entry : context.runs()) {
    if (entry.optimizer == optimizer && entry.params["alpha"] == alpha) return entry;
  }
  throw Error("no run " + optimizer);
}

TEST(ScaledToyExperiment, InvertedRulesNeedTheSameIterationsForEveryAlphaAndGdDoesNot) {
  const RunContext context = run_experiment("scaled-toy", {{"alpha", "1,10,100,1000"}});
  for (const std::string id : {"newton", "gn", "ig", "pg", "lm"}) {
    const RunEntry& reference = find_run(context, id, 1.0);
    EXPECT_EQ(reference.termination, "converged") << id;
    for (const double alpha : {10.0, 100.0, 1000.0}) {
      const RunEntry& entry = find_run(context, id, alpha);
      EXPECT_EQ(entry.termination, "converged") << id << " alpha " << alpha;
      EXPECT_EQ(entry.iterations, reference.iterations) << id << " alpha " << alpha;
    }
  }
  // One fixed step size: GD converges for α = 1 and diverges for α = 1000 (η α² ≫ 2).
  EXPECT_EQ(find_run(context, "gd", 1.0).termination, "converged");
  EXPECT_EQ(find_run(context, "gd", 1000.0).termination, "numerical_failure");
  EXPECT_EQ(context.tables().size(), 1u);
  EXPECT_EQ(context.figures().size(), 1u + 2u * 4u);  // iterations vs α, landscape + loss per α
}

// The message's verb agrees with the count of rules that need the same iterations at every α: one
// rule "needs" (Newton alone here, as GD's count moves with α), several "need".
TEST(ScaledToyExperiment, TheInvarianceSentenceAgreesWithItsRuleCount) {
  const RunContext one =
      run_experiment("scaled-toy", {{"alpha", "1,1000"}, {"optimizers", "newton,gd"}});
  EXPECT_NE(one.message().find("Newton (") , std::string::npos) << one.message();
  EXPECT_NE(one.message().find(") needs the same iterations at every α"), std::string::npos)
      << one.message();
  const RunContext two =
      run_experiment("scaled-toy", {{"alpha", "1,1000"}, {"optimizers", "newton,gn,gd"}});
  EXPECT_NE(two.message().find(") need the same iterations at every α"), std::string::npos)
      << two.message();
}

// time-reversal's "N× fewer" has two significant digits, as every other ratio (664 / 7 passes
// read "95×", not "94.86×").
TEST(TimeReversalExperiment, TheFewerPassesRatioHasTwoDigits) {
  const RunContext context = run_experiment("time-reversal", {});
  const std::string& message = context.message();
  std::size_t at = message.find("× fewer than");
  ASSERT_NE(at, std::string::npos) << message;
  for (; at != std::string::npos; at = message.find("× fewer than", at + 1)) {
    const std::size_t start = message.rfind(' ', at) + 1;
    const std::string number = message.substr(start, at - start);
    std::size_t digits = 0;
    for (const char c : number) digits += std::isdigit(static_cast<unsigned char>(c)) != 0;
    const bool leading_zero = number.rfind("0.", 0) == 0;
    EXPECT_LE(digits - (leading_zero ? 1 : 0), 2u) << number << " in " << message;
  }
}

// A step size that breaks some rules numerically (η = 1e308: GN's normal matrix, IG's Jacobian
// solve and PG's inverse see Inf) ends those runs as numerical failures naming the rule; the
// experiment runs to the end and keeps every other result.
TEST(ScaledToyExperiment, RulesThatFailNumericallyAreMarkedAndTheOthersKept) {
  RunContext context;
  ASSERT_NO_THROW(context = run_experiment("scaled-toy", {{"alpha", "1,100"}, {"lr", "1e308"}}));
  EXPECT_EQ(context.runs().size(), 20u);  // 10 rules × 2 values of α
  for (const std::string id : {"gd", "newton", "gn", "ig", "pg"}) {
    const RunEntry& entry = find_run(context, id, 100.0);
    EXPECT_EQ(entry.termination, "numerical_failure") << id;
    EXPECT_FALSE(entry.message.empty()) << id;
  }
  EXPECT_EQ(find_run(context, "lm", 100.0).termination, "converged");  // lm has no step size
}

TEST(SensitivityExperiment, GdStepGrowsWithAlphaSquaredInvertedStepsDoNot) {
  const RunContext context = run_experiment("sensitivity", {{"alpha", "0.1,1,10"}, {"iters", "1"}});
  const auto first_step = [&](const std::string& id, double alpha) {
    for (const nlohmann::json& row : context.metrics()) {
      if (row["optimizer"] == id && row["alpha"] == alpha && row["iteration"] == 1) {
        return row["step_norm"].get<double>();
      }
    }
    return -1.0;
  };
  EXPECT_NEAR(first_step("gd", 10.0) / first_step("gd", 1.0), 100.0, 1e-9);
  EXPECT_NEAR(first_step("gd", 1.0) / first_step("gd", 0.1), 100.0, 1e-9);
  for (const std::string id : {"newton", "ig"}) {
    EXPECT_NEAR(first_step(id, 10.0), first_step(id, 0.1), 1e-12) << id;
  }
}

TEST(ComparisonExperiment, PgEndsClosestToTheMinimumAndBothInversesAgree) {
  const RunContext context = run_experiment("comparison", {});
  std::map<std::string, double> distance;
  for (const RunEntry& entry : context.runs()) {
    const std::vector<double> x = entry.final.more.at("x");
    distance[entry.label] = std::hypot(x[0], x[1]);
  }
  // docs/reference_experiments.md (comparison): distances GD 2.63, Newton 0.925, PG 0.51 after
  // 10 steps.
  EXPECT_NEAR(distance["GD"], 2.63, 0.005);
  EXPECT_NEAR(distance["Newton"], 0.925, 0.0005);
  EXPECT_NEAR(distance["PG (analytic inverse)"], 0.511, 0.0005);
  EXPECT_NEAR(distance["PG (L-BFGS inverse)"], distance["PG (analytic inverse)"], 1e-6);
  for (const auto& [label, d] : distance) {
    EXPECT_LE(distance["PG (analytic inverse)"], d + 1e-6) << label;
  }
}

// docs/reference_experiments.md (HIG toy), shortened: on λ = 0.01 HIG ends far below Adam and GN.
TEST(HigToyExperiment, HalfInverseGradientsBeatAdamAndGaussNewtonWhenIllConditioned) {
  const RunContext context =
      run_experiment("hig-toy", {{"lambda", "0.01"}, {"seeds", "2"}, {"iters", "2000"}, {"eval-every", "500"}});
  std::map<std::string, std::vector<double>> losses;
  for (const RunEntry& entry : context.runs()) {
    const double initial = entry.initial.test_loss.value(), final_loss = entry.final.test_loss.value();
    losses[entry.optimizer].push_back(final_loss);
    if (entry.optimizer != "gn") {
      EXPECT_LT(final_loss, initial) << entry.label;
    }
  }
  ASSERT_EQ(losses["hig"].size(), 2u);
  const auto worst = [](const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); };
  const auto best = [](const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); };
  EXPECT_LT(worst(losses["hig"]), 0.1 * best(losses["adam"]));
  EXPECT_LT(worst(losses["hig"]), 0.1 * worst(losses["gn"]));
  // Tables: losses and saturation for the one λ, and the time split.
  EXPECT_EQ(context.tables().size(), 3u);
}

// --lr and --rcond take the range every rule with that option takes, from the rules' option
// descriptions; an experiment option named like a rule option is that shared option.
TEST(ExperimentSettings, TheSharedRuleOptionsTakeTheRulesRanges) {
  const Experiment& experiment = experiments::builtin_registry().find("hig-toy");
  const std::vector<OptionSpec> specs = all_options(experiment);
  const OptionSpec& rcond = find_option(experiment, specs, "rcond");
  int rules = 0;
  for (const RuleInfo& rule : rule_catalogue()) {
    if (rule.kind != RuleKind::kLearning) continue;
    for (const OptionDescription& option : rule_options(rule)) {
      if (option.name != "rcond") continue;
      ++rules;
      EXPECT_EQ(rcond.min, option.range.min) << rule.id;
      EXPECT_EQ(rcond.min_exclusive, option.range.min_open) << rule.id;
      EXPECT_EQ(rcond.max, option.range.max) << rule.id;
      EXPECT_EQ(rcond.max_exclusive, option.range.max_open) << rule.id;
    }
  }
  EXPECT_EQ(rules, 6);  // gn, hig and their structured approximations
  EXPECT_EQ(resolve_settings(experiment, {{"rcond", "0.7"}}).real("rcond"), 0.7);
  try {
    resolve_settings(experiment, {{"rcond", "1"}});
    ADD_FAILURE() << "--rcond 1 accepted";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "--rcond: must be in [0, 1), got '1'");
  }
  EXPECT_NE(rcond.help.find("(gn, hig, kfac, kfac-hig, lanczos-gn, lanczos-hig; default: each "
                            "rule's own)"),
            std::string::npos)
      << rcond.help;
  for (const auto& any : experiments::builtin_registry()) {
    const std::string& name = any->name();
    for (const OptionSpec& spec : all_options(*any)) {
      for (const RuleKind kind : {RuleKind::kDirect, RuleKind::kLearning}) {
        const std::vector<std::string> rule_names = rule_option_names(kind);
        if (std::find(rule_names.begin(), rule_names.end(), spec.name) == rule_names.end()) continue;
        const OptionRange range = shared_rule_option(spec.name, kind).option.range;
        EXPECT_EQ(spec.min, range.min) << name << " --" << spec.name;
        EXPECT_EQ(spec.max, range.max) << name << " --" << spec.name;
      }
    }
  }
}

// Besides --lr, a learning experiment offers the learning rules' options of the inversion and
// schedule groups (OptionGroup), each once and in the catalogue's order: the command line code
// names none of them.
TEST(ExperimentSettings, TheLearningRuleFlagsAreTheRulesGroupedOptions) {
  const Experiment& experiment = experiments::builtin_registry().find("hig-toy");
  const std::vector<std::string> names = rule_option_names(RuleKind::kLearning);
  std::vector<std::string> flags;  // the rule options among the experiment's, in their order
  for (const OptionSpec& spec : all_options(experiment)) {
    std::string name = spec.name;
    std::replace(name.begin(), name.end(), '-', '_');
    if (name != "lr" && std::binary_search(names.begin(), names.end(), name)) {
      flags.push_back(name);
    }
  }
  const std::vector<std::string> inversion =
      grouped_rule_options(RuleKind::kLearning, OptionGroup::kInversion);
  const std::vector<std::string> schedule =
      grouped_rule_options(RuleKind::kLearning, OptionGroup::kSchedule);
  EXPECT_EQ(inversion, (std::vector<std::string>{"rcond", "precision", "eigensolver", "damping",
                                                 "refresh", "factor_decay", "samples",
                                                 "products"}));
  EXPECT_EQ(schedule, (std::vector<std::string>{"schedule", "decay", "decay_every", "t_max",
                                                "min_lr", "patience", "threshold"}));
  std::vector<std::string> expected = inversion;
  expected.insert(expected.end(), schedule.begin(), schedule.end());
  EXPECT_EQ(flags, expected);
}

TEST(ExperimentSettings, DefaultsResolveAndBadValuesNameTheOption) {
  const Experiment& experiment = experiments::builtin_registry().find("scaled-toy");
  const Settings settings = resolve_settings(experiment, {});
  EXPECT_EQ(settings.integer("iters"), 1000);
  EXPECT_FALSE(settings.has("lr"));
  EXPECT_EQ(settings.reals("alpha"), (std::vector<double>{1, 10, 100, 1000}));
  const auto message = [&](const std::string& name, const std::string& text) {
    try {
      resolve_settings(experiment, {{name, text}});
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message("lr", "-1"), "--lr: must be > 0, got '-1'");
  EXPECT_EQ(message("lr", "1e400"), "--lr: '1e400' is out of the range of a double");
  EXPECT_EQ(message("alpha", "1,2,"), "--alpha: empty entry in list '1,2,'");
  EXPECT_EQ(message("alpha", " "), "--alpha: needs at least one value");
  EXPECT_EQ(message("iters", "ten"),
            "--iters: 'ten' is not a whole number (decimal digits, like 16)");
  EXPECT_EQ(message("optimizers", "gd,gd"), "--optimizers: 'gd' is listed twice");
  EXPECT_EQ(message("alpha", "1,,2"), "--alpha: empty entry in list '1,,2'");
  EXPECT_EQ(message("tol-mode", "loose"),
            "--tol-mode: unknown value 'loose' (known: relative, absolute)");
  EXPECT_THROW(experiments::builtin_registry().find("scaled_toy"), Error);
}

// One number syntax for reals and integers, on the command line and in config files: decimal,
// with an optional sign; what strtod reads besides is not a number.
TEST(ExperimentSettings, NumbersAreDecimal) {
  const Experiment& experiment = experiments::builtin_registry().find("scaled-toy");
  const auto read = [&](const std::string& name, const std::string& text) {
    return resolve_settings(experiment, {{name, text}});
  };
  EXPECT_EQ(read("lr", "+0.5").real("lr"), 0.5);
  EXPECT_EQ(read("lr", ".5").real("lr"), 0.5);
  EXPECT_EQ(read("lr", "5.").real("lr"), 5);
  EXPECT_EQ(read("lr", "2.5E-1").real("lr"), 0.25);
  EXPECT_EQ(read("lr", "1e+2").real("lr"), 100);
  EXPECT_EQ(read("iters", "+12").integer("iters"), 12);
  // A list's entries are cut at the commas and the blanks around them dropped; a number alone
  // is its text and nothing around it.
  EXPECT_EQ(read("start", "+1, -0.5e1 ").reals("start"), (std::vector<double>{1, -5}));
  for (const std::string text : {" 12 ", "12 ", " 12", "12\t"}) {
    EXPECT_THROW(read("iters", text), Error) << text;
  }
  EXPECT_THROW(read("lr", " 0.5"), Error);
  for (const std::string text : {"0x10", "0X1P4", "inf", "-Infinity", "nan", "1e", "1e+", ".",
                                 "+", "-.e1", "1.2.3", "١", "1 2", "\n5", "5f", "--5", "+-5"}) {
    EXPECT_THROW(read("lr", text), Error) << text;
    EXPECT_THROW(read("start", "1," + text), Error) << text;
  }
  for (const std::string text : {"0x10", "1e3", "1.0", "12.", ".5", "inf", "+", "1_000"}) {
    EXPECT_THROW(read("iters", text), Error) << text;
  }
}

}  // namespace
}  // namespace physgrad::run
