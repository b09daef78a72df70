// The time budget bounds a run's wall time: steps, evaluations and checkpoints count against it,
// a step whose measured cost would overrun it is not started, and a run limited by time keeps
// its checkpoints to a tenth of its wall time.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <limits>
#include <memory>
#include <string>
#include <thread>

#include "learning_fixture.hpp"
#include "physgrad/catalogue.hpp"
#include "physgrad/error.hpp"
#include "physgrad/timing.hpp"
#include "physgrad/train/trainer.hpp"

namespace physgrad {
namespace {

using testing::AdamWithDelay;
using testing::NetworkThroughPhysics;
using Clock = std::chrono::steady_clock;

// A budget of 1 s and steps of at least 0.6 s: the second step would end past the budget, so
// it is not started, and the termination says why.
TEST(TrainerTime, AStepThatCannotFitInTheBudgetIsNotStarted) {
  NetworkThroughPhysics s(8);
  AdamWithDelay rule(
      [](long long) { std::this_thread::sleep_for(std::chrono::milliseconds(600)); });
  TrainerOptions options;
  options.batch_size = 4;
  options.time_budget_seconds = 1.0;
  const auto start = Clock::now();
  const TrainingSummary summary = train(s.network, rule, s.problem, s.data, &s.data, options);
  const double wall = seconds_since(start);
  EXPECT_EQ(summary.iterations, 1);
  ASSERT_TRUE(summary.termination.has_value());
  EXPECT_EQ(*summary.termination, TrainingTermination::kTimeBudget) << summary.message;
  EXPECT_NE(summary.message.find("time limit: next step would overrun"), std::string::npos)
      << summary.message;
  EXPECT_LT(wall, 1.0);
  EXPECT_LE(summary.wall_seconds, wall);
  EXPECT_GE(summary.wall_seconds, summary.train_seconds);
}

// Evaluations of 20 ms after every step of a few microseconds: the run still ends within its
// 0.5 s budget plus one step and one evaluation (given a second here), instead of spending the
// budget on steps alone while the evaluations run on (stopped after 200 of them, 4 s).
TEST(TrainerTime, EvaluationsCountAgainstTheBudget) {
  NetworkThroughPhysics s(8);
  const auto adam = make_learning_update("adam");
  std::atomic<bool> stop{false};
  int evaluations = 0;
  TrainerOptions options;
  options.batch_size = 4;
  options.time_budget_seconds = 0.5;
  options.eval_every = 1;
  options.stop = &stop;
  options.on_evaluate = [](const Network&, TrainingRecord&) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  };
  options.on_progress = [&](const TrainingRecord&) {
    if (++evaluations >= 200) stop = true;
  };
  const auto start = Clock::now();
  const TrainingSummary summary = train(s.network, *adam, s.problem, s.data, &s.data, options);
  const double wall = seconds_since(start);
  ASSERT_TRUE(summary.termination.has_value());
  EXPECT_EQ(*summary.termination, TrainingTermination::kTimeBudget) << summary.message;
  EXPECT_LT(wall, 1.5);
  EXPECT_GE(summary.iterations, 1);
  EXPECT_GE(summary.wall_seconds, 0.5 - 0.1);  // the budget was used, not given up early
}

// Checkpoints of 20 ms asked for after every step of a few microseconds in a run of 1 s: they
// take at most about a tenth of the run (a fifth allowed for a loaded machine) instead of all
// of it (stopped after 100 of them).
TEST(TrainerTime, CheckpointsOfARunLimitedByTimeTakeATenthOfIt) {
  NetworkThroughPhysics s(8);
  const auto adam = make_learning_update("adam");
  std::atomic<bool> stop{false};
  int checkpoints = 0;
  double checkpoint_seconds = 0;
  TrainerOptions options;
  options.batch_size = 4;
  options.time_budget_seconds = 1.0;
  options.checkpoint_every = 1;
  options.stop = &stop;
  options.on_checkpoint = [&](const TrainerState&) {
    const auto begin = Clock::now();
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    checkpoint_seconds += seconds_since(begin);
    if (++checkpoints >= 100) stop = true;
  };
  const auto start = Clock::now();
  const TrainingSummary summary = train(s.network, *adam, s.problem, s.data, &s.data, options);
  const double wall = seconds_since(start);
  ASSERT_TRUE(summary.termination.has_value());
  EXPECT_EQ(*summary.termination, TrainingTermination::kTimeBudget) << summary.message;
  EXPECT_GE(checkpoints, 2);
  EXPECT_LT(checkpoint_seconds, 0.2 * wall) << checkpoints << " checkpoints";
  EXPECT_LT(wall, 2.0);
  EXPECT_GT(summary.iterations, checkpoints);
}

// The run's wall time is kept in the state and goes on after a resume: a run resumed from a
// state that has spent its budget makes no further step.
TEST(TrainerTime, AResumedRunCountsTheWallTimeBeforeTheInterruption) {
  NetworkThroughPhysics s(8);
  const auto adam = make_learning_update("adam");
  TrainerState saved;
  TrainerOptions options;
  options.batch_size = 4;
  options.max_iterations = 3;
  options.checkpoint_every = 3;
  options.on_checkpoint = [&saved](const TrainerState& state) { saved = state; };
  options.on_evaluate = [](const Network&, TrainingRecord&) {
    std::this_thread::sleep_for(std::chrono::milliseconds(30));
  };
  options.eval_every = 1;
  train(s.network, *adam, s.problem, s.data, &s.data, options);
  ASSERT_EQ(saved.summary.iterations, 3);
  // Four evaluations of 30 ms: training time is a small part of the run's wall time.
  EXPECT_GE(saved.summary.wall_seconds, 0.09);
  EXPECT_LT(saved.summary.train_seconds, saved.summary.wall_seconds);
  const TrainerState state =
      trainer_state_from_json(trainer_state_to_json(saved), s.network.num_parameters());
  EXPECT_EQ(state.summary.wall_seconds, saved.summary.wall_seconds);

  NetworkThroughPhysics t(8);
  const auto again = make_learning_update("adam");
  TrainerOptions resumed;
  resumed.batch_size = 4;
  resumed.time_budget_seconds = 0.09;
  resumed.resume = &state;
  const TrainingSummary summary = train(t.network, *again, t.problem, t.data, &t.data, resumed);
  EXPECT_EQ(summary.iterations, 3);
  EXPECT_EQ(*summary.termination, TrainingTermination::kTimeBudget);
  EXPECT_GE(summary.wall_seconds, state.summary.wall_seconds);
}

TEST(TrainerTime, StateFromJsonRejectsABadWallTime) {
  NetworkThroughPhysics s(8);
  const auto adam = make_learning_update("adam");
  nlohmann::json saved;
  TrainerOptions options;
  options.batch_size = 4;
  options.max_iterations = 2;
  options.checkpoint_every = 2;
  options.on_checkpoint = [&saved](const TrainerState& state) {
    saved = trainer_state_to_json(state);
  };
  train(s.network, *adam, s.problem, s.data, nullptr, options);
  const Index count = s.network.num_parameters();
  const double inf = std::numeric_limits<double>::infinity();
  for (const nlohmann::json& bad : {nlohmann::json(-1.0), nlohmann::json("x"),
                                    nlohmann::json(nullptr), nlohmann::json(inf)}) {
    nlohmann::json document = saved;
    document["summary"]["wall_seconds"] = bad;
    EXPECT_THROW(trainer_state_from_json(document, count), Error) << bad.dump();
  }
  // A state of an earlier version has none: its training time stands for it.
  saved["summary"].erase("wall_seconds");
  EXPECT_EQ(trainer_state_from_json(saved, count).summary.wall_seconds,
            trainer_state_from_json(saved, count).summary.train_seconds);
}

}  // namespace
}  // namespace physgrad
