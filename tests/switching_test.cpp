// A rule made of two rules in turn (SwitchingUpdate, the HIG paper's Adam→HIG): the switch after N
// updates or on a plateau of the evaluated loss, what the trainer does at the switch, and what it
// refuses.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "learning_fixture.hpp"
#include "physgrad/error.hpp"
#include "physgrad/learn/switching.hpp"

namespace physgrad {
namespace {

using testing::NetworkThroughPhysics;
using testing::test_settings;

std::unique_ptr<SwitchingUpdate> adam_then(const std::string& id, Index adam_batch, Index batch,
                                           SwitchCondition condition) {
  return std::make_unique<SwitchingUpdate>(make_learning_update("adam"), adam_batch,
                                           make_learning_update(id, test_settings(id)), batch,
                                           condition);
}

TEST(Switching, APlateauSwitchesAndAFallingCurveDoesNot) {
  const SwitchCondition condition{.window = 3, .fraction = 0.05};
  std::vector<double> falling, flat;
  for (int k = 0; k < 40; ++k) {
    falling.push_back(1.0 / (1 + k));  // falls by ≥ 5 % over any 3 evaluations
    flat.push_back(k < 10 ? 1.0 / (1 + k) : 0.1 * (1 - 1e-3 * (k - 10)));
    EXPECT_FALSE(levelled_off(falling, condition)) << k;
  }
  // Flat from evaluation 10: levelled off once three evaluations have gained less than 5 %.
  std::vector<double> seen;
  int first = -1;
  for (std::size_t k = 0; k < flat.size() && first < 0; ++k) {
    seen.push_back(flat[k]);
    if (levelled_off(seen, condition)) first = static_cast<int>(k);
  }
  EXPECT_EQ(first, 12);
  // Too few evaluations to judge, a rise counts as no gain, and a fixed switch never judges.
  EXPECT_FALSE(levelled_off({1.0, 1.0, 1.0}, condition));
  EXPECT_TRUE(levelled_off({1.0, 1.0, 2.0, 3.0}, condition));
  EXPECT_FALSE(levelled_off({1.0, 1.0, 1.0, 1.0, 1.0}, SwitchCondition{.after = 5}));
}

TEST(Switching, TheRuleSwitchesOnTheEvaluationsItObserves) {
  auto rule = adam_then("hig", 8, 4, {.window = 2, .fraction = 0.1});
  EXPECT_EQ(rule->id(), "adam-hig");
  EXPECT_EQ(rule->phase(), 0);
  EXPECT_EQ(rule->batch_size(), 8);
  EXPECT_EQ(rule->need(), UpdateNeed::kGradient);
  for (const double loss : {1.0, 0.5, 0.3, 0.29}) rule->observe({0, loss, NAN});
  EXPECT_EQ(rule->phase(), 0);  // 0.29 is 3 % below 0.3, but 0.3 was 40 % below 0.5
  rule->observe({0, 0.295, NAN});  // the last two gained 3 % over 0.3
  EXPECT_EQ(rule->phase(), 1);
  EXPECT_EQ(rule->batch_size(), 4);
  EXPECT_EQ(rule->need(), UpdateNeed::kStackedJacobian);
  EXPECT_EQ(rule->switched_at(), 0);
  const nlohmann::json params = rule->params();
  EXPECT_EQ(params.at("kappa"), 0.5);
  EXPECT_EQ(params.at("pretrain_window"), 2);
  EXPECT_EQ(params.at("pretrain_batch"), 8);
  EXPECT_TRUE(params.contains("pretrain_beta1"));
  // Its state says where it is; a restored rule continues there, a malformed state is refused.
  auto restored = adam_then("hig", 8, 4, {.window = 2, .fraction = 0.1});
  restored->restore(rule->state(), 10);
  EXPECT_EQ(restored->phase(), 1);
  nlohmann::json bad = rule->state();
  bad["switched_at"] = 5;  // after the 0 updates made
  EXPECT_THROW(restored->restore(bad, 10), Error);
}

// Adam's first updates, then HIG from that network: the history up to the switch is the plain
// Adam run's to the bit, HIG takes over with its own batch size at a new epoch (evaluated
// there), and the steps after the switch report HIG's inversion.
TEST(Switching, AdamMakesTheFirstUpdatesThenTheRuleTakesOver) {
  // 30 samples: Adam in batches of 8 (4 per epoch), HIG in batches of 4 (8 per epoch).
  TrainerOptions options;
  options.batch_size = 8;
  options.max_iterations = 20;
  options.eval_every = 3;
  NetworkThroughPhysics a(30);
  const auto adam = make_learning_update("adam");
  const TrainingSummary plain = train(a.network, *adam, a.problem, a.data, &a.data, options);

  for (const long long switch_at : {6LL, 7LL}) {
    NetworkThroughPhysics s(30);
    const auto rule = adam_then("hig", 8, 4, {.after = switch_at});
    const TrainingSummary summary = train(s.network, *rule, s.problem, s.data, &s.data, options);
    EXPECT_EQ(summary.termination, TrainingTermination::kMaxIterations);
    EXPECT_EQ(summary.iterations, 20);
    std::size_t compared = 0;
    bool evaluated_at_switch = false;
    for (const TrainingRecord& r : summary.history) {
      evaluated_at_switch = evaluated_at_switch || r.iteration == switch_at;
      if (r.iteration > switch_at) {
        EXPECT_TRUE(r.step.contains("kept_directions")) << r.iteration << ": " << r.step;
        continue;
      }
      const auto same =
          std::find_if(plain.history.begin(), plain.history.end(),
                       [&](const TrainingRecord& p) { return p.iteration == r.iteration; });
      if (same == plain.history.end()) continue;  // the switch off the schedule of 3
      ++compared;
      EXPECT_EQ(r.train_loss, same->train_loss) << r.iteration;
      EXPECT_EQ(r.test_loss, same->test_loss) << r.iteration;
      EXPECT_EQ(r.epoch, same->epoch) << r.iteration;
    }
    EXPECT_EQ(compared, 3u) << switch_at;  // iterations 0, 3 and 6
    EXPECT_TRUE(evaluated_at_switch) << switch_at;
    EXPECT_LT(summary.history.back().train_loss, summary.history.front().train_loss);
    // Samples seen: the switch iteration's batches of 8, then batches of 4.
    EXPECT_DOUBLE_EQ(summary.history.back().epoch,
                     static_cast<double>(8 * switch_at + 4 * (20 - switch_at)) / 30.0);
    ASSERT_EQ(summary.phases.size(), 2u);
    EXPECT_EQ(summary.phases[1].first_iteration, switch_at);
    EXPECT_EQ(summary.phases[0].batch_size, 8);
    EXPECT_EQ(summary.phases[1].batch_size, 4);
    EXPECT_NE(brief_report(summary).find("adam-hig: 20 iterations"), std::string::npos)
        << brief_report(summary);
    EXPECT_NE(brief_report(summary).find("part 2 from iteration " + std::to_string(switch_at)),
              std::string::npos)
        << brief_report(summary);
    EXPECT_NE(full_report(summary).find("batch size from iteration " + std::to_string(switch_at)),
              std::string::npos);
  }
}

// A run whose limit comes first never switches: one part, Adam's updates alone. Bad parts and
// conditions are refused.
TEST(Switching, ARunThatEndsFirstNeverSwitchesAndBadRulesAreRefused) {
  NetworkThroughPhysics s(30);
  TrainerOptions options;
  options.batch_size = 4;
  options.max_epochs = 1;
  const auto rule = adam_then("hig", 8, 4, {.after = 100});
  const TrainingSummary summary = train(s.network, *rule, s.problem, s.data, nullptr, options);
  EXPECT_EQ(summary.termination, TrainingTermination::kMaxEpochs);
  EXPECT_EQ(summary.iterations, 4);  // one epoch of Adam's batches
  EXPECT_EQ(summary.phases.size(), 1u);
  EXPECT_EQ(rule->switched_at(), -1);

  const auto make = [](Index first_batch, SwitchCondition condition) {
    return adam_then("hig", first_batch, 4, condition);
  };
  EXPECT_THROW(make(0, {.after = 5}), Error);
  EXPECT_THROW(make(8, {.after = -1}), Error);
  EXPECT_THROW(make(8, {.window = 0}), Error);
  EXPECT_THROW(make(8, {.fraction = 1.0}), Error);
  EXPECT_THROW(make(8, {.fraction = 0.0}), Error);
  EXPECT_THROW(SwitchingUpdate(nullptr, 8, make_learning_update("hig"), 4, {.after = 5}), Error);
}

}  // namespace
}  // namespace physgrad
