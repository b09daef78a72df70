// Short seeded runs of the physics experiments (iteration limits, never wall-clock): every
// method lowers the loss it starts from, except Gauss-Newton, whose failures are reported.
#include <gtest/gtest.h>

#include "experiment_runs.hpp"

namespace physgrad::experiments {
namespace {

RunContext run(const std::string& name,
               std::vector<std::pair<std::string, std::string>> given) {
  given.emplace_back("time", "1e6");  // stop on the iteration count only
  return testing::run_experiment(name, given);
}

// Each run's final test loss is below its initial one; returns the number of runs checked.
std::size_t expect_every_run_improves(const RunContext& context) {
  for (const nlohmann::json& entry : context.runs()) {
    const double initial = entry["initial"]["test_loss"];
    const nlohmann::json& final_loss = entry["final"]["test_loss"];
    EXPECT_TRUE(final_loss.is_number() && final_loss.get<double>() < initial) << entry["label"];
    EXPECT_EQ(entry["termination"], "max_iterations") << entry["label"];
  }
  return context.runs().size();
}

TEST(OscillatorsExperiment, BookVariantAdamHigAndSipLowerTheLoss) {
  const RunContext context = run("oscillators", {{"variant", "book"}, {"train-size", "256"},
                                                 {"test-size", "64"}, {"iters", "12"}});
  EXPECT_EQ(expect_every_run_improves(context), 3u);
}

TEST(OscillatorsExperiment, PaperVariantAdamAndHigLowerTheLossGaussNewtonIsReported) {
  const RunContext context =
      run("oscillators", {{"optimizers", "adam,hig"}, {"train-size", "256"}, {"test-size", "64"},
                          {"iters", "12"}});
  EXPECT_EQ(expect_every_run_improves(context), 2u);
  const RunContext gn = run("oscillators", {{"optimizers", "gn"}, {"train-size", "256"},
                                            {"test-size", "64"}, {"iters", "12"}});
  ASSERT_EQ(gn.runs().size(), 1u);
  const std::string end = gn.runs()[0]["termination"];
  EXPECT_TRUE(end == "max_iterations" || end == "numerical_failure") << end;
}

TEST(QuantumDipoleExperiment, AdamAndHigLowerTheInfidelity) {
  const RunContext context = run("quantum-dipole", {{"train-size", "64"}, {"test-size", "32"},
                                                    {"steps", "96"}, {"iters", "10"}});
  EXPECT_EQ(expect_every_run_improves(context), 2u);
}

TEST(PoissonExperiment, AdamHigAndSipLowerTheLoss) {
  const RunContext context =
      run("poisson", {{"optimizers", "adam,hig,sip"}, {"grid", "4"}, {"train-size", "128"},
                      {"test-size", "32"}, {"iters", "30"}});
  EXPECT_EQ(expect_every_run_improves(context), 3u);
}

}  // namespace
}  // namespace physgrad::experiments
