// Learning: the batch derivatives the trainer computes (∇θ and the stacked Jacobian of
// network + physics) against finite differences, the update rules, and the training loop's
// limits, determinism and numerical guard.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <functional>

#include "physgrad/autodiff/finite_difference.hpp"
#include "physgrad/error.hpp"
#include "physgrad/physics/comparison_toy.hpp"
#include "physgrad/physics/diagonal_scale.hpp"
#include "physgrad/threads.hpp"
#include "physgrad/train/trainer.hpp"

namespace physgrad {
namespace {

// A 2 → 6 → 2 tanh network in front of the nonlinear comparison function P(x) = (x₀, x₁²).
struct NetworkThroughPhysics {
  ComparisonToy physics;
  L2Loss loss{1.0};
  LearningProblem problem{&physics, &loss};
  Mlp network{{2, 6, 2}, Activation::kTanh};
  Dataset data;

  // Reachable targets: y* = P(x*) with x* = (sin 2u, cos 3v) of the input (u, v).
  explicit NetworkThroughPhysics(Index n = 5) {
    network.initialize(3);
    data.inputs.resize(2, n);
    Matrix x_star(2, n);
    for (Index j = 0; j < n; ++j) {
      const double u = std::sin(1.3 * static_cast<double>(j)), v = std::cos(0.7 * static_cast<double>(j));
      data.inputs.col(j) << u, v;
      x_star.col(j) << std::sin(2 * u), std::cos(3 * v);
    }
    data.targets = physics.forward_batch(x_star, Matrix());
  }

  // Stacked outputs y(θ) in the trainer's order (entry k·B + i).
  Vector stacked_outputs(const Vector& theta) const {
    Mlp copy = network;
    copy.set_parameters(theta);
    const Matrix y = physics.forward_batch(copy.forward(data.inputs), data.context);
    return y.transpose().reshaped();
  }
};

TEST(EvaluateBatch, StackedJacobianMatchesFiniteDifferences) {
  NetworkThroughPhysics s;
  MlpCache cache;
  const BatchState state =
      evaluate_batch(s.network, s.problem, s.data, UpdateNeed::kStackedJacobian, cache);
  const Matrix expected = finite_difference_jacobian(
      [&](const Vector& theta) { return s.stacked_outputs(theta); }, s.network.parameters());
  const Matrix j = state.jacobian->materialize();
  ASSERT_EQ(j.rows(), 2 * s.data.size());
  EXPECT_LT((j - expected).cwiseAbs().maxCoeff(), 1e-7);
}

// The factored forms agree with the formed J: J Jᵀ from the layer factors, Jᵀc by one backward.
TEST(EvaluateBatch, FactoredGramAndTransposeProductMatchTheFormedJacobian) {
  NetworkThroughPhysics s(7);
  MlpCache cache;
  const BatchState state =
      evaluate_batch(s.network, s.problem, s.data, UpdateNeed::kStackedJacobian, cache);
  const Matrix j = state.jacobian->materialize();
  const Matrix expected = j * j.transpose();
  EXPECT_LT((state.jacobian->gram() - expected).cwiseAbs().maxCoeff(),
            1e-13 * expected.cwiseAbs().maxCoeff());
  const Vector c = Vector::LinSpaced(j.rows(), -1.0, 2.0);
  EXPECT_LT((state.jacobian->apply_transpose(c) - j.transpose() * c).norm(),
            1e-13 * (j.transpose() * c).norm());
}

// The physics VJPs on several threads give bit-identical results: each output's VJP is
// computed by one thread into its own matrix.
TEST(EvaluateBatch, StackedJacobianIsTheSameOnAnyNumberOfThreads) {
  NetworkThroughPhysics s(9);
  const auto gram_and_transpose = [&](int threads) {
    set_jacobian_threads(threads);
    MlpCache cache;
    const BatchState state =
        evaluate_batch(s.network, s.problem, s.data, UpdateNeed::kStackedJacobian, cache);
    const Vector c = Vector::LinSpaced(state.jacobian->rows(), -1.0, 2.0);
    return std::make_pair(state.jacobian->gram(), state.jacobian->apply_transpose(c));
  };
  const auto one = gram_and_transpose(1);
  for (const int threads : {2, 3}) {
    const auto many = gram_and_transpose(threads);
    EXPECT_TRUE(many.first == one.first) << threads << " threads";
    EXPECT_TRUE(many.second == one.second) << threads << " threads";
  }
  set_jacobian_threads(1);
  EXPECT_GT(one.first.norm(), 0.0);
}

TEST(EvaluateBatch, GradientMatchesFiniteDifferencesAndTheJacobianPath) {
  NetworkThroughPhysics s;
  MlpCache cache;
  const BatchState with_gradient =
      evaluate_batch(s.network, s.problem, s.data, UpdateNeed::kGradient, cache);
  const auto mean = [&](const Vector& theta) {
    Mlp copy = s.network;
    copy.set_parameters(theta);
    return Vector::Constant(1, mean_loss(copy, s.problem, s.data));
  };
  const Matrix expected = finite_difference_jacobian(mean, s.network.parameters());
  EXPECT_LT((with_gradient.gradient - expected.row(0).transpose()).cwiseAbs().maxCoeff(), 1e-8);
  EXPECT_NEAR(with_gradient.loss, mean(s.network.parameters())(0), 1e-14);

  // Jᵀ ∂(mean L)/∂y is the same gradient.
  const BatchState with_jacobian =
      evaluate_batch(s.network, s.problem, s.data, UpdateNeed::kStackedJacobian, cache);
  EXPECT_LT((with_jacobian.jacobian->materialize().transpose() * with_jacobian.loss_gradient_y -
             with_gradient.gradient)
                .norm(),
            1e-12);
}

TEST(LearningUpdates, JacobianInverseRulesApplyTheirPowerOfJ) {
  NetworkThroughPhysics s;
  MlpCache cache;
  const BatchState state =
      evaluate_batch(s.network, s.problem, s.data, UpdateNeed::kStackedJacobian, cache);
  // κ = 1 (gn) is −η J⁺ g; κ = ½ (hig) is −η V Σ^{−½} Uᵀ g from an independent SVD.
  const Eigen::JacobiSVD<Matrix> svd(state.jacobian->materialize(),
                                     Eigen::ComputeThinU | Eigen::ComputeThinV);
  const Vector& sigma = svd.singularValues();
  const auto expected = [&](double kappa) {
    Vector c = svd.matrixU().transpose() * state.loss_gradient_y;
    for (Index i = 0; i < c.size(); ++i) {
      c(i) = sigma(i) > 1e-6 * sigma(0) ? c(i) * std::pow(sigma(i), -kappa) : 0.0;
    }
    return Vector(-0.5 * svd.matrixV() * c);
  };
  for (const auto& [id, kappa] : {std::pair{"gn", 1.0}, std::pair{"hig", 0.5}}) {
    LearningUpdateSettings settings;
    settings.lr = 0.5;
    settings.rcond = 1e-6;
    settings.backend = PinvBackend::kSvd;  // the Gram paths square the spectrum (power_pinv_test)
    const Vector delta = make_learning_update(id, settings)->step(state).delta;
    EXPECT_LT((delta - expected(kappa)).norm(), 1e-9 * expected(kappa).norm()) << id;
    // The factored Gram path (J never formed) gives the same update within what squaring the
    // spectrum costs: ε·(σ_max/σ_min,kept)², here well below 1e-6.
    settings.backend = PinvBackend::kGram;
    const Vector factored = make_learning_update(id, settings)->step(state).delta;
    EXPECT_LT((factored - expected(kappa)).norm(), 1e-6 * expected(kappa).norm()) << id;
  }
  EXPECT_THROW(make_learning_update("lbfgs"), Error);
}

// On an invertible linear simulator, x̃ = P⁻¹(y + η(y* − y)) = x + η(P⁻¹y* − x) in closed form,
// so one SIP step is Adam on the gradient of mean ½‖f(in; θ) − x̃‖² with that x̃.
TEST(SipUpdate, OneStepOnALinearSimulatorIsAdamOnTheClosedFormProxyGradient) {
  const DiagonalScale physics(Vector{{2.0, -0.5}});
  const L2Loss loss;
  Mlp network({2, 4, 2}, Activation::kTanh);
  network.initialize(5);
  Dataset data{Matrix(2, 3), Matrix(2, 3), Matrix()};
  data.inputs << 0.1, -0.4, 0.8, 0.3, 0.5, -0.2;
  data.targets << 1.0, -2.0, 0.5, 0.25, 0.0, -1.0;
  for (const double eta : {1.0, 0.5}) {
    const Matrix x = network.forward(data.inputs);
    const Matrix x_tilde =
        x + eta * (physics.scales().cwiseInverse().asDiagonal() * data.targets - x);
    const auto proxy = [&](const Vector& theta) {
      Mlp copy = network;
      copy.set_parameters(theta);
      return Vector::Constant(1, 0.5 * (copy.forward(data.inputs) - x_tilde).squaredNorm() / 3);
    };
    const Vector gradient =
        finite_difference_jacobian(proxy, network.parameters()).row(0).transpose();
    AdamState adam({0.01});
    const Vector expected = adam.update(gradient);

    MlpCache cache;
    const BatchState state = evaluate_batch(network, {&physics, &loss}, data,
                                            UpdateNeed::kNetworkOutputs, cache);
    SipOptions options;
    options.adam.lr = 0.01;
    options.y_step = eta;
    SipUpdate sip(options);
    const Vector delta = sip.step(state).delta;
    // Adam's first step is lr·g/(|g| + ε) per component, insensitive to the FD error in g.
    EXPECT_LT((delta - expected).cwiseAbs().maxCoeff(), 1e-6) << "eta " << eta;
  }
}

TEST(SipUpdate, NumericalLocalInverseGivesTheAnalyticStep) {
  NetworkThroughPhysics s;  // ComparisonToy's analytic inverse against L-BFGS on ½‖P(x) − y‖²
  MlpCache cache;
  const BatchState state =
      evaluate_batch(s.network, s.problem, s.data, UpdateNeed::kNetworkOutputs, cache);
  LearningUpdateSettings analytic, numeric;
  analytic.inverse = InverseMethod::kAnalytic;
  numeric.inverse = InverseMethod::kLbfgs;
  const Vector a = make_learning_update("sip", analytic)->step(state).delta;
  const Vector b = make_learning_update("sip", numeric)->step(state).delta;
  EXPECT_LT((a - b).cwiseAbs().maxCoeff(), 1e-6);
}

TrainerOptions limits(long long iterations) {
  TrainerOptions options;
  options.batch_size = 4;
  options.max_iterations = iterations;
  options.eval_every = 5;
  return options;
}

TEST(Trainer, EveryRuleLowersTheLossAndRunsAreDeterministic) {
  for (const std::string& id : learning_update_ids()) {
    NetworkThroughPhysics a(32), b(32);
    b.data = a.data;
    LearningUpdateSettings settings;
    if (id == "gn" || id == "hig") settings.lr = 0.1;
    const auto ua = make_learning_update(id, settings), ub = make_learning_update(id, settings);
    const TrainingSummary sa = train(a.network, *ua, a.problem, a.data, nullptr, limits(40));
    const TrainingSummary sb = train(b.network, *ub, b.problem, b.data, nullptr, limits(40));
    EXPECT_EQ(sa.termination, "max_iterations") << id;
    EXPECT_EQ(sa.iterations, 40) << id;
    EXPECT_LT(sa.history.back().train_loss, sa.history.front().train_loss) << id;
    EXPECT_EQ(a.network.parameters(), b.network.parameters()) << id;
    // Evaluations at the start and every 5 iterations.
    ASSERT_EQ(sa.history.size(), 9u) << id;
    EXPECT_EQ(sa.history[3].iteration, 15) << id;
    EXPECT_TRUE(std::isnan(sa.history.back().test_loss)) << id;
  }
}

TEST(Trainer, StopsAfterEpochsAndEvaluatesOncePerEpochByDefault) {
  NetworkThroughPhysics s(10);
  TrainerOptions options;
  options.batch_size = 4;  // 3 batches per epoch, the last one of 2 samples
  options.max_epochs = 2;
  const auto update = make_learning_update("adam");
  const TrainingSummary summary = train(s.network, *update, s.problem, s.data, &s.data, options);
  EXPECT_EQ(summary.termination, "max_epochs");
  EXPECT_EQ(summary.iterations, 6);
  ASSERT_EQ(summary.history.size(), 3u);
  EXPECT_DOUBLE_EQ(summary.history[1].epoch, 1.2);  // 3 batches of 4 over 10 samples
  EXPECT_DOUBLE_EQ(summary.history[2].train_loss, summary.history[2].test_loss);
}

// P(x) = x, except NaN once the output exceeds a bound (1e3).
class Fragile final : public Simulator {
 public:
  std::string name() const override { return "fragile"; }
  Index input_dim() const override { return 1; }
  Index output_dim() const override { return 1; }
  Matrix forward_batch(const Matrix& x, const Matrix&) const override {
    return x.unaryExpr([](double v) { return v > 1e3 ? NAN : v; });
  }
  Matrix vjp_batch(const Matrix&, const Matrix&, const Matrix& gy) const override { return gy; }
};

TEST(Trainer, NonFiniteLossStopsTrainingWithFiniteParameters) {
  const Fragile physics;
  const L2Loss loss;
  Mlp network({1, 1}, Activation::kTanh);
  network.initialize(0);
  Dataset data{Matrix::Ones(1, 8), Matrix::Constant(1, 8, 5e3), Matrix()};
  const auto update = make_learning_update("sgd", {.lr = 0.4});
  const TrainingSummary summary =
      train(network, *update, {&physics, &loss}, data, nullptr, limits(1000));
  EXPECT_EQ(summary.termination, "numerical_failure");
  EXPECT_NE(summary.message.find("non-finite loss"), std::string::npos) << summary.message;
  EXPECT_NE(summary.message.find("undone"), std::string::npos) << summary.message;
  EXPECT_LT(summary.iterations, 1000);
  EXPECT_TRUE(all_finite(network.parameters()));
  // The final evaluation is of the restored parameters, whose loss is finite.
  EXPECT_TRUE(std::isfinite(summary.history.back().train_loss));
}

TEST(Trainer, InvertedStepsThatBreakTheNextBatchAreRetriedAtHalfLength) {
  // Gauss-Newton at 4× its full step (η = 4B, as ∂(mean L)/∂y carries 1/B) overshoots the
  // target 900 to 3600, past Fragile's bound; two halvings bring the step back to 900.
  const Fragile physics;
  const L2Loss loss;
  Mlp network({1, 1}, Activation::kTanh);
  network.initialize(0);
  const Dataset data{Matrix::Ones(1, 8), Matrix::Constant(1, 8, 900.0), Matrix()};
  const auto gn = make_learning_update("gn", {.lr = 16.0});
  const TrainingSummary summary = train(network, *gn, {&physics, &loss}, data, nullptr, limits(20));
  EXPECT_EQ(summary.termination, "max_iterations") << summary.message;
  EXPECT_GE(summary.step_halvings, 2);
  EXPECT_LT(summary.history.back().train_loss, 1e-12 * summary.history.front().train_loss);

  // Without halvings allowed the same run stops at the first broken batch, undoing that step.
  network.initialize(0);
  TrainerOptions no_retry = limits(20);
  no_retry.max_step_halvings = 0;
  const TrainingSummary stopped = train(network, *gn, {&physics, &loss}, data, nullptr, no_retry);
  EXPECT_EQ(stopped.termination, "numerical_failure");
  EXPECT_EQ(stopped.iterations, 1);
  EXPECT_NE(stopped.message.find("update 1 undone"), std::string::npos) << stopped.message;
  EXPECT_TRUE(std::isfinite(stopped.history.back().train_loss));
}

TEST(Trainer, NonFiniteTestLossRestoresTheLastEvaluatedParameters) {
  // Training on inputs 1 towards 50 drives the test outputs (inputs 100) past Fragile's bound
  // while every training batch stays finite.
  const Fragile physics;
  const L2Loss loss;
  Mlp network({1, 1}, Activation::kTanh);
  network.initialize(0);
  const Dataset train_set{Matrix::Ones(1, 8), Matrix::Constant(1, 8, 50.0), Matrix()};
  const Dataset test_set{Matrix::Constant(1, 4, 100.0), Matrix::Constant(1, 4, 5e3), Matrix()};
  const auto adam = make_learning_update("adam", {.lr = 0.5});
  const TrainingSummary summary =
      train(network, *adam, {&physics, &loss}, train_set, &test_set, limits(500));
  EXPECT_EQ(summary.termination, "numerical_failure");
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
  UpdateStep step(const BatchState& batch) override {
    const Vector delta = -0.1 * batch.gradient;
    return {++steps_ == 4 ? Vector::Constant(delta.size(), NAN) : delta, 0};
  }

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
    LearningUpdateSettings settings;
    if (c.rule == "gn" || c.rule == "hig") settings.lr = 0.1;
    const auto update = make_learning_update(c.rule, settings);
    const TrainingSummary summary =
        train(network, *update, {&physics, &loss}, data, nullptr, limits(30));
    const std::string what = c.rule + " from call " + std::to_string(c.from);
    EXPECT_TRUE(all_finite(network.parameters())) << what;
    for (const TrainingRecord& r : summary.history) {
      EXPECT_TRUE(std::isfinite(r.train_loss)) << what << " at " << r.iteration;
    }
    if (c.expected.empty()) {
      EXPECT_EQ(summary.termination, "max_iterations") << what << ": " << summary.message;
      EXPECT_GE(summary.step_halvings, 1) << what;
    } else {
      EXPECT_EQ(summary.termination, "numerical_failure") << what;
      EXPECT_NE(summary.message.find(c.expected), std::string::npos) << what << ": " << summary.message;
    }
  }
  // A non-finite step from the rule itself is not applied.
  const Poisoned clean(Poisoned::Where::kForward, 1 << 30, 0);
  Mlp network({2, 5, 2}, Activation::kTanh);
  network.initialize(2);
  NanStep nan_step;
  const TrainingSummary summary = train(network, nan_step, {&clean, &loss}, data, nullptr, limits(30));
  EXPECT_EQ(summary.termination, "numerical_failure");
  EXPECT_EQ(summary.iterations, 3);
  EXPECT_NE(summary.message.find("non-finite update at iteration 4; the step was not applied"),
            std::string::npos)
      << summary.message;
  EXPECT_TRUE(all_finite(network.parameters()));
}

TEST(Trainer, UntrainedNetworkWithNonFiniteLossIsAnError) {
  const Fragile physics;
  const L2Loss loss;
  Mlp network({1, 1}, Activation::kTanh);
  network.initialize(0);
  network.bias(0)[0] = 2e3;
  const Dataset data{Matrix::Ones(1, 4), Matrix::Zero(1, 4), Matrix()};
  const auto adam = make_learning_update("adam");
  EXPECT_THROW(train(network, *adam, {&physics, &loss}, data, nullptr, limits(5)), Error);
}

// Interrupts a run when the evaluation after `stop_after` iterations is recorded, continues
// it from the JSON of its last checkpoint and returns the continuation's summary.
TrainingSummary interrupt_and_resume(const std::string& id, const TrainerOptions& base,
                                     long long stop_after, Vector& final_theta) {
  NetworkThroughPhysics s(30);
  LearningUpdateSettings settings;
  if (id == "gn" || id == "hig") settings.lr = 0.1;
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
  const auto first = make_learning_update(id, settings);
  const TrainingSummary interrupted = train(s.network, *first, s.problem, s.data, &s.data, options);
  EXPECT_EQ(interrupted.termination, "interrupted") << id;

  // A new process: a fresh network and rule, the state read back from its text.
  NetworkThroughPhysics t(30);
  const TrainerState state =
      trainer_state_from_json(nlohmann::json::parse(saved), t.network.num_parameters());
  EXPECT_EQ(state.summary.iterations, interrupted.iterations) << id;
  TrainerOptions resumed = base;
  resumed.resume = &state;
  const auto second = make_learning_update(id, settings);
  const TrainingSummary summary = train(t.network, *second, t.problem, t.data, &t.data, resumed);
  final_theta = t.network.parameters();
  return summary;
}

TEST(Trainer, ResumedRunIsBitIdenticalToAnUninterruptedOne) {
  TrainerOptions by_iterations;  // 30 samples in batches of 8: epochs end mid-way
  by_iterations.batch_size = 8;
  by_iterations.max_iterations = 25;
  by_iterations.eval_every = 4;
  TrainerOptions by_epochs;  // evaluated once per epoch
  by_epochs.batch_size = 8;
  by_epochs.max_epochs = 6;
  for (const TrainerOptions& options : {by_iterations, by_epochs}) {
    for (const std::string& id : learning_update_ids()) {
      NetworkThroughPhysics s(30);
      LearningUpdateSettings settings;
      if (id == "gn" || id == "hig") settings.lr = 0.1;
      const auto update = make_learning_update(id, settings);
      const TrainingSummary whole = train(s.network, *update, s.problem, s.data, &s.data, options);
      Vector theta;
      const TrainingSummary resumed = interrupt_and_resume(id, options, 9, theta);
      EXPECT_EQ(resumed.termination, whole.termination) << id;
      EXPECT_EQ(resumed.iterations, whole.iterations) << id;
      EXPECT_TRUE(theta == s.network.parameters()) << id;  // every bit
      ASSERT_EQ(resumed.history.size(), whole.history.size()) << id;
      for (std::size_t k = 0; k < whole.history.size(); ++k) {
        EXPECT_EQ(resumed.history[k].iteration, whole.history[k].iteration) << id;
        EXPECT_EQ(resumed.history[k].train_loss, whole.history[k].train_loss) << id << " " << k;
        EXPECT_EQ(resumed.history[k].test_loss, whole.history[k].test_loss) << id << " " << k;
      }
    }
  }
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
