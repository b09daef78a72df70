// A twin's two parts with their own options (--pretrain-lr, … for the Adam part; --lr for the rule
// after it), the control arm Adam→Adam switched where the twins switch, and each part's cost per
// update; the verdict sets each twin against the control.
#include <gtest/gtest.h>

#include <map>

#include "cli_fixture.hpp"
#include "experiment_runs.hpp"
#include "physgrad/run/cases/learning_runs.hpp"
#include "physgrad/run/pages/learning_verdict.hpp"

namespace physgrad::run {
namespace {

RunContext run_poisson(std::vector<std::pair<std::string, std::string>> given) {
  for (auto option : std::vector<std::pair<std::string, std::string>>{
           {"grid", "4"}, {"train-size", "128"}, {"test-size", "32"}, {"eval-every", "2"},
           {"time", "1e6"}, {"seeds", "1"}}) {
    given.push_back(std::move(option));
  }
  return testing::run_experiment("poisson", given);
}

const RunEntry& entry_of(const RunContext& context, const std::string& optimizer) {
  for (const RunEntry& entry : context.runs()) {
    if (entry.optimizer == optimizer) return entry;
  }
  throw Error("no run " + optimizer);
}

// Each evaluation of run `optimizer`: iteration → its row of metrics.csv.
std::map<long long, nlohmann::json> rows_of(const RunContext& context,
                                            const std::string& optimizer) {
  std::map<long long, nlohmann::json> rows;
  for (const nlohmann::json& row : context.metrics()) {
    if (row["optimizer"] == optimizer) rows[row["iteration"].get<long long>()] = row;
  }
  return rows;
}

// Whether two rows hold the same losses and fields to the bit.
bool same_figures(const nlohmann::json& a, const nlohmann::json& b) {
  return a["train_loss"] == b["train_loss"] && a["test_loss"] == b["test_loss"] &&
         a["x_l1"] == b["x_l1"];
}

// --lr 0.05 reaches Adam's run, HIG's and the rule of the twin; --pretrain-lr 0.002 the twin's Adam
// part alone, which then follows an Adam run at lr 0.002 to the bit up to the switch and leaves the
// Adam run at 0.05 from its first update.
TEST(PretrainPhases, PretrainLrSetsTheAdamPartAndLrTheRuleAfterIt) {
  const RunContext context =
      run_poisson({{"optimizers", "adam,hig"}, {"iters", "12"}, {"pretrain", "6"},
                   {"lr", "0.05"}, {"pretrain-lr", "0.002"}, {"control", "off"}});
  ASSERT_EQ(context.runs().size(), 3u);
  const RunEntry& twin = entry_of(context, "adam-hig");
  EXPECT_DOUBLE_EQ(entry_of(context, "adam").params["lr"].get<double>(), 0.05);
  EXPECT_DOUBLE_EQ(entry_of(context, "hig").params["lr"].get<double>(), 0.05);
  EXPECT_DOUBLE_EQ(twin.params["lr"].get<double>(), 0.05);
  EXPECT_DOUBLE_EQ(twin.params["pretrain_lr"].get<double>(), 0.002);
  EXPECT_EQ(twin.params["pretrain_iterations"], 6);

  const RunContext slow =
      run_poisson({{"optimizers", "adam"}, {"iters", "6"}, {"lr", "0.002"}, {"pretrain", "0"}});
  const auto twin_rows = rows_of(context, "adam-hig");
  const auto slow_rows = rows_of(slow, "adam");
  const auto fast_rows = rows_of(context, "adam");
  for (const long long iteration : {0, 2, 4, 6}) {
    ASSERT_TRUE(twin_rows.count(iteration) && slow_rows.count(iteration)) << iteration;
    EXPECT_TRUE(same_figures(twin_rows.at(iteration), slow_rows.at(iteration))) << iteration;
  }
  EXPECT_FALSE(same_figures(twin_rows.at(2), fast_rows.at(2)));
}

// Beside the twin, the control: the same Adam part (to the bit, the Adam run's), switched where
// the twin switches on the same plateau, then a fresh Adam at a tenth of the step; both runs'
// cost is recorded per part, and the verdict sets the twin against the control.
TEST(PretrainPhases, TheControlSwitchesWithTheTwinAndFollowsAdamUntilThen) {
  const RunContext context =
      run_poisson({{"optimizers", "adam,hig"}, {"iters", "16"}, {"pretrain", "auto"},
                   {"plateau-window", "1"}, {"plateau-fraction", "0.5"}});
  ASSERT_EQ(context.runs().size(), 4u);
  const RunEntry& twin = entry_of(context, "adam-hig");
  const RunEntry& control = context.runs()[3];
  EXPECT_EQ(control.optimizer, "adam-adam");
  EXPECT_EQ(control.label, "Adam→Adam (lr ×0.1; 4x4)");
  ASSERT_EQ(twin.params["switched"], true);
  ASSERT_EQ(control.params["switched"], true);
  const long long at = control.params["pretrain_iterations"].get<long long>();
  EXPECT_EQ(at, twin.params["pretrain_iterations"].get<long long>());
  EXPECT_GT(at, 0);
  EXPECT_LT(at, 16);
  EXPECT_DOUBLE_EQ(control.params["lr"].get<double>(),
                   0.1 * control.params["pretrain_lr"].get<double>());
  EXPECT_EQ(control.params["pretrain_lr"], entry_of(context, "adam").params["lr"]);

  const auto adam = rows_of(context, "adam");
  std::size_t before = 0, after_differing = 0;
  for (const auto& [iteration, row] : rows_of(context, "adam-adam")) {
    ASSERT_TRUE(adam.count(iteration)) << iteration;
    if (iteration <= at) {
      EXPECT_TRUE(same_figures(row, adam.at(iteration))) << iteration;
      ++before;
    } else {
      after_differing += !same_figures(row, adam.at(iteration));
    }
  }
  EXPECT_GE(before, 2u);
  EXPECT_GE(after_differing, 1u);

  // Each part's updates and seconds, which add up to the run's.
  for (const RunEntry* run : {&twin, &control}) {
    const nlohmann::json& phases = run->more.at("phases");
    ASSERT_EQ(phases.size(), 2u) << run->label;
    EXPECT_EQ(phases[0]["rule"], "adam");
    EXPECT_EQ(phases[1]["rule"], run == &twin ? "hig" : "adam");
    EXPECT_EQ(phases[0]["updates"], at);
    EXPECT_EQ(phases[1]["updates"], 16 - at);
    EXPECT_NEAR(phases[0]["train_seconds"].get<double>() +
                    phases[1]["train_seconds"].get<double>(),
                run->wall_seconds, 1e-9 * run->wall_seconds);
    EXPECT_DOUBLE_EQ(phases[1]["seconds_per_update"].get<double>(),
                     phases[1]["train_seconds"].get<double>() / static_cast<double>(16 - at));
  }
  EXPECT_FALSE(entry_of(context, "adam").more.contains("phases"));
  EXPECT_NE(context.message().find("Adam→HIG ends "), std::string::npos) << context.message();
  EXPECT_NE(context.message().find(" the control Adam→Adam (lr ×0.1) ("), std::string::npos)
      << context.message();
}

// The control's step follows --control-lr-factor; --control off or a factor of 0 leave it out, and
// without a twin there is none.
TEST(PretrainPhases, TheControlFollowsItsFactorAndIsOffWhenAsked) {
  const RunContext half = run_poisson({{"optimizers", "adam,hig"}, {"iters", "8"},
                                       {"pretrain", "4"}, {"control-lr-factor", "0.5"},
                                       {"pretrain-lr", "0.004"}});
  const RunEntry& control = entry_of(half, "adam-adam");
  EXPECT_EQ(control.label, "Adam→Adam (lr ×0.5; 4x4)");
  EXPECT_DOUBLE_EQ(control.params["lr"].get<double>(), 0.002);
  EXPECT_DOUBLE_EQ(control.params["pretrain_lr"].get<double>(), 0.004);
  EXPECT_EQ(control.params["control_lr_factor"], 0.5);
  for (const auto& off : std::vector<std::pair<std::string, std::string>>{
           {"control", "off"}, {"control-lr-factor", "0"}}) {
    const RunContext context =
        run_poisson({{"optimizers", "adam,hig"}, {"iters", "8"}, {"pretrain", "4"}, off});
    EXPECT_EQ(context.runs().size(), 3u) << off.first;
  }
  const RunContext no_twin =
      run_poisson({{"optimizers", "adam,sip"}, {"iters", "8"}, {"pretrain", "4"}});
  EXPECT_EQ(no_twin.runs().size(), 2u);
}

// --alone off: a rule with a twin runs only as its twin (with the control beside it); rules without
// a twin and Adam still run; without --pretrain the flag is refused, as the other twin options.
TEST(PretrainPhases, AloneOffRunsTheTwinInsteadOfTheRule) {
  const auto optimizers_of = [](const RunContext& context) {
    std::vector<std::string> ids;
    for (const RunEntry& entry : context.runs()) ids.push_back(entry.optimizer);
    return ids;
  };
  const RunContext twins = run_poisson({{"optimizers", "adam,hig,sip"}, {"iters", "8"},
                                        {"pretrain", "4"}, {"alone", "off"}});
  EXPECT_EQ(optimizers_of(twins),
            (std::vector<std::string>{"adam", "adam-hig", "sip", "adam-adam"}));
  EXPECT_EQ(entry_of(twins, "adam-hig").params["pretrain_iterations"], 4);
  try {
    run_poisson({{"optimizers", "adam,hig"}, {"iters", "4"}, {"pretrain", "0"}, {"alone", "off"}});
    ADD_FAILURE() << "--alone off without --pretrain was accepted";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("--alone"), std::string::npos) << error.what();
  }
}

// A twin's cost per part: Adam's updates up to the evaluation at the switch, the rule's after it.
TEST(PretrainPhases, PhaseCostsSplitATwinAtItsSwitch) {
  LearningResult twin;
  twin.id = "adam-hig";
  for (const auto& [iteration, seconds] :
       std::vector<std::pair<long long, double>>{{0, 0}, {4, 0.04}, {6, 0.06}, {12, 1.26}}) {
    TrainingRecord record;
    record.iteration = iteration;
    record.train_seconds = seconds;
    twin.summary.history.push_back(record);
  }
  twin.summary.iterations = 12;
  twin.summary.train_seconds = 1.26;
  twin.params = {{"switched", true}, {"pretrain_iterations", 6}};
  const std::vector<PhaseCost> parts = phase_costs(twin);
  ASSERT_EQ(parts.size(), 2u);
  EXPECT_EQ(parts[0].rule, "adam");
  EXPECT_EQ(parts[0].updates, 6);
  EXPECT_DOUBLE_EQ(parts[0].seconds_per_update(), 0.01);
  EXPECT_EQ(parts[1].rule, "hig");
  EXPECT_EQ(parts[1].updates, 6);
  EXPECT_DOUBLE_EQ(parts[1].seconds_per_update(), 0.2);

  twin.params = {{"switched", false}};
  ASSERT_EQ(phase_costs(twin).size(), 1u);
  EXPECT_EQ(phase_costs(twin)[0].updates, 12);
  twin.id = "hig";
  twin.params = nlohmann::json::object();
  EXPECT_TRUE(phase_costs(twin).empty());
}

// A run whose test loss at iteration k·10 is `losses[k]`, at 1 ms an update.
LearningResult phases_run(const std::string& id, const std::vector<double>& losses,
                          nlohmann::json params = nlohmann::json::object()) {
  LearningResult r;
  r.id = id;
  r.params = std::move(params);
  for (std::size_t k = 0; k < losses.size(); ++k) {
    TrainingRecord record;
    record.iteration = static_cast<long long>(k) * 10;
    record.train_seconds = static_cast<double>(record.iteration) * 1e-3;
    record.train_loss = record.test_loss = losses[k];
    r.summary.history.push_back(record);
  }
  r.summary.iterations = r.summary.history.back().iteration;
  r.summary.train_seconds = r.summary.history.back().train_seconds;
  r.summary.termination = TrainingTermination::kMaxIterations;
  return r;
}

// Each switched twin against the switched control, below or above it, with two digits for one
// seed; a control that never switched is not compared with.
TEST(PretrainPhases, TheVerdictSetsEachTwinAgainstTheControl) {
  const auto loss = [](const TrainingRecord& r) { return r.test_loss; };
  const nlohmann::json switched = {{"switched", true}, {"pretrain_iterations", 10}};
  nlohmann::json control_params = switched;
  control_params["control_lr_factor"] = 0.1;
  const LearningResult adam = phases_run("adam", {1.0, 0.5, 0.2});
  const LearningResult hig = phases_run("adam-hig", {1.0, 0.5, 0.05}, switched);
  const LearningResult gn = phases_run("adam-gn", {1.0, 0.5, 0.3}, switched);
  const LearningResult control = phases_run("adam-adam", {1.0, 0.5, 0.1}, control_params);
  const std::string sentence =
      verdict_sentence({{{&adam}, {&hig}, {&gn}, {&control}}, loss, "final test loss"});
  EXPECT_NE(sentence.find("After the same switch, Adam→HIG ends 2× below the control "
                          "Adam→Adam (lr ×0.1) (0.05 vs 0.1); Adam→Gauss-Newton ends 3.0× above "
                          "the control Adam→Adam (lr ×0.1) (0.3 vs 0.1)."),
            std::string::npos)
      << sentence;
  // The control is ranked as a twin is: second here.
  EXPECT_NE(sentence.find("Adam→HIG's final test loss is 2× below Adam→Adam (lr ×0.1)'s"),
            std::string::npos)
      << sentence;

  LearningResult unswitched = control;
  unswitched.params = {{"switched", false}, {"control_lr_factor", 0.1}};
  const std::string without =
      verdict_sentence({{{&adam}, {&hig}, {&unswitched}}, loss, "final test loss"});
  EXPECT_EQ(without.find("After the same switch"), std::string::npos) << without;
}

class PretrainPhasesCli : public physgrad::testing::Cli {};

// The Adam part's options are Adam's own, each with a one-line error naming it; they need twins.
TEST_F(PretrainPhasesCli, BadValuesAreOneLineErrorsNamingTheOption) {
  expect_rejected("run poisson --pretrain-lr -1", "--pretrain-lr");
  expect_rejected("run poisson --pretrain-lr 0", "--pretrain-lr: ");
  expect_rejected("run poisson --pretrain-beta1 1", "--pretrain-beta1");
  expect_rejected("run poisson --pretrain-schedule weekly", "'weekly'");
  expect_rejected("run poisson --control maybe", "'maybe'");
  expect_rejected("run poisson --control-lr-factor 2", "--control-lr-factor");
  expect_rejected("run hig-toy --iters 10 --pretrain-lr 0.01",
                  "--pretrain-lr: 0.01 is for the Adam→ twins, which need --pretrain auto or N");
  const physgrad::testing::Outcome described = run("describe poisson");
  ASSERT_EQ(described.exit_code, 0) << described.err;
  EXPECT_NE(described.out.find("pretrain-lr"), std::string::npos);
  EXPECT_NE(described.out.find("pretrain-decay-every"), std::string::npos);
  EXPECT_NE(described.out.find("the Adam part of the Adam→ twins too unless --pretrain-lr is "
                               "given"),
            std::string::npos)
      << described.out;
}

}  // namespace
}  // namespace physgrad::run
