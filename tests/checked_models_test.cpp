// A user's simulator and network as the library takes them: every size they return is checked
// where it enters the library (an Error naming the model, the method and both sizes).
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <type_traits>

#include "physgrad/autodiff/dual.hpp"
#include "physgrad/autodiff/finite_difference.hpp"
#include "physgrad/catalogue.hpp"
#include "physgrad/error.hpp"
#include "physgrad/nn/mlp.hpp"
#include "physgrad/optim/minimize.hpp"
#include "physgrad/physics/checked_simulator.hpp"
#include "physgrad/train/step.hpp"
#include "lotka_volterra.hpp"

namespace physgrad {
namespace {

using testing::lotka;
const Vector& kTruth = testing::kLotkaTruth;

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

}  // namespace
}  // namespace physgrad
