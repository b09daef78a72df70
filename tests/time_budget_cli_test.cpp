// `--time` bounds a learning run's wall time end to end: evaluated and checkpointed after every
// step, a run of hig-toy ends within its budget plus a margin, where it used to spend minutes
// on evaluations and ever-growing checkpoints beyond a budget counted in training time.
#include <gtest/gtest.h>

#include <chrono>
#include <nlohmann/json.hpp>

#include "cli_fixture.hpp"

namespace {

using physgrad::testing::Cli;
using physgrad::testing::read_file;
using Clock = std::chrono::steady_clock;

class TimeBudget : public Cli {
 protected:
  // Runs hig-toy's Adam with `options` and a 1-second budget; returns the command's wall time
  // and checks that the run ended by its budget with its run_seconds within `run_bound`.
  double run_for_a_second(const std::string& options, double run_bound) {
    const auto start = Clock::now();
    const physgrad::testing::Outcome outcome =
        run("run hig-toy --seeds 1 --lambda 1 --optimizers adam --iters 1000000 --time 1 " +
            options + " --out result");
    const double wall = std::chrono::duration<double>(Clock::now() - start).count();
    EXPECT_EQ(outcome.exit_code, 0) << outcome.err;
    const nlohmann::json summary =
        nlohmann::json::parse(read_file(dir_ / "result" / "summary.json"));
    const nlohmann::json& run = summary.at("runs").at(0);
    EXPECT_EQ(run.at("termination"), "time_budget") << run.dump();
    EXPECT_GE(run.at("iterations").get<long long>(), 1);
    EXPECT_LT(run.at("run_seconds").get<double>(), run_bound) << run.dump();
    EXPECT_LE(run.at("wall_seconds").get<double>(), run.at("run_seconds").get<double>());
    return wall;
  }
};

// Before: 448 s of wall time for 1 s of training (2816 checkpoints of a growing history).
TEST_F(TimeBudget, CheckpointsAndEvaluationsAfterEveryStepStayWithinTheBudget) {
  const double wall = run_for_a_second("--eval-every 1 --checkpoint-every 1", 1.5);
  // Set-up and the report come on top of the run's second; 6 s leaves room for a loaded machine.
  EXPECT_LT(wall, 6.0);
}

// Before: 10.3 s of wall time (4140 evaluations besides the 1 s of training).
TEST_F(TimeBudget, EvaluationsAfterEveryStepStayWithinTheBudget) {
  const double wall = run_for_a_second("--eval-every 1", 1.5);
  EXPECT_LT(wall, 6.0);
}

}  // namespace
