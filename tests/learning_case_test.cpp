// A learning experiment's case, declared once (run/cases/learning_case.hpp): its training and
// test sets are streams 2s and 2s + 1 of its samples, and its reference case at batch B is the
// network of seed s with the first B samples of that training set — for every built-in
// experiment with a reference case too.
#include <gtest/gtest.h>

#include <memory>

#include "physgrad/loss/loss.hpp"
#include "physgrad/physics/diagonal_scale.hpp"
#include "physgrad/run/cases/learning_case.hpp"
#include "physgrad/run/cases/learning_experiment.hpp"
#include "physgrad/run/cases/sampling.hpp"
#include "registry.hpp"

namespace physgrad::run {
namespace {

// Samples whose values name their stream and position: stream·1000 + i.
LearningCase counting_case() {
  return {std::make_shared<DiagonalScale>(Vector{{1.0, 0.5}}), std::make_shared<L2Loss>(),
          [](std::uint64_t seed) {
            Mlp network({2, 3, 2}, Activation::kTanh);
            network.initialize(seed);
            return network;
          },
          [](std::uint64_t stream, Index count) {
            Dataset data{Matrix(2, count), Matrix(2, count), Matrix()};
            for (Index i = 0; i < count; ++i) {
              data.inputs.col(i).setConstant(static_cast<double>(stream) * 1000 + static_cast<double>(i));
            }
            data.targets = data.inputs;
            return data;
          },
          {{"hig", {{{"lr", 0.5}}, 16}}}};
}

TEST(LearningCase, TrainingAndTestSetsAreTheSeedsTwoStreams) {
  const LearningCase c = counting_case();
  EXPECT_EQ(c.training_set(3, 7).inputs(0, 2), 14 * 1000 + 2);
  EXPECT_EQ(c.test_set(3, 7).inputs(1, 0), 15 * 1000);
  EXPECT_EQ(c.problem().physics, c.physics.get());
  EXPECT_EQ(c.problem().loss, c.loss.get());
}

TEST(LearningCase, TheReferenceCaseIsTheSeedsNetworkOnTheFirstTrainingSamples) {
  const LearningCase c = counting_case();
  const ReferenceCase reference = c.reference(4, 5);
  EXPECT_EQ(reference.batch.inputs, c.training_set(4, 5).inputs);
  EXPECT_EQ(reference.network.parameters(), c.network(5).parameters());
  EXPECT_NE(reference.network.parameters(), c.network(6).parameters());
  EXPECT_EQ(reference.physics, c.physics);
  EXPECT_EQ(reference.batch_size("hig"), 16);
  EXPECT_EQ(reference.update("hig")->params().at("lr"), 0.5);
}

// The built-in reference cases come from the cases their experiments train: the network of
// the seed and a prefix of one training set, whatever the batch.
TEST(LearningCase, EveryBuiltInReferenceCaseIsAPrefixOfOneTrainingSet) {
  const Registry& registry = experiments::builtin_registry();
  const std::vector<std::string> names = registry.reference_names();
  EXPECT_GE(names.size(), 4u);
  for (const std::string& name : names) {
    const ReferenceCase small = registry.reference(name, 2, 3);
    const ReferenceCase large = registry.reference(name, 5, 3);
    EXPECT_EQ(small.network.parameters(), large.network.parameters()) << name;
    EXPECT_EQ(small.batch.inputs, large.batch.inputs.leftCols(2)) << name;
    EXPECT_EQ(small.batch.targets, large.batch.targets.leftCols(2)) << name;
    EXPECT_NE(small.network.parameters(), registry.reference(name, 2, 4).network.parameters())
        << name;
  }
}

}  // namespace
}  // namespace physgrad::run
