// Learning-rate schedules as torch.optim.lr_scheduler defines them (StepLR, CosineAnnealingLR,
// ReduceLROnPlateau), applied by SGD and Adam, kept in checkpoints, and offered by name.
#include <gtest/gtest.h>

#include <cmath>

#include "learning_fixture.hpp"
#include "physgrad/error.hpp"
#include "physgrad/learn/schedule.hpp"

namespace physgrad {
namespace {

using testing::NetworkThroughPhysics;

TEST(Schedule, StepAndCosineFollowTheirClosedForms) {
  LearningRateSchedule step({.schedule = ScheduleKind::kStep, .decay = 0.5, .decay_every = 3});
  LearningRateSchedule cosine({.schedule = ScheduleKind::kCosine, .t_max = 8, .min_lr = 0.01});
  LearningRateSchedule constant;
  for (int t = 0; t < 12; ++t) {
    EXPECT_DOUBLE_EQ(step.rate(0.2), 0.2 * std::pow(0.5, t / 3)) << t;
    const double c = std::min(t, 8);
    EXPECT_NEAR(cosine.rate(0.2), 0.01 + 0.19 * (1 + std::cos(M_PI * c / 8)) / 2, 1e-15) << t;
    EXPECT_EQ(constant.rate(0.2), 0.2);
    step.advance();
    cosine.advance();
    constant.advance();
  }
  EXPECT_DOUBLE_EQ(cosine.rate(0.2), 0.01);  // held at the minimum after t_max
}

// torch's ReduceLROnPlateau (mode min, relative threshold): a decay once more than `patience`
// evaluations in a row failed to beat the best by the threshold; never below min_lr.
TEST(Schedule, PlateauDecaysAfterPatienceEvaluationsWithoutImprovement) {
  LearningRateSchedule plateau({.schedule = ScheduleKind::kPlateau,
                                .decay = 0.1,
                                .min_lr = 1e-3,
                                .patience = 2,
                                .threshold = 0.01});
  const double losses[] = {1.0, 0.5, 0.499, 0.498, 0.497, 0.3, 0.3, 0.3, 0.3, 0.3, 0.3, 0.3};
  const double expected[] = {1, 1, 1, 1, 0.1, 0.1, 0.1, 0.1, 0.01, 0.01, 0.01, 0.001};
  for (std::size_t k = 0; k < std::size(losses); ++k) {
    plateau.observe(losses[k]);
    EXPECT_DOUBLE_EQ(plateau.rate(1.0), expected[k]) << k;
  }
  for (int k = 0; k < 20; ++k) plateau.observe(0.3);
  EXPECT_DOUBLE_EQ(plateau.rate(1.0), 1e-3);  // the floor
  // The state carries the decays and the count since the best.
  LearningRateSchedule restored(plateau.options());
  restored.restore(plateau.state());
  EXPECT_EQ(restored.state(), plateau.state());
  EXPECT_THROW(restored.restore(nlohmann::json::array()), Error);
  EXPECT_THROW(LearningRateSchedule().restore(plateau.state()), Error);  // constant has none
}

// Adam's step at the scheduled rate is its step at the base rate scaled by rate/η; SGD's is
// −rate·∇θ. The schedule's state travels with the rule's.
TEST(Schedule, SgdAndAdamStepAtTheScheduledRate) {
  NetworkThroughPhysics s(8);
  MlpCache cache;
  const BatchState batch = s.evaluate(UpdateNeed::kGradient, cache);
  const RuleSettings step_every_one{{"lr", 0.1}, {"schedule", "step"}, {"decay", 0.5},
                                    {"decay_every", 1}};
  const auto sgd = make_learning_update("sgd", step_every_one);
  EXPECT_TRUE(sgd->step(batch).delta.isApprox(-0.1 * batch.gradient, 1e-15));
  EXPECT_TRUE(sgd->step(batch).delta.isApprox(-0.05 * batch.gradient, 1e-15));
  EXPECT_EQ(sgd->params().at("schedule"), "step");
  EXPECT_FALSE(sgd->params().contains("t_max"));  // only the chosen kind's options

  const auto plain = make_learning_update("adam", {{"lr", 0.1}});
  const auto scheduled = make_learning_update("adam", step_every_one);
  for (int t = 0; t < 3; ++t) {
    const Vector expected = std::pow(0.5, t) * plain->step(batch).delta;
    EXPECT_TRUE(scheduled->step(batch).delta.isApprox(expected, 1e-14)) << t;
  }
  const auto copy = make_learning_update("adam", step_every_one);
  copy->restore(scheduled->state(), s.network.num_parameters());
  EXPECT_EQ(copy->state(), scheduled->state());
  // A constant schedule leaves Adam's state as it was (no schedule entry).
  EXPECT_FALSE(plain->state().contains("schedule"));
}

TEST(Schedule, BadSettingsAreRefusedNamingThem) {
  EXPECT_THROW(make_learning_update("adam", {{"schedule", "exponential"}}), Error);
  EXPECT_THROW(make_learning_update("sgd", {{"schedule", "step"}, {"decay", 1.5}}), Error);
  EXPECT_THROW(make_learning_update("sgd", {{"schedule", "step"}, {"decay_every", 0}}), Error);
  try {
    make_learning_update("adam", {{"schedule", "cosine"}, {"t_max", -3}});
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("t_max"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace physgrad
