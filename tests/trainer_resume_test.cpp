// Training resumed from a checkpoint is bit-identical to an uninterrupted run: for every rule, for
// a rule that switches from Adam (after N updates or on a plateau, interrupted before, at and after
// the switch) and with fresh samples drawn for every batch.
#include <gtest/gtest.h>

#include <atomic>
#include <functional>
#include <memory>

#include "learning_fixture.hpp"
#include "physgrad/learn/switching.hpp"

namespace physgrad {
namespace {

using testing::NetworkThroughPhysics;
using testing::test_settings;
using MakeRule = std::function<std::unique_ptr<LearningUpdate>()>;

// Interrupts a run when the evaluation after `stop_after` iterations is recorded, continues it in
// a fresh network and rule from the JSON of its last checkpoint and returns the continuation's
// summary, with its final θ in `final_theta`.
TrainingSummary interrupt_and_resume(const MakeRule& make, const TrainerOptions& base,
                                     long long stop_after, Vector& final_theta) {
  NetworkThroughPhysics s(30);
  std::atomic<bool> stop{false};
  std::string saved;
  TrainerOptions options = base;
  options.stop = &stop;
  options.checkpoint_every = 3;
  options.on_checkpoint = [&saved](const TrainerState& state) {
    saved = trainer_state_to_json(state).dump();
  };
  options.on_progress = [&](const TrainingRecord& r) {
    if (r.iteration >= stop_after) stop = true;
  };
  const auto first = make();
  const TrainingSummary interrupted = train(s.network, *first, s.problem, s.data, &s.data, options);
  EXPECT_EQ(interrupted.termination, TrainingTermination::kInterrupted);

  NetworkThroughPhysics t(30);
  const TrainerState state =
      trainer_state_from_json(nlohmann::json::parse(saved), t.network.num_parameters());
  EXPECT_EQ(state.summary.iterations, interrupted.iterations);
  TrainerOptions resumed = base;
  resumed.resume = &state;
  const auto second = make();
  const TrainingSummary summary = train(t.network, *second, t.problem, t.data, &t.data, resumed);
  final_theta = t.network.parameters();
  return summary;
}

// The uninterrupted run of `make` under `options`, and its resumed twins interrupted after each
// of `stops`: the same termination, θ to the bit and every record.
void expect_resumes_exactly(const MakeRule& make, const TrainerOptions& options,
                            const std::vector<long long>& stops, const std::string& what) {
  NetworkThroughPhysics s(30);
  const auto update = make();
  const TrainingSummary whole = train(s.network, *update, s.problem, s.data, &s.data, options);
  for (const long long stop_after : stops) {
    Vector theta;
    const TrainingSummary resumed = interrupt_and_resume(make, options, stop_after, theta);
    const std::string where = what + ", stopped after " + std::to_string(stop_after);
    EXPECT_EQ(resumed.termination, whole.termination) << where;
    EXPECT_EQ(resumed.iterations, whole.iterations) << where;
    EXPECT_TRUE(theta == s.network.parameters()) << where;  // every bit
    ASSERT_EQ(resumed.phases.size(), whole.phases.size()) << where;
    for (std::size_t p = 0; p < whole.phases.size(); ++p) {
      EXPECT_EQ(resumed.phases[p].first_iteration, whole.phases[p].first_iteration) << where;
    }
    ASSERT_EQ(resumed.history.size(), whole.history.size()) << where;
    for (std::size_t k = 0; k < whole.history.size(); ++k) {
      EXPECT_EQ(resumed.history[k].iteration, whole.history[k].iteration) << where;
      EXPECT_EQ(resumed.history[k].train_loss, whole.history[k].train_loss) << where << " " << k;
      EXPECT_EQ(resumed.history[k].test_loss, whole.history[k].test_loss) << where << " " << k;
      EXPECT_EQ(resumed.history[k].step, whole.history[k].step) << where << " " << k;
    }
  }
}

TEST(TrainerResume, ResumedRunIsBitIdenticalToAnUninterruptedOne) {
  TrainerOptions by_iterations;  // 30 samples in batches of 8: epochs end mid-way
  by_iterations.batch_size = 8;
  by_iterations.max_iterations = 25;
  by_iterations.eval_every = 4;
  TrainerOptions by_epochs;  // evaluated once per epoch
  by_epochs.batch_size = 8;
  by_epochs.max_epochs = 6;
  for (const TrainerOptions& options : {by_iterations, by_epochs}) {
    for (const std::string& id : rule_ids(RuleKind::kLearning)) {
      expect_resumes_exactly([id] { return make_learning_update(id, test_settings(id)); }, options,
                             {9}, id);
    }
  }
}

// Adam in batches of 8, then the rule in batches of 4 after 7 updates (mid-epoch) or on a plateau
// of the evaluated loss, interrupted in Adam's part, at the switch and after it.
TEST(TrainerResume, ResumedSwitchingRunIsBitIdentical) {
  TrainerOptions options;
  options.batch_size = 4;
  options.max_iterations = 25;
  options.eval_every = 2;
  for (const std::string id : {"gn", "hig"}) {
    for (const SwitchCondition condition :
         {SwitchCondition{.after = 7}, SwitchCondition{.window = 2, .fraction = 0.5}}) {
      const MakeRule make = [id, condition] {
        return std::make_unique<SwitchingUpdate>(make_learning_update("adam"), 8,
                                                 make_learning_update(id, test_settings(id)), 4,
                                                 condition);
      };
      NetworkThroughPhysics probe(30);
      const auto rule = make();
      const TrainingSummary whole =
          train(probe.network, *rule, probe.problem, probe.data, &probe.data, options);
      ASSERT_EQ(whole.phases.size(), 2u) << id << " " << condition.text();
      const long long at = whole.phases[1].first_iteration;
      expect_resumes_exactly(make, options, {at / 2, at, at + 4},
                             std::string(id) + " " + condition.text());
    }
  }
}

TEST(TrainerResume, ResumedRunOnFreshSamplesIsBitIdentical) {
  const NetworkThroughPhysics source;
  TrainerOptions options;
  options.batch_size = 8;
  options.max_iterations = 20;
  options.eval_every = 4;
  options.fresh_samples = [&source](std::uint64_t stream, Index count) {
    return source.draw(stream, count);
  };
  for (const std::string id : {"adam", "hig"}) {
    expect_resumes_exactly([id] { return make_learning_update(id, test_settings(id)); }, options,
                           {6, 13}, std::string(id) + " on fresh samples");
  }
}

}  // namespace
}  // namespace physgrad
