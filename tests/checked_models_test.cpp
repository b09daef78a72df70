// A user's simulator and network as the library takes them: every size they return is checked
// where it enters the library (an Error naming the model, the method and both sizes); a run that
// made the loss worse, or met a NaN Jacobian, never counts as converged; the simulator's work is
// counted by kind (the inner solves of pg included) and bounded by max_evaluations and
// max_seconds.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <string>
#include <thread>
#include <type_traits>

#include "physgrad/autodiff/dual.hpp"
#include "physgrad/autodiff/finite_difference.hpp"
#include "physgrad/catalogue.hpp"
#include "physgrad/error.hpp"
#include "physgrad/nn/mlp.hpp"
#include "physgrad/optim/minimize.hpp"
#include "physgrad/physics/checked_simulator.hpp"
#include "physgrad/train/step.hpp"

namespace physgrad {
namespace {

// Prey and predators, u' = αu − βuv, v' = δuv − γv from (10, 5), 100 RK4 steps to t = 5:
// x = (α, β, γ, δ) ↦ (u(5), v(5)).
struct LotkaVolterra {
  template <typename T>
  Eigen::Matrix<T, Eigen::Dynamic, 1> operator()(const Eigen::Matrix<T, Eigen::Dynamic, 1>& p,
                                                 const Vector& /*context*/) const {
    const auto rate = [&p](const T& u, const T& v) {
      Eigen::Matrix<T, 2, 1> r;
      r << p(0) * u - p(1) * u * v, p(3) * u * v - p(2) * v;
      return r;
    };
    Eigen::Matrix<T, 2, 1> s;
    s << T(10.0), T(5.0);
    const double dt = 0.05;
    for (int k = 0; k < 100; ++k) {
      const Eigen::Matrix<T, 2, 1> k1 = rate(s(0), s(1));
      const Eigen::Matrix<T, 2, 1> a = s + 0.5 * dt * k1;
      const Eigen::Matrix<T, 2, 1> k2 = rate(a(0), a(1));
      const Eigen::Matrix<T, 2, 1> b = s + 0.5 * dt * k2;
      const Eigen::Matrix<T, 2, 1> k3 = rate(b(0), b(1));
      const Eigen::Matrix<T, 2, 1> c = s + dt * k3;
      const Eigen::Matrix<T, 2, 1> k4 = rate(c(0), c(1));
      s += dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    }
    return Eigen::Matrix<T, Eigen::Dynamic, 1>(s);
  }
};

const AutoDiffSimulator<LotkaVolterra>& lotka() {
  static const AutoDiffSimulator<LotkaVolterra> model(LotkaVolterra{}, "lotka", 4, 2);
  return model;
}
const Vector kTruth{{1.0, 0.1, 1.5, 0.075}};

// The Lotka-Volterra model whose method `method` returns a rows×cols result of ones (a vector of
// `rows` entries for inverse and time_reversal); the other methods are honest (its inverse and
// time reversal return the guess and zero).
class Misreporting final : public Simulator {
 public:
  Misreporting(std::string method, Index rows, Index cols)
      : method_(std::move(method)), rows_(rows), cols_(cols) {}
  std::string name() const override { return "lotka"; }
  Index input_dim() const override { return 4; }
  Index output_dim() const override { return 2; }
  Matrix forward_batch(const Matrix& x, const Matrix& c) const override {
    return report("forward_batch", lotka().forward_batch(x, c));
  }
  Matrix vjp_batch(const Matrix& x, const Matrix& c, const Matrix& gy) const override {
    return report("vjp_batch", lotka().vjp_batch(x, c, gy));
  }
  Matrix jacobian(const Vector& x, const Vector& c) const override {
    return report("jacobian", lotka().jacobian(x, c));
  }
  bool has_jacobian() const override { return true; }
  Matrix weighted_hessian(const Vector& x, const Vector& c, const Vector& w) const override {
    return report("weighted_hessian", lotka().weighted_hessian(x, c, w));
  }
  bool has_inverse() const override { return true; }
  Vector inverse(const Vector& /*y*/, const Vector& x0, const Vector& /*c*/) const override {
    return report("inverse", x0);
  }
  bool has_time_reversal() const override { return true; }
  Vector time_reversal(const Vector& /*y*/, const Vector& /*c*/) const override {
    return report("time_reversal", Vector(Vector::Zero(4)));
  }

 private:
  Matrix report(const char* method, Matrix honest) const {
    return method_ == method ? Matrix::Ones(rows_, cols_) : std::move(honest);
  }
  Vector report(const char* method, Vector honest) const {
    return method_ == method ? Vector::Ones(rows_) : std::move(honest);
  }
  std::string method_;
  Index rows_, cols_;
};

std::string error_of(const std::function<void()>& call) {
  try {
    call();
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(CheckedSimulator, AnEmptyJacobianIsAnErrorForEveryRuleThatUsesIt) {
  const Misreporting empty("jacobian", 0, 0);
  const L2Loss loss;
  const Objective objective(empty, loss, lotka().forward(kTruth));
  for (const char* id : {"newton", "gn", "lm", "ig"}) {
    EXPECT_EQ(error_of([&] { minimize(*make_optimizer(id), objective, 1.2 * kTruth); }),
              "simulator 'lotka': jacobian returned 0×0, expected 2×4")
        << id;
  }
}

TEST(CheckedSimulator, AnEmptyInverseOrTimeReversalIsAnErrorInTheLocalInverse) {
  const Vector y = lotka().forward(kTruth);
  const Misreporting no_inverse("inverse", 0, 1), no_reversal("time_reversal", 0, 1);
  EXPECT_EQ(error_of([&] {
              local_inverse(no_inverse, y, kTruth, Vector(), {.method = InverseMethod::kAnalytic});
            }),
            "simulator 'lotka': inverse returned 0 entries, expected 4");
  EXPECT_EQ(error_of([&] {
              local_inverse(no_reversal, y, kTruth, Vector(),
                            {.method = InverseMethod::kTimeReversal});
            }),
            "simulator 'lotka': time_reversal returned 0 entries, expected 4");
}

// Each method returning a result of the wrong size, to a rule that uses it: an Error naming it,
// never a result.
TEST(CheckedSimulator, AWrongSizeFromAnyMethodIsAnErrorNotARun) {
  struct Case {
    std::string method;
    Index rows, cols;
    std::string rule;
    RuleSettings settings;
    std::string expected;
  };
  const Case cases[] = {
      {"time_reversal", 5, 1, "pg", {{"inverse", "time_reversal"}},
       "time_reversal returned 5 entries, expected 4"},
      {"inverse", 3, 1, "pg", {{"inverse", "analytic"}},
       "inverse returned 3 entries, expected 4"},
      {"vjp_batch", 5, 1, "gd", {}, "vjp_batch returned 5×1, expected 4×1"},
      {"vjp_batch", 4, 2, "lbfgs", {}, "vjp_batch returned 4×2, expected 4×1"},
      {"forward_batch", 3, 1, "gd", {}, "forward_batch returned 3×1, expected 2×1"},
      {"weighted_hessian", 5, 5, "newton", {}, "weighted_hessian returned 5×5, expected 4×4"},
      {"jacobian", 2, 5, "gn", {}, "jacobian returned 2×5, expected 2×4"},
      {"jacobian", 4, 2, "lm", {}, "jacobian returned 4×2, expected 2×4"},
  };
  const L2Loss loss;
  const Vector target = lotka().forward(kTruth);
  for (const Case& c : cases) {
    const Misreporting physics(c.method, c.rows, c.cols);
    const Objective objective(physics, loss, target);
    MinimizeOptions options;
    options.parameter_tolerance = 1e-8;
    options.function_tolerance = 1e-8;
    EXPECT_EQ(error_of([&] {
                minimize(*make_optimizer(c.rule, c.settings), objective, 1.2 * kTruth, options);
              }),
              "simulator 'lotka': " + c.expected)
        << c.rule;
  }
  // check_derivatives too (it compared shapes and reported an infinite error at best).
  const Misreporting wide("jacobian", 2, 5);
  EXPECT_EQ(error_of([&] { check_derivatives(wide, kTruth); }),
            "simulator 'lotka': jacobian returned 2×5, expected 2×4");
}

// The stacked Jacobian of a learning step asks a simulator with its own jacobian() once per
// sample: a wrong size there is the same Error.
TEST(CheckedSimulator, AWrongSizedJacobianIsAnErrorInTheStackedJacobian) {
  const Misreporting wide("jacobian", 2, 5);
  const L2Loss loss;
  const LearningProblem problem{&wide, &loss};
  Dataset data;
  data.inputs = Matrix{{0.1, 0.2, -0.3}, {0.4, -0.5, 0.6}};
  data.targets = lotka().forward_batch(kTruth.replicate(1, 3), Matrix());
  Mlp network({2, 4}, Activation::kTanh);
  network.initialize(1);
  const std::unique_ptr<LearningUpdate> hig = make_learning_update("hig", {});
  StepState state;
  EXPECT_EQ(error_of([&] { train_step(network, *hig, problem, data, state); }),
            "simulator 'lotka': jacobian returned 2×5, expected 2×4");
}

TEST(CheckedSimulator, DimensionsBelowOneAreErrors) {
  class Flat final : public Simulator {
   public:
    std::string name() const override { return "flat"; }
    Index input_dim() const override { return 0; }
    Index output_dim() const override { return 1; }
    Matrix forward_batch(const Matrix& x, const Matrix&) const override { return x; }
    Matrix vjp_batch(const Matrix& x, const Matrix&, const Matrix&) const override { return x; }
  };
  const Flat flat;
  EXPECT_EQ(error_of([&] { const CheckedSimulator checked(flat); }),
            "simulator 'flat': input_dim() returned 0, expected ≥ 1");
}

// An Mlp 2 → 4 → 4 whose method `method` returns a result of the wrong size.
class MisreportingNetwork final : public Network {
 public:
  explicit MisreportingNetwork(std::string method) : method_(std::move(method)) {
    mlp_.initialize(1);
  }
  std::string name() const override { return "shortcut"; }
  Index input_dim() const override { return 2; }
  Index output_dim() const override { return 4; }
  Index num_parameters() const override {
    return mlp_.num_parameters() + (method_ == "num_parameters" ? 1 : 0);
  }
  const Vector& parameters() const override { return mlp_.parameters(); }
  Vector& parameters() override { return mlp_.parameters(); }
  std::unique_ptr<NetworkCache> new_cache() const override {
    return method_ == "new_cache" ? nullptr : mlp_.new_cache();
  }
  Matrix forward(const Matrix& x, NetworkCache& cache) const override {
    const Matrix out = mlp_.forward(x, cache);
    return method_ == "forward" ? Matrix(out.topRows(3)) : out;
  }
  Vector backward(const NetworkCache& cache, const Matrix& gy) const override {
    const Vector g = mlp_.backward(cache, gy);
    return method_ == "backward" ? Vector(g.head(3)) : g;
  }
  void per_sample_gradients(const NetworkCache& cache, const Matrix& gy,
                            StridedMatrixRef out) const override {
    mlp_.per_sample_gradients(cache, gy, out);
  }
  Matrix per_sample_gram(const NetworkCache& cache,
                         const std::vector<Matrix>& cotangents) const override {
    const Matrix gram = mlp_.per_sample_gram(cache, cotangents);
    return method_ == "per_sample_gram" ? Matrix(gram.topLeftCorner(2, 2)) : gram;
  }

 private:
  std::string method_;
  Mlp mlp_{{2, 4, 4}, Activation::kTanh};
};

TEST(CheckedNetwork, AWrongSizeFromAnyMethodIsAnErrorNamingTheNetwork) {
  // The network's 4 outputs x ↦ (x₀ + x₁, x₂x₃).
  const AutoDiffSimulator pairs(
      [](const auto& x, const Vector&) {
        using Column = std::decay_t<decltype(x)>;
        Column y(2);
        y << x(0) + x(1), x(2) * x(3);
        return y;
      },
      "pairs", 4, 2);
  const L2Loss loss;
  const LearningProblem problem{&pairs, &loss};
  Dataset data;
  data.inputs = Matrix{{0.1, 0.2, -0.3}, {0.4, -0.5, 0.6}};
  data.targets = Matrix{{0.5, -0.5, 0.2}, {0.1, 0.2, 0.3}};
  const Index parameters = Mlp({2, 4, 4}, Activation::kTanh).num_parameters();
  const std::pair<std::string, std::string> cases[] = {
      {"forward", "network 'shortcut': forward returned 3×3, expected 4×3"},
      {"backward", "network 'shortcut': backward returned 3 entries, expected " +
                       std::to_string(parameters)},
      {"per_sample_gram", "network 'shortcut': per_sample_gram returned 2×2, expected 6×6"},
      {"new_cache", "network 'shortcut': new_cache returned no cache"},
      {"num_parameters", "network 'shortcut': parameters() has " + std::to_string(parameters) +
                             " entries, num_parameters() says " + std::to_string(parameters + 1)},
  };
  for (const auto& [method, expected] : cases) {
    // sgd uses backward; hig on the Gram path uses per_sample_gram.
    const bool gram = method == "per_sample_gram";
    MisreportingNetwork network(method);
    const Vector before = network.parameters();
    const auto update = gram ? make_learning_update("hig", {{"backend", "gram"}})
                             : make_learning_update("sgd");
    StepState state;
    EXPECT_EQ(error_of([&] { train_step(network, *update, problem, data, state); }), expected)
        << method;
    EXPECT_EQ(network.parameters(), before) << method;
  }
}

// A rule that first raises the loss (x: 1 → 30) and then creeps (steps of 1e-12).
class Worsening final : public Optimizer {
 public:
  std::string id() const override { return "worsening"; }
  nlohmann::json params() const override { return nlohmann::json::object(); }

 private:
  Step propose(const Objective& /*objective*/, const Vector& x, const Domain& /*domain*/) override {
    return {Vector::Constant(1, x(0) < 2 ? 29.0 : 1e-12), Step::Status::kOk, {}, 0};
  }
};

TEST(Termination, ARunThatMadeTheLossWorseIsDivergedNotConverged) {
  const AutoDiffSimulator identity([](const auto& x, const Vector&) { return x; }, "identity", 1,
                                   1);
  const L2Loss loss;
  const Objective objective(identity, loss, Vector::Zero(1));
  for (const auto& [name, options] :
       {std::pair{"parameter_tolerance", MinimizeOptions{.parameter_tolerance = 1e-8}},
        std::pair{"function_tolerance", MinimizeOptions{.function_tolerance = 1e-8}}}) {
    Worsening rule;
    const MinimizeSummary s = minimize(rule, objective, Vector::Ones(1), options);
    EXPECT_EQ(s.termination, Termination::kDiverged) << name << ": " << s.message;
    EXPECT_FALSE(converged(s.termination));
    EXPECT_EQ(s.iterations, 2);
    EXPECT_EQ(s.message.rfind(std::string(name) + " held (", 0), 0u) << s.message;
    EXPECT_NE(s.message.find("is above L(x₀) = 0.5"), std::string::npos) << s.message;
    EXPECT_NE(full_report(s).find("Termination: diverged\n"), std::string::npos) << full_report(s);
  }
}

// Gauss-Newton's full steps from this start raise the loss from 16.6 to 27.5, then shrink below
// the parameter tolerance: that used to end "parameter_tolerance (convergence)".
TEST(Termination, GaussNewtonOnLotkaVolterraEndsDivergedWhenTheLossRose) {
  const L2Loss loss;
  const Objective objective(lotka(), loss, lotka().forward(kTruth));
  MinimizeOptions options;
  options.parameter_tolerance = 1e-8;
  const MinimizeSummary s =
      minimize(*make_optimizer("gn"), objective, Vector{{1.41, 0.06028, 1.044, 0.1712}}, options);
  EXPECT_GT(s.loss, s.initial_loss);
  EXPECT_EQ(s.termination, Termination::kDiverged) << brief_report(s) << ": " << s.message;
  EXPECT_EQ(s.message.rfind("parameter_tolerance held (", 0), 0u) << s.message;
}

TEST(Termination, LevenbergMarquardtNamesANanJacobianAsANumericalFailure) {
  class NanJacobian final : public Simulator {
   public:
    std::string name() const override { return "lotka"; }
    Index input_dim() const override { return 4; }
    Index output_dim() const override { return 2; }
    Matrix forward_batch(const Matrix& x, const Matrix& c) const override {
      return lotka().forward_batch(x, c);
    }
    Matrix vjp_batch(const Matrix& x, const Matrix& c, const Matrix& gy) const override {
      return lotka().vjp_batch(x, c, gy);
    }
    Matrix jacobian(const Vector&, const Vector&) const override {
      return Matrix::Constant(2, 4, NAN);
    }
  };
  const NanJacobian physics;
  const L2Loss loss;
  const Objective objective(physics, loss, lotka().forward(kTruth));
  const MinimizeSummary s = minimize(*make_optimizer("lm"), objective, 1.2 * kTruth);
  EXPECT_EQ(s.termination, Termination::kNumericalFailure) << s.message;
  EXPECT_EQ(s.iterations, 0);
  EXPECT_EQ(s.message, "iteration 1 of lm: the Jacobian at x has non-finite entries");
}

// y = A x + b (2×3) with closed forms for everything, counting the calls that reach it.
class Counted final : public Simulator {
 public:
  std::string name() const override { return "counted"; }
  Index input_dim() const override { return 3; }
  Index output_dim() const override { return 2; }
  Matrix forward_batch(const Matrix& x, const Matrix&) const override {
    seen.forward += x.cols();
    return (a_ * x).colwise() + b_;
  }
  Matrix vjp_batch(const Matrix& x, const Matrix&, const Matrix& gy) const override {
    seen.vjp += x.cols();
    return a_.transpose() * gy;
  }
  Matrix jacobian(const Vector&, const Vector&) const override {
    ++seen.jacobians;
    return a_;
  }
  Matrix weighted_hessian(const Vector&, const Vector&, const Vector&) const override {
    ++seen.hessians;
    return Matrix::Zero(3, 3);
  }
  bool has_inverse() const override { return true; }
  Vector inverse(const Vector& y, const Vector& x0, const Vector&) const override {
    ++seen.inverses;
    return x0 + pinv_ * (y - a_ * x0 - b_);
  }
  bool has_time_reversal() const override { return true; }
  Vector time_reversal(const Vector& y, const Vector&) const override {
    ++seen.reversals;
    return pinv_ * (y - b_);
  }
  // The passes of what was seen (m = 2 per Jacobian, 2n = 6 per Hessian).
  long long passes() const {
    return seen.forward + seen.vjp + 2 * seen.jacobians + 6 * seen.hessians + seen.reversals +
           seen.inverses;
  }
  mutable SimulatorCounts seen;

 private:
  Matrix a_{{2.0, 0.5, 0.0}, {0.0, 1.0, 3.0}};
  Vector b_{{0.3, -0.2}};
  Matrix pinv_ = a_.completeOrthogonalDecomposition().pseudoInverse();
};

void expect_counts(const SimulatorCounts& counted, const Counted& physics,
                   const std::string& what) {
  SimulatorCounts expected = physics.seen;
  expected.passes = physics.passes();
  EXPECT_EQ(counted, expected) << what << ": " << to_string(counted) << " vs "
                               << to_string(expected);
}

TEST(SimulatorCounts, EveryCallIsCountedByKindPerIterationAndInTotal) {
  const L2Loss loss;
  const Vector x0{{1.0, -1.0, 2.0}};
  MinimizeOptions options;
  options.max_iterations = 5;
  for (const auto& [id, settings] :
       {std::pair{"gd", RuleSettings{{"lr", 0.01}}}, std::pair{"gn", RuleSettings{}},
        std::pair{"newton", RuleSettings{}}, std::pair{"lbfgs", RuleSettings{}},
        std::pair{"pg", RuleSettings{{"inverse", "analytic"}}},
        std::pair{"pg", RuleSettings{{"inverse", "time_reversal"}}},
        std::pair{"pg", RuleSettings{{"inverse", "ig"}}},
        std::pair{"pg", RuleSettings{{"lr", 0.5}, {"inverse", "lbfgs"}}}}) {
    const Counted physics;
    const Objective objective(physics, loss, Vector{{1.0, 2.0}});
    const MinimizeSummary s = minimize(*make_optimizer(id, settings), objective, x0, options);
    const std::string what = brief_report(s);
    expect_counts(s.counts, physics, what);
    // A run that ends inside a step (stationary, say) worked after its last iterate.
    EXPECT_LE(s.history.back().counts.passes, s.counts.passes) << what;
    if (s.termination == Termination::kMaxIterations) {
      EXPECT_EQ(s.history.back().counts, s.counts) << what;
    }
    for (std::size_t k = 1; k < s.history.size(); ++k) {
      EXPECT_GT(s.history[k].counts.passes, s.history[k - 1].counts.passes) << what;
    }
  }
  // gd: x₀'s loss, then per iteration the gradient (forward, VJP) and the new point's loss.
  const Counted physics;
  const Objective objective(physics, loss, Vector{{1.0, 2.0}});
  const MinimizeSummary s = minimize(*make_optimizer("gd", {{"lr", 0.01}}), objective, x0, options);
  EXPECT_EQ(s.counts.forward, 1 + 2 * 5);
  EXPECT_EQ(s.counts.vjp, 5);
  EXPECT_EQ(s.counts.passes, 16);
  EXPECT_EQ(s.history[2].counts.passes, 7);
}

// pg through a numerical local inverse: the inner solves' work is part of the outer run's.
TEST(SimulatorCounts, PgCountsItsLocalInverseSolves) {
  const Counted physics;
  const L2Loss loss;
  const Objective objective(physics, loss, Vector{{1.0, 2.0}});
  MinimizeOptions options;
  options.max_iterations = 3;
  const MinimizeSummary s = minimize(
      *make_optimizer("pg", {{"lr", 0.5}, {"inverse", "lbfgs"}}), objective,
      Vector{{1.0, -1.0, 2.0}}, options);
  expect_counts(s.counts, physics, brief_report(s));
  EXPECT_GT(s.counts.vjp, 3 * 2);  // the L-BFGS solves' gradients
  const LocalInverseResult inverse = local_inverse(
      physics, Vector{{0.5, 0.5}}, Vector::Zero(3), Vector(), {.method = InverseMethod::kLbfgs});
  EXPECT_GT(inverse.counts.vjp, 0);
  EXPECT_EQ(inverse.counts.passes, inverse.counts.forward + inverse.counts.vjp);
}

// P(x) = sin(x) componentwise in 6 dimensions, slowed down by `delay` per call; the target 3 is
// out of reach, so a local inverse through full Gauss-Newton steps never converges.
class SlowSine final : public Simulator {
 public:
  explicit SlowSine(std::chrono::microseconds delay = {}) : delay_(delay) {}
  std::string name() const override { return "sine"; }
  Index input_dim() const override { return 6; }
  Index output_dim() const override { return 6; }
  Matrix forward_batch(const Matrix& x, const Matrix&) const override {
    std::this_thread::sleep_for(delay_);
    return x.array().sin();
  }
  Matrix vjp_batch(const Matrix& x, const Matrix&, const Matrix& gy) const override {
    std::this_thread::sleep_for(delay_);
    return x.array().cos() * gy.array();
  }

 private:
  std::chrono::microseconds delay_;
};

// pg's local inverse runs until its iteration limit (no relative or stall test).
const RuleSettings kLongInverse{{"inverse", "ig"}, {"inverse_relative_tolerance", 0.0}, {"inverse_function_tolerance", 0.0}};

// pg from 0.1 towards sin(x) = 3 with `options`.
MinimizeSummary pg_out_of_reach(const SlowSine& sine, MinimizeOptions options) {
  const L2Loss loss;
  const Objective objective(sine, loss, Vector::Constant(6, 3.0));
  options.max_iterations = 200;
  return minimize(*make_optimizer("pg", kLongInverse), objective, Vector::Constant(6, 0.1),
                  options);
}

TEST(Budgets, MaxEvaluationsEndsAPgRunInsideItsLocalInverse) {
  const MinimizeSummary s = pg_out_of_reach(SlowSine(), {.max_evaluations = 150});
  EXPECT_EQ(s.termination, Termination::kMaxEvaluations) << s.message;
  // Each inner iteration costs 8 passes (its point, a Jacobian of 6, the new point's loss).
  EXPECT_LE(s.counts.passes, 150);
  EXPECT_GT(s.counts.passes, 150 - 8);
  EXPECT_EQ(s.iterations, 0);  // the first pg step's inverse ran out of budget
  EXPECT_EQ(s.message.rfind("max_evaluations reached in iteration 1: ", 0), 0u) << s.message;
  EXPECT_EQ(s.x, s.history.back().x);  // the last accepted iterate
  EXPECT_NE(full_report(s).find("max_evaluations         150\n"), std::string::npos)
      << full_report(s);
}

TEST(Budgets, MaxSecondsEndsARunWithinOneSimulatorCall) {
  const MinimizeSummary s =
      pg_out_of_reach(SlowSine(std::chrono::microseconds(2000)), {.max_seconds = 0.05});
  EXPECT_EQ(s.termination, Termination::kMaxSeconds) << s.message;
  EXPECT_GE(s.wall_seconds, 0.05);
  EXPECT_LT(s.wall_seconds, 0.5);  // not 200 inner × 200 outer iterations of 6 ms
  EXPECT_FALSE(converged(s.termination));
}

TEST(Reports, BriefAndFullReportsShowTheSimulatorsWork) {
  const Counted physics;
  const L2Loss loss;
  const Objective objective(physics, loss, Vector{{1.0, 2.0}});
  const MinimizeSummary s =
      minimize(*make_optimizer("pg", {{"inverse", "time_reversal"}}), objective,
               Vector{{1.0, -1.0, 2.0}}, {.max_iterations = 2, .loss_tolerance = 1e-20});
  const std::string passes = std::to_string(s.counts.passes);
  EXPECT_NE(brief_report(s).find(", " + passes + " simulator passes, "), std::string::npos)
      << brief_report(s);
  const std::string report = full_report(s);
  EXPECT_NE(report.find("simulator passes        " + passes + "\n"), std::string::npos) << report;
  EXPECT_NE(report.find("  time reversals        " + std::to_string(s.counts.reversals) + "\n"),
            std::string::npos)
      << report;
  EXPECT_GT(s.counts.reversals, 0);
}

}  // namespace
}  // namespace physgrad
