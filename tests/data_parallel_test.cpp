// Data-parallel training without MPI: the sharding arithmetic, the serial communicator, the
// choice of what the normal path exchanges, and train() over K threads acting as ranks against
// the one-process run of the same global batch (losses to 1e-10, θ bit-identical across ranks).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <ostream>
#include <string>
#include <thread>

#include "physgrad/error.hpp"
#include "physgrad/catalogue.hpp"
#include "physgrad/learn/sharded_jacobian.hpp"
#include "physgrad/nn/mlp.hpp"
#include "physgrad/physics/comparison_toy.hpp"
#include "physgrad/train/trainer.hpp"
#include "thread_communicator.hpp"

namespace physgrad {
namespace {

TEST(ShareOf, SplitsContiguouslyWithSharesDifferingByAtMostOne) {
  for (const std::size_t count : {0UL, 1UL, 2UL, 7UL, 32UL, 33UL, 128UL}) {
    for (int size = 1; size <= 5; ++size) {
      std::size_t next = 0, smallest = count, largest = 0;
      for (int rank = 0; rank < size; ++rank) {
        const Share share = share_of(count, rank, size);
        EXPECT_EQ(share.begin, next) << count << " over " << size;
        next += share.length;
        smallest = std::min(smallest, share.length);
        largest = std::max(largest, share.length);
      }
      EXPECT_EQ(next, count);
      EXPECT_LE(largest - smallest, 1U);
    }
  }
  // Fewer items than ranks: the first ranks get one each, the others none.
  EXPECT_EQ(share_of(2, 0, 3).length, 1U);
  EXPECT_EQ(share_of(2, 1, 3).begin, 1U);
  EXPECT_EQ(share_of(2, 2, 3).length, 0U);
  EXPECT_EQ(share_of(33, 0, 2).length, 17U);
  EXPECT_EQ(share_of(33, 1, 2).begin, 17U);
  EXPECT_THROW(share_of(4, 2, 2), Error);
  EXPECT_THROW(share_of(4, 0, 0), Error);
}

TEST(SerialCommunicator, CollectivesReturnTheLocalData) {
  SerialCommunicator serial;
  EXPECT_EQ(serial.rank(), 0);
  EXPECT_EQ(serial.size(), 1);
  std::vector<double> values = {1.5, -2.0, 3.25};
  serial.allreduce_sum(values);
  EXPECT_EQ(values, (std::vector<double>{1.5, -2.0, 3.25}));
  EXPECT_EQ(serial.allreduce_sum(4.0), 4.0);
  std::vector<std::size_t> counts;
  EXPECT_EQ(serial.allgather(values.data(), values.size(), &counts), values);
  EXPECT_EQ(counts, (std::vector<std::size_t>{3}));
  EXPECT_TRUE(serial.allgather(nullptr, 0).empty());
  serial.broadcast(values.data(), values.size(), 0);
  EXPECT_EQ(values[2], 3.25);
  EXPECT_THROW(serial.broadcast(values.data(), values.size(), 1), Error);
}

TEST(HashDoubles, SeesEveryBit) {
  const std::vector<double> a = {1.0, 2.0, 3.0};
  std::vector<double> b = a;
  EXPECT_EQ(hash_doubles(a.data(), 3), hash_doubles(b.data(), 3));
  b[1] = std::nextafter(b[1], 3.0);
  EXPECT_NE(hash_doubles(a.data(), 3), hash_doubles(b.data(), 3));
  const double zero = 0.0, negative_zero = -0.0;
  EXPECT_NE(hash_doubles(&zero, 1), hash_doubles(&negative_zero, 1));
  SerialCommunicator serial;
  EXPECT_TRUE(same_on_all_ranks(serial, hash_doubles(a.data(), 3)));
}

TEST(ThreadCommunicator, SumsGathersAndBroadcastsAcrossThreads) {
  constexpr int kRanks = 3;
  testing::ThreadHub hub(kRanks);
  std::vector<std::vector<double>> sums(kRanks), gathered(kRanks), broadcast(kRanks);
  std::vector<std::thread> threads;
  for (int r = 0; r < kRanks; ++r) {
    threads.emplace_back([&, r] {
      testing::ThreadCommunicator comm(hub, r);
      sums[r] = {static_cast<double>(r), 1.0};
      comm.allreduce_sum(sums[r]);
      const std::vector<double> mine(static_cast<std::size_t>(r), static_cast<double>(r));
      gathered[r] = comm.allgather(mine.data(), mine.size());
      broadcast[r] = {static_cast<double>(10 * r)};
      comm.broadcast(broadcast[r].data(), 1, 2);
    });
  }
  for (std::thread& t : threads) t.join();
  for (int r = 0; r < kRanks; ++r) {
    EXPECT_EQ(sums[r], (std::vector<double>{3.0, 3.0}));
    EXPECT_EQ(gathered[r], (std::vector<double>{1.0, 2.0, 2.0}));
    EXPECT_EQ(broadcast[r], (std::vector<double>{20.0}));
  }
}

TEST(ShardedJacobian, SumsTheNormalEquationsOnlyWhenThatMovesLessThanHalfTheData) {
  // Gathering B·m·n = 128·2·2 = 512 vs summing 2·(30·31/2 + 30) = 990: gather.
  EXPECT_FALSE(sums_normal_equations(128, 2, 2, 30));
  // B·m·n = 4096·2·2 = 16384 > 990: sum Jᵀ J.
  EXPECT_TRUE(sums_normal_equations(4096, 2, 2, 30));
}

// A problem like the trainer tests': a 2 → 6 → 2 tanh network (|θ| = 32) in front of
// P(x) = (x₀, x₁²).
struct Problem {
  ComparisonToy physics;
  L2Loss loss{1.0};
  LearningProblem problem{&physics, &loss};
  Dataset data;
  Mlp network{{2, 6, 2}, Activation::kTanh};

  explicit Problem(Index n) {
    network.initialize(5);
    data.inputs.resize(2, n);
    Matrix x_star(2, n);
    for (Index j = 0; j < n; ++j) {
      const double u = std::sin(1.3 * static_cast<double>(j));
      const double v = std::cos(0.7 * static_cast<double>(j));
      data.inputs.col(j) << u, v;
      x_star.col(j) << 0.5 + 0.4 * std::sin(2 * u), 0.5 + 0.4 * std::cos(3 * v);
    }
    data.targets = physics.forward_batch(x_star, Matrix());
  }
};

struct Outcome {
  TrainingSummary summary;
  Vector theta;
};

Outcome train_once(const Problem& p, const std::string& rule,
                   const RuleSettings& settings, TrainerOptions options,
                   std::shared_ptr<Communicator> communicator) {
  Outcome outcome;
  Mlp network = p.network;
  const auto update = make_learning_update(rule, settings);
  options.communicator = std::move(communicator);
  outcome.summary = train(network, *update, p.problem, p.data, &p.data, options);
  outcome.theta = network.parameters();
  return outcome;
}

// train() on `ranks` threads; every thread's history and θ.
std::vector<Outcome> train_on_threads(const Problem& p, const std::string& rule,
                                      const RuleSettings& settings,
                                      const TrainerOptions& options, int ranks) {
  testing::ThreadHub hub(ranks);
  std::vector<Outcome> outcomes(static_cast<std::size_t>(ranks));
  std::vector<std::thread> threads;
  for (int r = 0; r < ranks; ++r) {
    threads.emplace_back([&, r] {
      outcomes[static_cast<std::size_t>(r)] = train_once(
          p, rule, settings, options, std::make_shared<testing::ThreadCommunicator>(hub, r));
    });
  }
  for (std::thread& t : threads) t.join();
  return outcomes;
}

double largest_loss_difference(const TrainingSummary& a, const TrainingSummary& b) {
  EXPECT_EQ(a.history.size(), b.history.size());
  EXPECT_EQ(a.iterations, b.iterations);
  double worst = 0;
  for (std::size_t i = 0; i < std::min(a.history.size(), b.history.size()); ++i) {
    for (const auto& [x, y] : {std::pair{a.history[i].train_loss, b.history[i].train_loss},
                               std::pair{a.history[i].test_loss, b.history[i].test_loss}}) {
      worst = std::max(worst, std::abs(x - y) / std::max(std::abs(x), 1e-300));
    }
  }
  return worst;
}

struct Case {
  std::string rule;
  Index batch;
  double rcond;
  int ranks;
  double tolerance;
};

void PrintTo(const Case& c, std::ostream* out) {
  *out << c.rule << ", batch " << c.batch << ", rcond " << c.rcond << ", " << c.ranks << " ranks";
}

std::string case_name(const ::testing::TestParamInfo<Case>& param_info) {
  const Case& c = param_info.param;
  std::string rule = c.rule;
  std::replace(rule.begin(), rule.end(), '-', '_');  // test names take no '-'
  return rule + "_batch" + std::to_string(c.batch) + "_ranks" + std::to_string(c.ranks) + "_" +
         std::to_string(param_info.index);
}

class ThreadRanks : public ::testing::TestWithParam<Case> {};

TEST_P(ThreadRanks, MatchOneProcessAndKeepParametersIdentical) {
  const Case& c = GetParam();
  const Problem p(c.batch > 64 ? 320 : 40);
  RuleSettings settings;
  settings["rcond"] = c.rcond;
  if (settings_source(c.rule) == "hig") settings["lr"] = 0.3;
  if (settings_source(c.rule) == "gn") settings["lr"] = 0.1;
  TrainerOptions options;
  options.batch_size = c.batch;
  options.max_iterations = 12;
  options.eval_every = 3;
  options.seed = 7;

  const Outcome single = train_once(p, c.rule, settings, options, nullptr);
  ASSERT_EQ(single.summary.termination, TrainingTermination::kMaxIterations) << single.summary.message;
  EXPECT_LT(single.summary.history.back().train_loss, single.summary.history.front().train_loss);
  const std::vector<Outcome> ranks = train_on_threads(p, c.rule, settings, options, c.ranks);
  for (const Outcome& rank : ranks) {
    EXPECT_EQ(rank.summary.termination, TrainingTermination::kMaxIterations) << rank.summary.message;
    EXPECT_LE(largest_loss_difference(single.summary, rank.summary), c.tolerance);
    // Bit-identical parameters on every rank.
    EXPECT_EQ(hash_doubles(rank.theta.data(), static_cast<std::size_t>(rank.theta.size())),
              hash_doubles(ranks.front().theta.data(),
                           static_cast<std::size_t>(ranks.front().theta.size())));
  }
}

// B·m = 8·2 = 16 ≤ |θ| = 32: Gram path; 24·2 = 48 > 32: normal path with gathered cotangents;
// τ = 1e-10: SVD path; 320·2·2 = 1280 > 2·(32·33/2 + 32) = 1120: normal path summing Jᵀ J,
// exact only up to rounding amplified by the kept spectrum (τ = 1e-2 keeps it tame).
INSTANTIATE_TEST_SUITE_P(
    Rules, ThreadRanks,
    ::testing::Values(Case{"sgd", 10, 1e-6, 2, 1e-10}, Case{"adam", 10, 1e-6, 3, 1e-10},
                      Case{"sip", 10, 1e-6, 2, 1e-10}, Case{"hig", 8, 1e-6, 2, 1e-10},
                      Case{"gn", 8, 1e-6, 3, 1e-10}, Case{"hig", 24, 1e-6, 2, 1e-10},
                      Case{"hig", 8, 1e-10, 3, 1e-10}, Case{"hig", 2, 1e-6, 3, 1e-10},
                      Case{"hig", 320, 1e-2, 2, 1e-9}),
    case_name);

// The structured rules see the ranks' Jacobian only through J w, Jᵀc and the layer factors, which
// every rank forms from the gathered cotangents as one process does (kfac with its factors
// refreshed every 10 steps; a batch of 2 on 3 ranks leaves one rank without samples).
INSTANTIATE_TEST_SUITE_P(
    StructuredRules, ThreadRanks,
    ::testing::Values(Case{"kfac", 8, 1e-6, 2, 1e-10}, Case{"kfac-hig", 10, 1e-6, 3, 1e-10},
                      Case{"kfac-hig", 2, 1e-6, 3, 1e-10}, Case{"lanczos-gn", 8, 1e-6, 3, 1e-10},
                      Case{"lanczos-hig", 24, 1e-6, 2, 1e-10},
                      Case{"lanczos-hig", 2, 1e-6, 3, 1e-10}),
    case_name);

// The doubles one step exchanges, as docs/distributed.md counts them (B = 8, m = 2, n = 2,
// |θ| = 32): the batch loss (1), then ∇θ (|θ|) for adam; ∂L/∂y (B·m), the output cotangents
// (B·m·n) and the Jᵀc cotangents (B·n) for hig on the Gram path.
TEST(DataParallel, ExchangesWhatTheModelCounts) {
  const Problem p(40);
  const std::vector<Index> indices = {3, 1, 4, 15, 9, 2, 6, 5};
  for (const std::string rule : {"adam", "hig"}) {
    constexpr int kRanks = 2;
    testing::ThreadHub hub(kRanks);
    std::vector<double> exchanged(kRanks);
    std::vector<Vector> deltas(kRanks);
    std::vector<std::thread> threads;
    for (int r = 0; r < kRanks; ++r) {
      threads.emplace_back([&, r] {
        const Shard shard(std::make_shared<testing::ThreadCommunicator>(hub, r));
        const auto update = make_learning_update(rule);
        MlpCache cache;
        const BatchState batch = evaluate_batch(p.network, p.problem, p.data.select(indices),
                                                update->need(), cache, shard);
        deltas[static_cast<std::size_t>(r)] = update->step(batch).delta;
        exchanged[static_cast<std::size_t>(r)] = shard.exchanged_doubles();
      });
    }
    for (std::thread& t : threads) t.join();
    const double expected = rule == "adam" ? 1 + 32 : 1 + 8 * 2 + 8 * 2 * 2 + 8 * 2;
    EXPECT_EQ(exchanged[0], expected) << rule;
    EXPECT_EQ(exchanged[1], expected) << rule;
    EXPECT_EQ(deltas[0], deltas[1]) << rule;
    // The same step as one process on the whole batch.
    MlpCache cache;
    const auto update = make_learning_update(rule);
    const BatchState whole =
        evaluate_batch(p.network, p.problem, p.data.select(indices), update->need(), cache);
    const Vector alone = update->step(whole).delta;
    EXPECT_LE((alone - deltas[0]).norm(), 1e-12 * alone.norm()) << rule;
  }
}

TEST(DataParallel, OneRankIsTheOneProcessPath) {
  const Problem p(40);
  TrainerOptions options;
  options.batch_size = 8;
  options.max_iterations = 6;
  options.eval_every = 2;
  for (const std::string rule : {"adam", "hig"}) {
    const Outcome alone = train_once(p, rule, {}, options, nullptr);
    const Outcome serial =
        train_once(p, rule, {}, options, std::make_shared<SerialCommunicator>());
    EXPECT_EQ(alone.theta, serial.theta) << rule;
    EXPECT_EQ(largest_loss_difference(alone.summary, serial.summary), 0.0) << rule;
  }
  EXPECT_FALSE(Shard(std::make_shared<SerialCommunicator>()).active());
  EXPECT_FALSE(Shard().active());
}

}  // namespace
}  // namespace physgrad
