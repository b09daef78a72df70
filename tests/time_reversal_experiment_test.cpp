// The time-reversal experiment: PG through the reversal reaches the true initial state in one
// step on the reversible FPU chain and in a few on the RK4 oscillators, with fewer simulator
// passes than PG through a numerical inverse; every run and figure is recorded.
#include <gtest/gtest.h>

#include "experiment_runs.hpp"
#include "physgrad/error.hpp"

namespace physgrad::run {
namespace {

using testing::run_experiment;

const RunEntry& find_run(const RunContext& context, const std::string& problem,
                               const std::string& optimizer, const std::string& inverse = "") {
  for (const RunEntry& entry : context.runs()) {
    if (entry.params["problem"] == problem && entry.optimizer == optimizer &&
        (inverse.empty() || entry.params["inverse"] == inverse)) {
      return entry;
    }
  }
  throw Error("no run " + problem + " " + optimizer + " " + inverse);
}

// The simulator passes of a run: its last metrics row.
long long passes(const RunContext& context, const RunEntry& run,
                 const std::string& problem) {
  long long last = -1;
  for (const nlohmann::json& row : context.metrics()) {
    if (row["problem"] == problem && row["label"] == run.label) {
      last = row["simulator_passes"].get<long long>();
    }
  }
  return last;
}

TEST(TimeReversalExperiment, ReversalPgBeatsTheNumericalInverseInSimulatorPasses) {
  const RunContext context = run_experiment(
      "time-reversal", {{"optimizers", "pg,gn,gd"}, {"pg-inverse", "time_reversal,lbfgs"},
                        {"fpu-steps", "50"}, {"osc-steps", "48"}, {"iters", "60"}});
  const RunEntry& fpu = find_run(context, "fpu", "pg", "time_reversal");
  EXPECT_EQ(fpu.termination, "converged");
  EXPECT_EQ(fpu.iterations, 1);  // an exact inverse: one full PG step
  const RunEntry& osc = find_run(context, "oscillators", "pg", "time_reversal");
  EXPECT_EQ(osc.termination, "converged");
  EXPECT_GT(osc.iterations, 1);  // RK4's reversal is inexact
  EXPECT_LE(osc.iterations, 10);
  for (const std::string problem : {"fpu", "oscillators"}) {
    const RunEntry& reversal = find_run(context, problem, "pg", "time_reversal");
    const RunEntry& numerical = find_run(context, problem, "pg", "lbfgs");
    EXPECT_EQ(numerical.termination, "converged") << problem;
    EXPECT_LT(4 * passes(context, reversal, problem), passes(context, numerical, problem))
        << problem;
    EXPECT_NE(find_run(context, problem, "gd").termination, "converged") << problem;
  }
  EXPECT_EQ(context.runs().size(), 8u);
  EXPECT_EQ(context.figures().size(), 6u);  // loss vs iteration, passes and time per problem
  EXPECT_EQ(context.tables().size(), 1u);
}

}  // namespace
}  // namespace physgrad::run
