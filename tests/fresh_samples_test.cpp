// Training on samples drawn afresh for every mini-batch (TrainerOptions::fresh_samples, the HIG
// paper's protocol), and a run that a limit ends above its start (kDiverged).
#include <gtest/gtest.h>

#include <set>
#include <tuple>

#include "learning_fixture.hpp"
#include "physgrad/error.hpp"
#include "physgrad/physics/diagonal_scale.hpp"
#include "physgrad/run/cases/sampling.hpp"

namespace physgrad {
namespace {

using testing::NetworkThroughPhysics;

// Each step trains on the batch drawn for it, every batch from a stream of its own: the network
// equals a loop of train_step() over those batches to the bit, and no sample comes twice.
TEST(FreshSamples, EveryStepTrainsOnANewBatchAndNoSampleComesTwice) {
  const NetworkThroughPhysics source;
  std::vector<std::uint64_t> streams;
  std::set<std::pair<double, double>> inputs;
  long long drawn = 0;
  TrainerOptions options;
  options.batch_size = 6;
  options.max_epochs = 5;  // 30 samples: 5 batches an epoch, 25 steps
  options.seed = 11;
  options.fresh_samples = [&](std::uint64_t stream, Index count) {
    streams.push_back(stream);
    Dataset batch = source.draw(stream, count);
    for (Index j = 0; j < count; ++j) inputs.emplace(batch.inputs(0, j), batch.inputs(1, j));
    drawn += count;
    return batch;
  };
  NetworkThroughPhysics s(30);
  const auto adam = make_learning_update("adam");
  const TrainingSummary summary = train(s.network, *adam, s.problem, s.data, &s.data, options);
  EXPECT_EQ(summary.iterations, 25);
  EXPECT_TRUE(summary.fresh_samples);
  ASSERT_EQ(streams.size(), 25u);
  for (long long t = 0; t < 25; ++t) {
    EXPECT_EQ(streams[static_cast<std::size_t>(t)], fresh_stream(11, t)) << t;
  }
  EXPECT_EQ(drawn, 150);
  EXPECT_EQ(static_cast<long long>(inputs.size()), drawn);  // no sample twice
  for (Index j = 0; j < s.data.size(); ++j) {  // and none of the fixed set
    EXPECT_EQ(inputs.count({s.data.inputs(0, j), s.data.inputs(1, j)}), 0u);
  }

  NetworkThroughPhysics by_hand(30);
  const auto adam_by_hand = make_learning_update("adam");
  StepState state;
  for (long long t = 0; t < 25; ++t) {
    train_step(by_hand.network, *adam_by_hand, by_hand.problem, source.draw(fresh_stream(11, t), 6),
               state);
  }
  EXPECT_TRUE(by_hand.network.parameters() == s.network.parameters());
}

TEST(FreshSamples, StreamsDifferAcrossSeedsAndIterationsAndBadBatchesAreRefused) {
  std::set<std::uint64_t> streams;
  for (std::uint64_t seed = 0; seed < 20; ++seed) {
    for (long long t = 0; t < 500; ++t) streams.insert(fresh_stream(seed, t));
  }
  EXPECT_EQ(streams.size(), 20u * 500u);

  NetworkThroughPhysics s(10);
  TrainerOptions options;
  options.batch_size = 4;
  options.max_iterations = 3;
  const auto adam = make_learning_update("adam");
  options.fresh_samples = [&s](std::uint64_t, Index count) { return s.draw(1, count + 1); };
  EXPECT_THROW(train(s.network, *adam, s.problem, s.data, nullptr, options), Error);
  options.fresh_samples = [&s](std::uint64_t, Index count) {
    Dataset d = s.draw(1, count);
    d.inputs(0, 0) = NAN;
    return d;
  };
  EXPECT_THROW(train(s.network, *adam, s.problem, s.data, nullptr, options), Error);
}

// Poisson's fields (phiflow's Noise): drawn batches of the run never repeat a field, nor one of
// the fixed test set.
TEST(FreshSamples, PoissonNoiseBatchesNeverRepeatAField) {
  using run::periodic_noise;
  using run::Sampler;
  Sampler test_sampler(2 * 0 + 1);
  const Matrix test = periodic_noise(256, 8, test_sampler);
  std::set<std::tuple<double, double, double>> seen;
  for (Index j = 0; j < test.cols(); ++j) seen.emplace(test(0, j), test(1, j), test(2, j));
  for (long long t = 0; t < 200; ++t) {
    Sampler sampler(fresh_stream(0, t));
    const Matrix batch = periodic_noise(64, 8, sampler);
    for (Index j = 0; j < batch.cols(); ++j) {
      EXPECT_TRUE(seen.emplace(batch(0, j), batch(1, j), batch(2, j)).second) << t << " " << j;
    }
  }
}

// SGD past its stability limit on ½(w + b)²: the loss grows 4× a step but stays finite, so the
// iteration limit ends the run, as diverged.
TEST(Trainer, ARunThatALimitEndsAboveItsStartHasDiverged) {
  const DiagonalScale physics(Vector::Ones(1));
  const L2Loss loss;
  Mlp network({1, 1}, Activation::kTanh);
  network.initialize(0);
  const Dataset data{Matrix::Ones(1, 4), Matrix::Zero(1, 4), Matrix()};
  const auto sgd = make_learning_update("sgd", {{"lr", 1.5}});
  TrainerOptions options;
  options.batch_size = 4;
  options.max_iterations = 5;
  const TrainingSummary summary = train(network, *sgd, {&physics, &loss}, data, nullptr, options);
  EXPECT_EQ(summary.termination, TrainingTermination::kDiverged);
  EXPECT_NEAR(summary.history.back().train_loss / summary.history.front().train_loss, 1024, 1e-6);
  EXPECT_NE(summary.message.find("reached max_iterations with the training loss"),
            std::string::npos)
      << summary.message;
  EXPECT_FALSE(ended_by_limit(*summary.termination));
  EXPECT_EQ(parse_training_termination("diverged"), TrainingTermination::kDiverged);
}

}  // namespace
}  // namespace physgrad
