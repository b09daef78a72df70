// The training loop: limits, evaluation schedule, determinism, the numerical guard through
// train() (NaN injected into the physics, the rule, the evaluation) and bit-identical resume.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>

#include "learning_fixture.hpp"
#include "physgrad/error.hpp"
#include "physgrad/physics/diagonal_scale.hpp"
#include "physgrad/text.hpp"
#include "test_problems.hpp"

namespace physgrad {
namespace {

using testing::NetworkThroughPhysics;
using testing::test_settings;

TrainerOptions limits(long long iterations) {
  TrainerOptions options;
  options.batch_size = 4;
  options.max_iterations = iterations;
  options.eval_every = 5;
  return options;
}

TEST(Trainer, EveryRuleLowersTheLossAndRunsAreDeterministic) {
  for (const std::string& id : rule_ids(RuleKind::kLearning)) {
    NetworkThroughPhysics a(32), b(32);
    b.data = a.data;
    const auto ua = make_learning_update(id, test_settings(id));
    const auto ub = make_learning_update(id, test_settings(id));
    const TrainingSummary sa = train(a.network, *ua, a.problem, a.data, nullptr, limits(40));
    const TrainingSummary sb = train(b.network, *ub, b.problem, b.data, nullptr, limits(40));
    EXPECT_EQ(sa.termination, TrainingTermination::kMaxIterations) << id;
    EXPECT_EQ(sa.iterations, 40) << id;
    EXPECT_LT(sa.history.back().train_loss, sa.history.front().train_loss) << id;
    EXPECT_EQ(a.network.parameters(), b.network.parameters()) << id;
    // Evaluations at the start and every 5 iterations.
    ASSERT_EQ(sa.history.size(), 9u) << id;
    EXPECT_EQ(sa.history[3].iteration, 15) << id;
    EXPECT_TRUE(std::isnan(sa.history.back().test_loss)) << id;
  }
}

TEST(Trainer, TheSummarySaysWhatRanAndReportsItLikeMinimize) {
  NetworkThroughPhysics s(10);
  const auto update = make_learning_update("hig");
  const TrainingSummary summary = train(s.network, *update, s.problem, s.data, nullptr, limits(6));
  EXPECT_EQ(summary.update, "hig");
  EXPECT_EQ(summary.params, update->params());
  EXPECT_EQ(summary.parameters, s.network.num_parameters());
  EXPECT_EQ(summary.samples, 10);
  ASSERT_EQ(summary.phases.size(), 1u);
  EXPECT_EQ(summary.phases[0].batch_size, 4);
  ASSERT_EQ(summary.limits.size(), 1u);
  EXPECT_EQ(summary.limits[0].first, "max_iterations");
  // Two epochs of batches of 4, 4 and 2 samples: each sample once forward and through the m
  // VJPs of the stacked Jacobian (Jᵀc on the Gram path reuses their cotangents).
  const long long m = s.physics.output_dim();
  EXPECT_EQ(summary.counts.forward, 20);
  EXPECT_EQ(summary.counts.vjp, 20 * m);
  EXPECT_EQ(summary.counts.passes, summary.counts.forward + summary.counts.vjp);
  EXPECT_EQ(brief_report(summary),
            "hig: 6 iterations (2.4 epochs), " + std::to_string(summary.counts.passes) +
                " simulator passes, train loss " + report_number(summary.history.front().train_loss) +
                " → " + report_number(summary.history.back().train_loss) + ", max_iterations");
  const std::string full = full_report(summary);
  for (const std::string part :
       {"physgrad training report", "  parameters", "  kappa                   0.5",
        "  max_iterations          6", "  iterations              6", "  step halvings           0",
        "\nTermination: max_iterations\n"}) {
    EXPECT_NE(full.find(part), std::string::npos) << part << "\n" << full;
  }
  // A checkpoint keeps the counts.
  EXPECT_EQ(training_summary_from_json(training_summary_to_json(summary)).counts, summary.counts);
}

TEST(Trainer, StopsAfterEpochsAndEvaluatesOncePerEpochByDefault) {
  NetworkThroughPhysics s(10);
  TrainerOptions options;
  options.batch_size = 4;  // 3 batches per epoch, the last one of 2 samples
  options.max_epochs = 2;
  const auto update = make_learning_update("adam");
  const TrainingSummary summary = train(s.network, *update, s.problem, s.data, &s.data, options);
  EXPECT_EQ(summary.termination, TrainingTermination::kMaxEpochs);
  EXPECT_EQ(summary.iterations, 6);
  ASSERT_EQ(summary.history.size(), 3u);
  EXPECT_DOUBLE_EQ(summary.history[1].epoch, 1.2);  // 3 batches of 4 over 10 samples
  EXPECT_DOUBLE_EQ(summary.history[2].train_loss, summary.history[2].test_loss);
}

TEST(Trainer, NonFiniteLossStopsTrainingWithFiniteParameters) {
  const testing::Bounded physics(1e3);
  const L2Loss loss;
  Mlp network({1, 1}, Activation::kTanh);
  network.initialize(0);
  Dataset data{Matrix::Ones(1, 8), Matrix::Constant(1, 8, 5e3), Matrix()};
  const auto update = make_learning_update("sgd", {{"lr", 0.4}});
  const TrainingSummary summary =
      train(network, *update, {&physics, &loss}, data, nullptr, limits(1000));
  EXPECT_EQ(summary.termination, TrainingTermination::kNumericalFailure);
  EXPECT_NE(summary.message.find("non-finite loss"), std::string::npos) << summary.message;
  EXPECT_NE(summary.message.find("undone"), std::string::npos) << summary.message;
  EXPECT_LT(summary.iterations, 1000);
  EXPECT_TRUE(all_finite(network.parameters()));
  // The final evaluation is of the restored parameters, whose loss is finite.
  EXPECT_TRUE(std::isfinite(summary.history.back().train_loss));
}

TEST(Trainer, InvertedStepsThatBreakTheNextBatchAreRetriedAtHalfLength) {
  // Gauss-Newton at 4× its full step (η = 4B, as ∂(mean L)/∂y carries 1/B) overshoots the
  // target 900 to 3600, past the bound; two halvings bring the step back to 900.
  const testing::Bounded physics(1e3);
  const L2Loss loss;
  Mlp network({1, 1}, Activation::kTanh);
  network.initialize(0);
  const Dataset data{Matrix::Ones(1, 8), Matrix::Constant(1, 8, 900.0), Matrix()};
  const auto gn = make_learning_update("gn", {{"lr", 16.0}});
  const TrainingSummary summary = train(network, *gn, {&physics, &loss}, data, nullptr, limits(20));
  EXPECT_EQ(summary.termination, TrainingTermination::kMaxIterations) << summary.message;
  EXPECT_GE(summary.step_halvings, 2);
  EXPECT_LT(summary.history.back().train_loss, 1e-12 * summary.history.front().train_loss);

  // Without halvings allowed the same run stops at the first broken batch, undoing that step.
  network.initialize(0);
  TrainerOptions no_retry = limits(20);
  no_retry.max_step_halvings = 0;
  const TrainingSummary stopped = train(network, *gn, {&physics, &loss}, data, nullptr, no_retry);
  EXPECT_EQ(stopped.termination, TrainingTermination::kNumericalFailure);
  EXPECT_EQ(stopped.iterations, 1);
  EXPECT_NE(stopped.message.find("update 1 undone"), std::string::npos) << stopped.message;
  EXPECT_TRUE(std::isfinite(stopped.history.back().train_loss));
}

TEST(Trainer, NonFiniteTestLossRestoresTheLastEvaluatedParameters) {
  // Training on inputs 1 towards 50 drives the test outputs (inputs 100) past the bound
  // while every training batch stays finite.
  const testing::Bounded physics(1e3);
  const L2Loss loss;
  Mlp network({1, 1}, Activation::kTanh);
  network.initialize(0);
  const Dataset train_set{Matrix::Ones(1, 8), Matrix::Constant(1, 8, 50.0), Matrix()};
  const Dataset test_set{Matrix::Constant(1, 4, 100.0), Matrix::Constant(1, 4, 5e3), Matrix()};
  const auto adam = make_learning_update("adam", {{"lr", 0.5}});
  const TrainingSummary summary =
      train(network, *adam, {&physics, &loss}, train_set, &test_set, limits(500));
  EXPECT_EQ(summary.termination, TrainingTermination::kNumericalFailure);
  EXPECT_NE(summary.message.find("non-finite test loss"), std::string::npos) << summary.message;
  ASSERT_GE(summary.history.size(), 2u);
  for (const TrainingRecord& r : summary.history) {
    EXPECT_TRUE(std::isfinite(r.train_loss) && std::isfinite(r.test_loss)) << r.iteration;
  }
  // θ is the one of the last record, whose test loss was finite.
  EXPECT_DOUBLE_EQ(mean_loss(network, {&physics, &loss}, test_set),
                   summary.history.back().test_loss);
  EXPECT_GT(summary.iterations, summary.history.back().iteration);
}

// P(x) = x with NaN injected from the `from`-th call of forward_batch or vjp_batch on (calls
// before it are clean), for `count` calls.
class Poisoned final : public Simulator {
 public:
  enum class Where { kForward, kVjp };
  Poisoned(Where where, int from, int count) : where_(where), from_(from), count_(count) {}
  std::string name() const override { return "poisoned"; }
  Index input_dim() const override { return 2; }
  Index output_dim() const override { return 2; }
  Matrix forward_batch(const Matrix& x, const Matrix&) const override {
    return where_ == Where::kForward ? poison(x) : x;
  }
  Matrix vjp_batch(const Matrix&, const Matrix&, const Matrix& gy) const override {
    return where_ == Where::kVjp ? poison(gy) : gy;
  }

 private:
  Matrix poison(const Matrix& m) const {
    const int call = calls_++;
    return call >= from_ && call < from_ + count_ ? Matrix::Constant(m.rows(), m.cols(), NAN) : m;
  }
  Where where_;
  int from_, count_;
  mutable int calls_ = 0;
};

// An update rule whose 4th step is NaN.
class NanStep final : public LearningUpdate {
 public:
  std::string id() const override { return "nan-step"; }
  nlohmann::json params() const override { return nlohmann::json::object(); }
  UpdateNeed need() const override { return UpdateNeed::kGradient; }
  Step step(const BatchState& batch) override {
    const Vector delta = -0.1 * batch.gradient;
    return {++steps_ == 4 ? Vector::Constant(delta.size(), NAN) : delta};
  }
  double learning_rate() const override { return 0.1; }
  void set_learning_rate(double) override {}

 private:
  int steps_ = 0;
};

TEST(Trainer, InjectedNonFiniteNumbersNeverReachTheParametersOrTheHistory) {
  const L2Loss loss;
  Dataset data{Matrix::Random(2, 16), Matrix::Random(2, 16), Matrix()};
  struct Case {
    std::string rule;
    Poisoned::Where where;
    int from, count;
    std::string expected;  // in the message; empty: training recovers
  };
  // Forward calls: the evaluation of the training set (call 0, then after every 5 iterations)
  // and one per batch; SIP's numerical inverses add theirs after the batch's.
  const std::vector<Case> cases = {
      {"adam", Poisoned::Where::kForward, 8, 1000, "non-finite loss"},
      {"adam", Poisoned::Where::kVjp, 5, 1000, "non-finite gradient"},
      {"sip", Poisoned::Where::kForward, 1, 1000, "non-finite loss at iteration 1"},
      {"sip", Poisoned::Where::kForward, 2, 1000, "non-finite update at iteration 1"},
      {"hig", Poisoned::Where::kVjp, 10, 1000, "also after halving"},  // Jacobian rows
      {"gn", Poisoned::Where::kForward, 9, 1000, "also after halving"},
      {"hig", Poisoned::Where::kVjp, 10, 2, ""},  // a passing fault: halving recovers
  };
  for (const Case& c : cases) {
    const Poisoned physics(c.where, c.from, c.count);
    Mlp network({2, 5, 2}, Activation::kTanh);
    network.initialize(2);
    const auto update = make_learning_update(c.rule, test_settings(c.rule));
    const TrainingSummary summary =
        train(network, *update, {&physics, &loss}, data, nullptr, limits(30));
    const std::string what = c.rule + " from call " + std::to_string(c.from);
    EXPECT_TRUE(all_finite(network.parameters())) << what;
    for (const TrainingRecord& r : summary.history) {
      EXPECT_TRUE(std::isfinite(r.train_loss)) << what << " at " << r.iteration;
    }
    if (c.expected.empty()) {
      EXPECT_EQ(summary.termination, TrainingTermination::kMaxIterations) << what << ": " << summary.message;
      EXPECT_GE(summary.step_halvings, 1) << what;
    } else {
      EXPECT_EQ(summary.termination, TrainingTermination::kNumericalFailure) << what;
      EXPECT_NE(summary.message.find(c.expected), std::string::npos) << what << ": " << summary.message;
    }
  }
  // A non-finite step from the rule itself is not applied.
  const Poisoned clean(Poisoned::Where::kForward, 1 << 30, 0);
  Mlp network({2, 5, 2}, Activation::kTanh);
  network.initialize(2);
  NanStep nan_step;
  const TrainingSummary summary = train(network, nan_step, {&clean, &loss}, data, nullptr, limits(30));
  EXPECT_EQ(summary.termination, TrainingTermination::kNumericalFailure);
  EXPECT_EQ(summary.iterations, 3);
  EXPECT_NE(summary.message.find("non-finite update at iteration 4; the step was not applied"),
            std::string::npos)
      << summary.message;
  EXPECT_TRUE(all_finite(network.parameters()));
}

TEST(Trainer, UntrainedNetworkWithNonFiniteLossIsAnError) {
  const testing::Bounded physics(1e3);
  const L2Loss loss;
  Mlp network({1, 1}, Activation::kTanh);
  network.initialize(0);
  network.bias(0)[0] = 2e3;
  const Dataset data{Matrix::Ones(1, 4), Matrix::Zero(1, 4), Matrix()};
  const auto adam = make_learning_update("adam");
  EXPECT_THROW(train(network, *adam, {&physics, &loss}, data, nullptr, limits(5)), Error);
}

TEST(Trainer, StateFromJsonRejectsStatesThatDoNotFit) {
  NetworkThroughPhysics s(12);
  std::string saved;
  TrainerOptions options = limits(6);
  options.checkpoint_every = 4;
  options.on_checkpoint = [&saved](const TrainerState& state) {
    saved = trainer_state_to_json(state).dump();
  };
  const auto adam = make_learning_update("adam");
  train(s.network, *adam, s.problem, s.data, nullptr, options);
  const nlohmann::json good = nlohmann::json::parse(saved);
  const Index count = s.network.num_parameters();
  EXPECT_NO_THROW(trainer_state_from_json(good, count));
  EXPECT_THROW(trainer_state_from_json(good, count + 1), Error);
  const auto rejects = [&](const std::function<void(nlohmann::json&)>& change) {
    nlohmann::json bad = good;
    change(bad);
    EXPECT_THROW(trainer_state_from_json(bad, count), Error) << bad.dump().substr(0, 200);
  };
  rejects([](nlohmann::json& d) { d.erase("parameters"); });
  rejects([](nlohmann::json& d) { d["parameters"][0] = "x"; });
  rejects([](nlohmann::json& d) { d["epoch"] = -1; });
  rejects([](nlohmann::json& d) { d["epoch"] = 1.5; });
  rejects([](nlohmann::json& d) { d["summary"]["history"] = nlohmann::json::array(); });
  rejects([](nlohmann::json& d) { d["summary"]["train_seconds"] = -3; });
  rejects([](nlohmann::json& d) { d["summary"]["history"][0]["train_loss"] = nullptr; });
  rejects([](nlohmann::json& d) { d["last_step"].erase(0); });

  // A state that parses but does not fit the run: batch start beyond the data.
  TrainerState state = trainer_state_from_json(good, count);
  state.batch_start = 400;
  TrainerOptions resume = limits(6);
  resume.resume = &state;
  EXPECT_THROW(train(s.network, *adam, s.problem, s.data, nullptr, resume), Error);
  // Adam moments of the wrong size.
  state = trainer_state_from_json(good, count);
  state.update_state["m"] = nlohmann::json::array({1.0});
  EXPECT_THROW(train(s.network, *adam, s.problem, s.data, nullptr, resume), Error);
}
// With eval_seconds, a run limited by time is evaluated at least that much training time apart
// (besides the iteration schedule, here too sparse to matter), and never does it otherwise.
// The budget is wall time, of which the steps of this tiny network took about a third in a run
// on a loaded machine (0.2 s gave 3 evaluations by time): 0.5 s leaves room for six.
TEST(Trainer, EvaluatesByTrainingTimeWhenAsked) {
  NetworkThroughPhysics s(32);
  TrainerOptions options;
  options.batch_size = 4;
  options.time_budget_seconds = 0.5;
  options.eval_every = 1'000'000'000;
  options.eval_seconds = 0.02;
  const auto update = make_learning_update("adam");
  const TrainingSummary summary = train(s.network, *update, s.problem, s.data, nullptr, options);
  EXPECT_EQ(summary.termination, TrainingTermination::kTimeBudget);
  ASSERT_GE(summary.history.size(), 6u);
  for (std::size_t k = 1; k + 1 < summary.history.size(); ++k) {
    EXPECT_GE(summary.history[k].train_seconds - summary.history[k - 1].train_seconds, 0.02) << k;
    EXPECT_GT(summary.history[k].iteration, summary.history[k - 1].iteration) << k;
  }
  EXPECT_EQ(summary.history.back().iteration, summary.iterations);

  // Without eval_seconds only the start and the end are evaluated.
  NetworkThroughPhysics t(32);
  options.eval_seconds.reset();
  const TrainingSummary plain = train(t.network, *update, t.problem, t.data, nullptr, options);
  EXPECT_EQ(plain.history.size(), 2u);
  options.eval_seconds = 0.0;
  EXPECT_THROW(train(t.network, *update, t.problem, t.data, nullptr, options), Error);
}

TEST(Trainer, RejectsMismatchedDataAndMissingLimits) {
  NetworkThroughPhysics s;
  const auto update = make_learning_update("adam");
  Dataset wrong = s.data;
  wrong.targets = Matrix::Zero(3, s.data.size());
  EXPECT_THROW(train(s.network, *update, s.problem, wrong, nullptr, limits(1)), Error);
  wrong = s.data;
  wrong.inputs(0, 0) = NAN;
  EXPECT_THROW(train(s.network, *update, s.problem, wrong, nullptr, limits(1)), Error);
  EXPECT_THROW(train(s.network, *update, s.problem, s.data, nullptr, TrainerOptions{}), Error);
  const DiagonalScale three(Vector::Ones(3));
  const LearningProblem mismatch{&three, &s.loss};
  EXPECT_THROW(train(s.network, *update, mismatch, s.data, nullptr, limits(1)), Error);
}

}  // namespace
}  // namespace physgrad
