// Short seeded runs of the physics experiments (iteration limits, never wall-clock): every
// method lowers the loss it starts from, except Gauss-Newton, whose failures (non-finite or
// diverged) are reported.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>

#include "experiment_runs.hpp"

namespace physgrad::run {
namespace {

RunContext run(const std::string& name,
               std::vector<std::pair<std::string, std::string>> given) {
  given.emplace_back("time", "1e6");  // stop on the iteration count only
  const bool seeds = std::any_of(given.begin(), given.end(),
                                 [](const auto& option) { return option.first == "seeds"; });
  if (!seeds) given.emplace_back("seeds", "1");  // one run per rule unless a test asks for more
  return testing::run_experiment(name, given);
}

// Each run's final test loss is below its initial one; returns the number of runs checked.
std::size_t expect_every_run_improves(const RunContext& context) {
  for (const RunEntry& entry : context.runs()) {
    const double initial = entry.initial.test_loss.value();
    const double final_loss = entry.final.test_loss.value();
    EXPECT_TRUE(final_loss < initial) << entry.label;
    EXPECT_EQ(entry.termination, "max_iterations") << entry.label;
  }
  return context.runs().size();
}

TEST(OscillatorsExperiment, BookVariantAdamHigAndSipLowerTheLoss) {
  const RunContext context =
      run("oscillators", {{"variant", "book"}, {"train-size", "256"}, {"test-size", "64"},
                          {"iters", "12"}, {"pretrain", "0"}});
  EXPECT_EQ(expect_every_run_improves(context), 3u);
}

TEST(OscillatorsExperiment, PaperVariantAdamAndHigLowerTheLossGaussNewtonIsReported) {
  const RunContext context =
      run("oscillators", {{"optimizers", "adam,hig"}, {"train-size", "256"}, {"test-size", "64"},
                          {"iters", "12"}, {"pretrain", "0"}});
  EXPECT_EQ(expect_every_run_improves(context), 2u);
  const RunContext gn = run("oscillators", {{"optimizers", "gn"}, {"train-size", "256"},
                                            {"test-size", "64"}, {"iters", "12"}, {"pretrain", "0"}});
  ASSERT_EQ(gn.runs().size(), 1u);
  const std::string end = gn.runs()[0].termination;
  EXPECT_TRUE(end == "max_iterations" || end == "numerical_failure" || end == "diverged") << end;
}

TEST(QuantumDipoleExperiment, AdamAndHigLowerTheInfidelity) {
  const RunContext context = run("quantum-dipole", {{"train-size", "64"}, {"test-size", "32"},
                                                    {"steps", "96"}, {"iters", "10"}});
  EXPECT_EQ(expect_every_run_improves(context), 2u);
}

// The default verdicts compare the rules per update, so the default budgets are updates, not
// seconds a loaded machine would shorten, evaluated densely enough to bracket a crossing (the
// seeds: LearningExperiments.SeedsByDefault).
TEST(LearningExperiments, TheDefaultBudgetsAreUpdatesNotSeconds) {
  struct Budget {
    std::string experiment;
    long long iters, eval_every;
  };
  for (const Budget& b : std::vector<Budget>{{"quantum-dipole", 400, 20},
                                             {"oscillators", 1000, 25},
                                             {"sin-rotation", 20000, 500},
                                             {"poisson", 12, 1}}) {
    const Settings settings =
        resolve_settings(experiments::builtin_registry().find(b.experiment), {});
    EXPECT_EQ(settings.integer("iters"), b.iters) << b.experiment;
    EXPECT_EQ(settings.integer("eval-every"), b.eval_every) << b.experiment;
    EXPECT_FALSE(settings.has("time")) << b.experiment;
  }
}

// Three paired seeds by default where a run takes a minute or two; the 64×64 U-net experiments
// one (a run takes about half an hour); hig-toy five.
TEST(LearningExperiments, SeedsByDefault) {
  const std::vector<std::pair<std::string, long long>> expected = {
      {"hig-toy", 5},      {"sin-rotation", 3}, {"oscillators", 3},  {"quantum-dipole", 3},
      {"poisson", 3},      {"heat-inverse", 1}, {"sip-poisson", 1}};
  for (const auto& [name, seeds] : expected) {
    const Settings settings = resolve_settings(experiments::builtin_registry().find(name), {});
    EXPECT_EQ(settings.integer("seeds"), seeds) << name;
  }
}

TEST(PoissonExperiment, AdamHigAndSipLowerTheLoss) {
  const RunContext context =
      run("poisson", {{"optimizers", "adam,hig,sip"}, {"grid", "4"}, {"train-size", "128"},
                      {"test-size", "32"}, {"iters", "30"}, {"pretrain", "0"}});
  EXPECT_EQ(expect_every_run_improves(context), 3u);
}

// --pretrain 6: next to the HIG run, one that Adam trains for 6 iterations first. Up to the switch
// its metrics are the Adam run's to the bit (both draw the same fresh batches); after it, HIG's
// steps report their inversion; its summary entry names the switch and Adam's settings, and the
// message compares all three runs. Every rule trains at the paper's batch of 64, HIG with the
// paper's step 0.01·B.
TEST(PoissonExperiment, PretrainedRunFollowsTheAdamRunThenInvertsTheJacobian) {
  const RunContext context =
      run("poisson", {{"optimizers", "adam,hig"}, {"grid", "4"}, {"train-size", "128"},
                      {"test-size", "32"}, {"iters", "12"}, {"eval-every", "2"},
                      {"pretrain", "6"}, {"control", "off"}});
  ASSERT_EQ(context.runs().size(), 3u);
  const RunEntry& entry = context.runs()[2];
  EXPECT_EQ(entry.label, "Adam→HIG (4x4)");
  EXPECT_EQ(entry.optimizer, "adam-hig");
  EXPECT_EQ(entry.iterations, 12);
  EXPECT_EQ(entry.params["pretrain_iterations"], 6);
  EXPECT_EQ(entry.params["pretrain_batch"], 64);  // the Adam run's
  EXPECT_EQ(entry.params["pretrain_lr"], context.runs()[0].params["lr"]);
  EXPECT_EQ(entry.params["lr"], context.runs()[1].params["lr"]);  // the HIG run's
  EXPECT_EQ(entry.params["batch"], 64);
  EXPECT_EQ(entry.params["switched"], true);
  EXPECT_DOUBLE_EQ(context.runs()[1].params["lr"].get<double>(), 0.64);

  std::map<long long, const nlohmann::json*> adam;
  for (const nlohmann::json& row : context.metrics()) {
    if (row["optimizer"] == "adam") adam[row["iteration"].get<long long>()] = &row;
  }
  std::size_t before = 0, after = 0;
  for (const nlohmann::json& row : context.metrics()) {
    if (row["optimizer"] != "adam-hig") continue;
    const long long iteration = row["iteration"];
    if (iteration <= 6) {
      ASSERT_TRUE(adam.count(iteration)) << iteration;
      EXPECT_EQ(row["test_loss"], (*adam[iteration])["test_loss"]) << iteration;
      EXPECT_EQ(row["train_loss"], (*adam[iteration])["train_loss"]) << iteration;
      EXPECT_EQ(row["x_l1"], (*adam[iteration])["x_l1"]) << iteration;
      EXPECT_FALSE(row.contains("pinv_path")) << iteration;
      ++before;
    } else {
      EXPECT_FALSE(row.value("pinv_path", "").empty()) << iteration;
      EXPECT_GE(row.value("kept_directions", 0), 1) << iteration;
      ++after;
    }
  }
  EXPECT_EQ(before, 4u);  // iterations 0, 2, 4 and 6
  EXPECT_EQ(after, 3u);   // 8, 10 and 12
  // Each rule named once, after a space (so that "HIG's" is not found in "Adam→HIG's").
  for (const std::string rule : {"Adam", "HIG", "Adam→HIG"}) {
    EXPECT_NE(context.message().find(" " + rule + "'s "), std::string::npos)
        << rule << ": " << context.message();
  }
  EXPECT_EQ(context.message_metric().labels.size(), 3u);
}

}  // namespace
}  // namespace physgrad::run
