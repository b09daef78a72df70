// train_step(), the one training step: a loop of one's own over it is train() step for step,
// rules can be switched between steps, and its numerical guard (not applied, halved, undone)
// reports what it did.
#include <gtest/gtest.h>

#include <cmath>

#include "learning_fixture.hpp"
#include "physgrad/error.hpp"
#include "test_problems.hpp"

namespace physgrad {
namespace {

using testing::NetworkThroughPhysics;

// Batches 0–3, 4–7, … of the data set in order, as train() draws them without shuffling.
Dataset batch_of(const Dataset& data, Index first, Index size) {
  return data.columns(first, std::min(size, data.size() - first));
}

TEST(TrainStep, AnOwnLoopIsTrainStepForStep) {
  for (const std::string id : {"adam", "hig", "sip"}) {
    NetworkThroughPhysics a(12), b(12);
    TrainerOptions options;
    options.batch_size = 4;
    options.max_iterations = 9;
    options.shuffle = false;
    const auto first = make_learning_update(id, testing::test_settings(id));
    train(a.network, *first, a.problem, a.data, nullptr, options);

    const auto second = make_learning_update(id, testing::test_settings(id));
    StepState state;
    for (Index it = 0; it < 9; ++it) {
      const StepReport report =
          train_step(b.network, *second, b.problem, batch_of(b.data, (it % 3) * 4, 4), state);
      ASSERT_TRUE(report.applied()) << id << " " << describe_failure(report, it);
      EXPECT_TRUE(std::isfinite(report.loss));
      EXPECT_GE(report.total_seconds, report.forward_seconds);
    }
    EXPECT_TRUE(a.network.parameters() == b.network.parameters()) << id;  // every bit
  }
}

// The HIG paper's pretraining: Adam first, then HIG on the same network; a schedule halves
// Adam's step size on the way.
TEST(TrainStep, RulesCanBeSwitchedBetweenSteps) {
  NetworkThroughPhysics s(16);
  const auto adam = make_learning_update("adam", {{"lr", 0.02}});
  const auto hig = make_learning_update("hig", {{"lr", 0.3}});
  StepState state;
  const double start = mean_loss(s.network, s.problem, s.data);
  for (int it = 0; it < 40; ++it) {
    if (it == 20) adam->set_learning_rate(0.01);
    ASSERT_TRUE(train_step(s.network, *adam, s.problem, s.data, state).applied());
  }
  const double after_adam = mean_loss(s.network, s.problem, s.data);
  for (int it = 0; it < 20; ++it) {
    ASSERT_TRUE(train_step(s.network, *hig, s.problem, s.data, state).applied());
  }
  const double after_hig = mean_loss(s.network, s.problem, s.data);
  EXPECT_LT(after_adam, start);
  EXPECT_LT(after_hig, 0.8 * after_adam);  // 0.067 → 0.045 in 20 steps
  EXPECT_TRUE(state.last_step_halvable);  // the last step was HIG's
}

TEST(TrainStep, TheGuardHalvesOrUndoesTheStepThatBrokeTheBatch) {
  const testing::Bounded physics(10.0);
  const L2Loss loss;
  const Dataset data{Matrix::Ones(1, 2), Matrix::Constant(1, 2, 8.0), Matrix()};
  // Gauss-Newton at 1.75× its full step (η = 1.75·B): 0 → 14, past the bound; one halving
  // brings it to 7.
  Mlp network({1, 1}, Activation::kIdentity);
  const auto gn = make_learning_update("gn", {{"lr", 3.5}});
  StepState state;
  ASSERT_TRUE(train_step(network, *gn, {&physics, &loss}, data, state).applied());
  EXPECT_NEAR(network.forward(Matrix::Ones(1, 1))(0, 0), 14.0, 1e-12);
  const StepReport halved = train_step(network, *gn, {&physics, &loss}, data, state);
  EXPECT_TRUE(halved.applied());
  EXPECT_EQ(halved.halvings, 1);
  EXPECT_NEAR(halved.loss, 0.5, 1e-12);  // the batch at the halved step: ½(7 − 8)²

  // SGD cannot halve: the step that broke the batch is undone.
  Mlp other({1, 1}, Activation::kIdentity);
  const auto sgd = make_learning_update("sgd", {{"lr", 2.0}});
  StepState sgd_state;
  ASSERT_TRUE(train_step(other, *sgd, {&physics, &loss}, data, sgd_state).applied());
  const Vector broken = other.parameters();
  const StepReport undone = train_step(other, *sgd, {&physics, &loss}, data, sgd_state);
  EXPECT_EQ(undone.failure, StepReport::Failure::kLoss);
  EXPECT_TRUE(undone.undone);
  EXPECT_TRUE(std::isnan(undone.loss));
  EXPECT_EQ(other.parameters(), Vector::Zero(2));
  EXPECT_NE(broken, other.parameters());
  EXPECT_EQ(describe_failure(undone, 1),
            "non-finite loss at iteration 2; update 1 undone, parameters restored to those "
            "before it");
  EXPECT_EQ(sgd_state.last_step.size(), 0);
}

TEST(TrainStep, RejectsABatchThatDoesNotFit) {
  NetworkThroughPhysics s;
  const auto adam = make_learning_update("adam");
  StepState state;
  Dataset wrong = s.data;
  wrong.targets = Matrix::Zero(3, s.data.size());
  EXPECT_THROW(train_step(s.network, *adam, s.problem, wrong, state), Error);
  EXPECT_THROW(train_step(s.network, *adam, s.problem, s.data.columns(0, 0), state), Error);
}

}  // namespace
}  // namespace physgrad
