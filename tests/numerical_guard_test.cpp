// Numerical trouble anywhere below a rule — a NaN or an infinity from the simulator's forward
// pass, VJP, Jacobian, Hessian or local inverse, at any call — never escapes minimize(),
// train_step() or train(): the run ends as numerical_failure (or its rule rejects the trial)
// with a message naming the rule, the iteration and the place, and the result stays finite.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "learning_fixture.hpp"
#include "physgrad/error.hpp"
#include "physgrad/optim/minimize.hpp"

namespace physgrad {
namespace {

// P(x) = (x₀, x₁²) of ComparisonToy, whose method `where` returns `value` everywhere from its
// `from`-th call on (calls before are exact).
class Faulty final : public Simulator {
 public:
  enum class Where { kForward, kVjp, kJacobian, kHessian, kInverse };
  Faulty(Where where, int from, double value) : where_(where), from_(from), value_(value) {}
  std::string name() const override { return "faulty"; }
  Index input_dim() const override { return 2; }
  Index output_dim() const override { return 2; }
  Matrix forward_batch(const Matrix& x, const Matrix& context) const override {
    return spoil(Where::kForward, exact_.forward_batch(x, context));
  }
  Matrix vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const override {
    return spoil(Where::kVjp, exact_.vjp_batch(x, context, gy));
  }
  Matrix jacobian(const Vector& x, const Vector& context) const override {
    return spoil(Where::kJacobian, exact_.jacobian(x, context));
  }
  Matrix weighted_hessian(const Vector& x, const Vector& context, const Vector& w) const override {
    return spoil(Where::kHessian, exact_.weighted_hessian(x, context, w));
  }
  bool has_inverse() const override { return true; }
  Vector inverse(const Vector& y, const Vector& x0, const Vector& context) const override {
    return spoil(Where::kInverse, exact_.inverse(y, x0, context));
  }

 private:
  Matrix spoil(Where where, Matrix m) const {
    if (where == where_ && calls_++ >= from_) m.setConstant(value_);
    return m;
  }
  ComparisonToy exact_;
  Where where_;
  int from_;
  double value_;
  mutable int calls_ = 0;
};

const char* to_text(Faulty::Where where) {
  switch (where) {
    case Faulty::Where::kForward: return "forward";
    case Faulty::Where::kVjp: return "vjp";
    case Faulty::Where::kJacobian: return "jacobian";
    case Faulty::Where::kHessian: return "hessian";
    case Faulty::Where::kInverse: return "inverse";
  }
  return "";
}

constexpr Faulty::Where kPlaces[] = {Faulty::Where::kForward, Faulty::Where::kVjp,
                                     Faulty::Where::kJacobian, Faulty::Where::kHessian,
                                     Faulty::Where::kInverse};
std::string number(double value) {
  std::ostringstream text;
  text << value;
  return text.str();
}

const double kValues[] = {std::numeric_limits<double>::quiet_NaN(),
                          std::numeric_limits<double>::infinity(), 1e308};

TEST(NumericalGuard, NothingEscapesMinimizeAndFailuresNameRuleIterationAndPlace) {
  const L2Loss loss;
  const Vector target{{0.5, 0.25}};
  const Vector x0{{1.5, -0.8}};
  int failures = 0;
  for (const std::string& id : rule_ids(RuleKind::kDirect)) {
    for (const Faulty::Where where : kPlaces) {
      for (const int from : {0, 1, 3}) {
        for (const double value : kValues) {
          // A start whose loss is not finite is bad input (an Error), not trouble in a rule.
          if (where == Faulty::Where::kForward && from == 0) continue;
          const std::string what = id + ", " + to_text(where) + " from call " +
                                   std::to_string(from) + " = " + number(value);
          const Faulty physics(where, from, value);
          const Objective objective(physics, loss, target);
          const auto optimizer = make_optimizer(id);
          MinimizeOptions options;
          options.max_iterations = 8;
          MinimizeSummary s;
          try {
            s = minimize(*optimizer, objective, x0, options);
          } catch (const std::exception& e) {
            ADD_FAILURE() << what << ": escaped: " << e.what();
            continue;
          }
          EXPECT_TRUE(all_finite(s.x) && std::isfinite(s.loss)) << what;
          // Overflow must not pass for a stationary point (a zero step).
          EXPECT_NE(s.termination, Termination::kStationary) << what << ": " << s.message;
          if (s.termination != Termination::kNumericalFailure) continue;
          ++failures;
          EXPECT_EQ(s.message.rfind("iteration " + std::to_string(s.iterations + 1) + " of " +
                                        id + ": ",
                                    0),
                    0u)
              << what << ": " << s.message;
          EXPECT_GT(s.message.size(), id.size() + 16) << what << ": the place is missing";
        }
      }
    }
  }
  EXPECT_GT(failures, 0);  // the faults reached the rules
}

// SIP with each local inverse, and the gradient and Jacobian rules, through train_step() and
// train().
TEST(NumericalGuard, NothingEscapesTrainingAndFailuresNameRuleIterationAndPlace) {
  const L2Loss loss{1.0};
  testing::NetworkThroughPhysics fixture(8);
  struct Rule {
    std::string id;
    RuleSettings settings;
  };
  std::vector<Rule> rules;
  for (const std::string& id : rule_ids(RuleKind::kLearning)) {
    if (id != "sip") rules.push_back({id, testing::test_settings(id)});
  }
  for (const char* method : {"analytic", "lbfgs", "ig"}) {
    rules.push_back({"sip", {{"inverse", method}}});
  }
  int failures = 0;
  for (const Rule& rule : rules) {
    for (const Faulty::Where where : kPlaces) {
      for (const int from : {1, 4}) {
        for (const double value : kValues) {
          const std::string what =
              rule.id + (rule.settings.contains("inverse")
                             ? " (" + rule.settings.at("inverse").get<std::string>() + ")"
                             : "") +
              ", " + to_text(where) + " from call " + std::to_string(from) + " = " + number(value);
          const Faulty physics(where, from, value);
          const LearningProblem problem{&physics, &loss};

          // train_step(): the failure is reported, never thrown, and θ stays finite.
          Mlp stepped = fixture.network;
          const auto update = make_learning_update(rule.id, rule.settings);
          StepState state;
          for (int k = 0; k < 6; ++k) {
            StepReport report;
            ASSERT_NO_THROW(report = train_step(stepped, *update, problem, fixture.data, state))
                << what;
            EXPECT_TRUE(all_finite(stepped.parameters())) << what;
            if (!report.applied()) {
              EXPECT_NE(describe_failure(report, k).find("at iteration " + std::to_string(k + 1)),
                        std::string::npos)
                  << what;
            }
          }

          // train(): numerical_failure naming rule, iteration and place.
          Mlp trained = fixture.network;
          const auto fresh = make_learning_update(rule.id, rule.settings);
          TrainerOptions options;
          options.batch_size = 4;
          options.max_iterations = 6;
          TrainingSummary summary;
          try {
            summary = train(trained, *fresh, problem, fixture.data, nullptr, options);
          } catch (const Error& e) {
            // Only an untrained network whose loss is already not finite is bad input.
            EXPECT_NE(std::string(e.what()).find("the untrained network's"), std::string::npos)
                << what << ": " << e.what();
            continue;
          } catch (const std::exception& e) {
            ADD_FAILURE() << what << ": " << e.what();
            continue;
          }
          EXPECT_TRUE(all_finite(trained.parameters())) << what;
          if (summary.termination != TrainingTermination::kNumericalFailure) continue;
          ++failures;
          // A step names its rule; an evaluation (of the run's rule) names itself.
          const bool step = summary.message.rfind(rule.id + ": non-finite ", 0) == 0 &&
                            summary.message.find(" at iteration ") != std::string::npos;
          const bool evaluation = summary.message.rfind("non-finite ", 0) == 0 &&
                                  summary.message.find(" loss at the evaluation after iteration ") !=
                                      std::string::npos;
          EXPECT_TRUE(step || evaluation) << what << ": " << summary.message;
        }
      }
    }
  }
  EXPECT_GT(failures, 0);
}

}  // namespace
}  // namespace physgrad
