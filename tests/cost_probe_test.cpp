// The cost yardstick (TrainerOptions::cost_reference): beside a rule's steps the trainer times an
// Adam step on the same batch at the same θ, never applied, so that each part's cost per update
// reads in Adam updates measured under the same load. The probes leave the run's results as they
// were, skip the reference's own part, and survive a checkpoint.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "learning_fixture.hpp"
#include "physgrad/learn/switching.hpp"
#include "physgrad/stop.hpp"
#include "physgrad/timing.hpp"
#include "test_problems.hpp"

namespace physgrad {
namespace {

using testing::AdamWithDelay;
using testing::NetworkThroughPhysics;
using testing::test_settings;

TrainerOptions probed(long long iterations, bool with_reference) {
  TrainerOptions options;
  options.batch_size = 4;
  options.max_iterations = iterations;
  options.eval_every = 5;
  if (with_reference) {
    options.cost_reference = [] { return make_learning_update("adam"); };
    options.cost_reference_batch = 2;
  }
  return options;
}

// HIG with probes follows HIG without them to the bit; its part holds probes whose ratio is a
// positive number; without a reference there are none.
TEST(CostProbe, ProbesLeaveTheRunAsItWasAndTimeTheRulesPart) {
  NetworkThroughPhysics a(32), b(32);
  b.data = a.data;
  const auto ua = make_learning_update("hig", test_settings("hig"));
  const auto ub = make_learning_update("hig", test_settings("hig"));
  const TrainingSummary sa = train(a.network, *ua, a.problem, a.data, nullptr, probed(20, true));
  const TrainingSummary sb = train(b.network, *ub, b.problem, b.data, nullptr, probed(20, false));
  EXPECT_EQ(a.network.parameters(), b.network.parameters());
  ASSERT_EQ(sa.history.size(), sb.history.size());
  for (std::size_t k = 0; k < sa.history.size(); ++k) {
    EXPECT_EQ(sa.history[k].train_loss, sb.history[k].train_loss) << k;
  }
  ASSERT_EQ(sa.phases.size(), 1u);
  EXPECT_GE(sa.phases[0].probes, 1);
  EXPECT_LE(sa.phases[0].probes, 20);
  EXPECT_GT(sa.phases[0].reference_updates(), 0);
  EXPECT_TRUE(std::isfinite(sa.phases[0].reference_updates()));
  EXPECT_EQ(sb.phases[0].probes, 0);
  EXPECT_TRUE(std::isnan(sb.phases[0].reference_updates()));
}

// Adam→HIG: the Adam part is the reference's own and is not probed; HIG's part is, from its first
// step on. The probes' totals go through the checkpoint's JSON and back.
TEST(CostProbe, TheReferencesOwnPartIsNotProbedAndProbesSurviveACheckpoint) {
  NetworkThroughPhysics s(32);
  SwitchingUpdate update(make_learning_update("adam"), 4,
                         make_learning_update("hig", test_settings("hig")), 4,
                         SwitchCondition{.after = 10});
  const TrainingSummary summary =
      train(s.network, update, s.problem, s.data, nullptr, probed(16, true));
  ASSERT_EQ(summary.phases.size(), 2u);
  EXPECT_EQ(summary.phases[0].probes, 0);
  EXPECT_GE(summary.phases[1].probes, 1);
  EXPECT_EQ(summary.phases[1].timed_steps, 6);
  EXPECT_GT(summary.phases[1].step_cpu_seconds, 0);
  EXPECT_GT(summary.phases[1].reference_cpu_seconds, 0);

  const TrainingSummary back = training_summary_from_json(training_summary_to_json(summary));
  ASSERT_EQ(back.phases.size(), 2u);
  EXPECT_EQ(back.phases[1].probes, summary.phases[1].probes);
  EXPECT_EQ(back.phases[1].timed_steps, summary.phases[1].timed_steps);
  EXPECT_EQ(back.phases[1].step_cpu_seconds, summary.phases[1].step_cpu_seconds);
  EXPECT_EQ(back.phases[1].reference_cpu_seconds, summary.phases[1].reference_cpu_seconds);
  // A file of the first version with probes timed the rule at its probes alone.
  nlohmann::json probed_only = training_summary_to_json(summary);
  for (nlohmann::json& phase : probed_only["phases"]) {
    phase["probed_step_cpu_seconds"] = phase["step_cpu_seconds"];
    phase.erase("timed_steps");
    phase.erase("step_cpu_seconds");
  }
  const TrainingSummary::Phase read = training_summary_from_json(probed_only).phases[1];
  EXPECT_EQ(read.timed_steps, summary.phases[1].probes);
  EXPECT_EQ(read.step_cpu_seconds, summary.phases[1].step_cpu_seconds);
  // A file of an earlier version has no probes: its parts read as unprobed.
  nlohmann::json old = probed_only;
  for (nlohmann::json& phase : old["phases"]) {
    phase.erase("probes");
    phase.erase("probed_step_cpu_seconds");
    phase.erase("reference_cpu_seconds");
  }
  EXPECT_EQ(training_summary_from_json(old).phases[1].probes, 0);
}

// A reference whose step runs `body` on the batch and proposes no change: it records, burns CPU
// time or asks to stop, as a test needs.
class ScriptedReference final : public LearningUpdate {
 public:
  explicit ScriptedReference(std::function<void(const BatchState&)> body)
      : body_(std::move(body)) {}
  std::string id() const override { return "scripted-reference"; }
  nlohmann::json params() const override { return nlohmann::json::object(); }
  UpdateNeed need() const override { return UpdateNeed::kGradient; }
  Step step(const BatchState& batch) override {
    body_(batch);
    return {Vector::Zero(batch.gradient.size())};
  }
  double learning_rate() const override { return 0; }
  void set_learning_rate(double /*lr*/) override {}

 private:
  std::function<void(const BatchState&)> body_;
};

// The reference steps at its own batch size: the rule's batch of 4 is cut to 2, or its samples
// repeated to 12 (an Adam run at batch 12 beside a rule at batch 4 costs a batch of 12).
TEST(CostProbe, TheReferenceStepsAtItsOwnBatchSize) {
  for (const Index reference_batch : {2, 12}) {
    NetworkThroughPhysics s(32);
    std::vector<Index> sizes;
    TrainerOptions options = probed(6, false);
    options.cost_reference = [&sizes] {
      return std::make_unique<ScriptedReference>(
          [&sizes](const BatchState& batch) { sizes.push_back(batch.batch_size); });
    };
    options.cost_reference_batch = reference_batch;
    const auto rule = make_learning_update("hig", test_settings("hig"));
    train(s.network, *rule, s.problem, s.data, nullptr, options);
    ASSERT_FALSE(sizes.empty());
    for (const Index size : sizes) EXPECT_EQ(size, reference_batch);
  }
}

// Spends `seconds` of the process's CPU time.
void burn_cpu(double seconds) {
  const double until = process_cpu_seconds() + seconds;
  volatile double sink = 0;
  while (process_cpu_seconds() < until) sink = sink + 1;
}

// A rule whose every tenth step costs 5 ms more is charged its mean cost per update: at least the
// burns' 0.5 ms per step, at most the whole run's CPU time per step. Charged at the probed steps
// alone it read several times that: with probes as rare as here, a long step is the one that
// most often makes the next probe due.
TEST(CostProbe, ARuleWithUnevenStepsIsChargedItsMeanCost) {
  NetworkThroughPhysics s(32);
  AdamWithDelay rule([](long long k) {
    if (k % 10 == 9) burn_cpu(5e-3);
  });
  TrainerOptions options = probed(400, false);
  // A reference step of 1 ms keeps the probes rare (2 % of the time).
  options.cost_reference = [] {
    return std::make_unique<ScriptedReference>([](const BatchState&) { burn_cpu(1e-3); });
  };
  const double start = process_cpu_seconds();
  const TrainingSummary summary = train(s.network, rule, s.problem, s.data, nullptr, options);
  const double per_step = (process_cpu_seconds() - start) / 400;  // steps, evaluations, probes
  const TrainingSummary::Phase& phase = summary.phases.back();
  ASSERT_GE(phase.probes, 2);
  EXPECT_EQ(phase.timed_steps, 400);
  const double charged = phase.reference_updates() * phase.reference_cpu_seconds /
                         static_cast<double>(phase.probes);
  EXPECT_GE(charged, 0.999 * 0.5e-3);
  EXPECT_LE(charged, per_step);
}

// A stop inside a probe drops the probe, not the step before it: the run stops at the next
// iteration boundary with that step counted, and its checkpoint resumes to the parameters of a
// run that was never stopped, to the bit.
TEST(CostProbe, AStopInsideAProbeStopsAtTheNextIterationAndResumesExactly) {
  NetworkThroughPhysics a(32), b(32);
  b.data = a.data;
  clear_stop_request();
  TrainerOptions options = probed(6, false);
  options.stop = &stop_request_flag();
  // The reference asks the process to stop and then polls, as a simulator inside it would: the
  // stop lands inside a probe.
  options.cost_reference = [] {
    return std::make_unique<ScriptedReference>([](const BatchState&) {
      request_stop();
      throw_if_stop_requested("the probe");
    });
  };
  std::optional<TrainerState> saved;
  options.on_checkpoint = [&saved](const TrainerState& state) { saved = state; };
  const auto stopped_rule = make_learning_update("hig", test_settings("hig"));
  const TrainingSummary stopped =
      train(a.network, *stopped_rule, a.problem, a.data, nullptr, options);
  clear_stop_request();
  EXPECT_EQ(stopped.termination, TrainingTermination::kInterrupted);
  EXPECT_EQ(stopped.iterations, 1);
  ASSERT_TRUE(saved.has_value());
  EXPECT_EQ(saved->summary.phases[0].probes, 0);

  TrainerOptions resumed = probed(6, false);
  resumed.resume = &*saved;
  const auto resumed_rule = make_learning_update("hig", test_settings("hig"));
  train(a.network, *resumed_rule, a.problem, a.data, nullptr, resumed);
  const auto straight_rule = make_learning_update("hig", test_settings("hig"));
  train(b.network, *straight_rule, b.problem, b.data, nullptr, probed(6, false));
  EXPECT_EQ(a.network.parameters(), b.network.parameters());
}

}  // namespace
}  // namespace physgrad
