// Seeded fuzz of the library's entry points with a user's simulator and network that lie: from
// some call on, one method returns a result of the wrong size, an empty one, NaN or Inf entries,
// or throws (physgrad::Error, NumericalError, std::runtime_error, a type not derived from
// std::exception); or a dimension is zero or negative. minimize() runs every direct rule of the
// catalogue (pg with every local inverse), local_inverse() every method, check_derivatives(),
// train_step() and train() every learning rule. Each outcome must be an exception of a
// documented kind — an Error naming the liar and the method for a wrong size, the user's own
// exception unchanged — or a result; a minimize() run to which a lie was told never converges.
//
// PHYSGRAD_FUZZ_SEED sets the seed (default below), PHYSGRAD_FUZZ_CASES the number of cases.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>

#include "physgrad/autodiff/finite_difference.hpp"
#include "physgrad/catalogue.hpp"
#include "physgrad/error.hpp"
#include "physgrad/inversion/power_pinv.hpp"
#include "physgrad/nn/mlp.hpp"
#include "physgrad/optim/minimize.hpp"
#include "physgrad/physics/checked_simulator.hpp"
#include "physgrad/threads.hpp"
#include "physgrad/train/trainer.hpp"
#include "lying_models.hpp"

namespace physgrad {
namespace {

constexpr std::uint64_t kDefaultSeed = 20240611;
constexpr int kDefaultCases = 10000;

std::uint64_t environment_number(const char* name, std::uint64_t fallback) {
  const char* text = std::getenv(name);
  return text != nullptr && *text != '\0' ? std::strtoull(text, nullptr, 10) : fallback;
}

using testing::Conduct;
using testing::kLies;
using testing::Liar;
using testing::Lie;
using testing::LyingNetwork;
using testing::LyingSimulator;
using testing::NotAnException;
using testing::Plan;
using testing::to_text;
using testing::wrong_size;

constexpr InverseMethod kInverseMethods[] = {InverseMethod::kAuto, InverseMethod::kAnalytic,
                                             InverseMethod::kTimeReversal, InverseMethod::kLbfgs,
                                             InverseMethod::kInverseGradient};

// How each case ended, counted by kind.
class Outcomes {
 public:
  void add(const std::string& kind) { ++counts_[kind]; }
  void print(std::uint64_t seed, int cases) const {
    std::printf("fuzz seed %llu, %d cases; outcomes:\n", static_cast<unsigned long long>(seed),
                cases);
    for (const auto& [kind, count] : counts_) std::printf("  %6d  %s\n", count, kind.c_str());
  }
  int count(const std::string& kind) const {
    const auto at = counts_.find(kind);
    return at == counts_.end() ? 0 : at->second;
  }

 private:
  std::map<std::string, int> counts_;
};

// Runs `body`; classifies and checks what escaped it. Returns true when nothing did.
template <typename Body>
bool survive(const std::string& what, const Conduct& conduct, Outcomes& outcomes,
             const Body& body) {
  try {
    body();
    return true;
  } catch (const BudgetExhausted& e) {
    ADD_FAILURE() << what << ": a budget escaped its run: " << e.what();
  } catch (const NumericalError& e) {
    outcomes.add("exception: physgrad::NumericalError");
  } catch (const Error& e) {
    const std::string message = e.what();
    // A wrong result size is reported by the check that met it, naming the liar and the method
    // (a wrong dimension may also meet the liar's own check_batch first).
    const bool dimension = conduct.lied_in.find("_dim") != std::string::npos;
    if (wrong_size(conduct.lie) && conduct.thrown == Lie::kNone && !dimension) {
      const std::string named = conduct.lied_in == "network forward" ? "forward" : conduct.lied_in;
      const bool names_it =
          (message.find("simulator 'liar'") != std::string::npos ||
           message.find("network '") != std::string::npos) &&
          message.find(named) != std::string::npos;
      EXPECT_TRUE(names_it) << what << ": " << message;
      outcomes.add("exception: physgrad::Error naming the wrong size");
    } else {
      outcomes.add(conduct.thrown == Lie::kThrowError && message.rfind("liar: ", 0) == 0
                       ? "exception: the liar's physgrad::Error, unchanged"
                       : "exception: physgrad::Error");
    }
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(conduct.thrown, Lie::kThrowRuntime) << what << ": " << e.what();
    EXPECT_EQ(std::string(e.what()).rfind("liar: ", 0), 0u) << what << ": " << e.what();
    outcomes.add("exception: the liar's std::runtime_error, unchanged");
  } catch (const std::exception& e) {
    ADD_FAILURE() << what << ": undocumented exception: " << e.what();
  } catch (const NotAnException& e) {
    EXPECT_EQ(conduct.thrown, Lie::kThrowOther) << what;
    EXPECT_EQ(e.code, 7) << what;
    outcomes.add("exception: the liar's NotAnException, unchanged");
  }
  return false;
}

// A dimension lies in one case of eight, a result in the others.
const std::vector<std::string> kSimulatorMethods = {
    "forward_batch", "vjp_batch", "jacobian", "weighted_hessian", "inverse", "time_reversal",
    "forward_batch", "vjp_batch", "jacobian", "weighted_hessian", "inverse", "time_reversal",
    "forward_batch", "vjp_batch", "jacobian", "weighted_hessian", "inverse", "time_reversal",
    "input_dim",     "output_dim", "context_dim"};
const std::vector<std::string> kNetworkMethods = {
    "network forward", "backward",       "per_sample_gradients", "per_sample_gram",
    "new_cache",       "num_parameters", "network forward",      "backward",
    "per_sample_gram", "network input_dim", "network output_dim"};

class Fuzz {
 public:
  explicit Fuzz(std::uint64_t seed) : rng_(seed) {}

  void one_case(int index) {
    const int entry = pick(10);
    if (entry < 6) {
      direct_case(index);
    } else if (entry < 8) {
      local_inverse_case(index);
    } else if (entry < 9) {
      derivative_case(index);
    } else {
      learning_case(index);
    }
  }
  const Outcomes& outcomes() const { return outcomes_; }

 private:
  int pick(int n) { return static_cast<int>(rng_() % static_cast<std::uint64_t>(n)); }
  double uniform(double lo, double hi) {
    return lo + (hi - lo) * static_cast<double>(rng_() >> 11) * 0x1.0p-53;
  }
  Matrix random(Index rows, Index cols) {
    Matrix m(rows, cols);
    for (Index i = 0; i < m.size(); ++i) m(i) = uniform(-1, 1);
    return m;
  }
  // A well-conditioned m×n map: random, plus a unit diagonal.
  Matrix map(Index m, Index n) {
    Matrix a = 0.3 * random(m, n);
    for (Index i = 0; i < std::min(m, n); ++i) a(i, i) += 1.0 + uniform(0, 2);
    return a;
  }
  // One lie: a method (or kNone, an honest case now and then), what, from which call.
  // One lie (kNone: an honest case now and then). A dimension lies from its first read (always
  // the library's); a block of per-sample rows has its size fixed by the caller, so only its
  // values lie.
  Plan draw_lie(const std::vector<std::string>& methods) {
    Plan plan;
    plan.method = methods[static_cast<std::size_t>(pick(static_cast<int>(methods.size())))];
    plan.lie = pick(12) == 0 ? Lie::kNone : kLies[pick(static_cast<int>(std::size(kLies)))];
    plan.from = pick(3) == 0 ? 0 : pick(8);
    if (plan.method.find("_dim") != std::string::npos) plan.from = 0;
    if (plan.method == "per_sample_gradients" && wrong_size(plan.lie)) plan.lie = Lie::kNaN;
    return plan;
  }
  static std::string describe(int index, const std::string& entry, const Plan& plan) {
    return "case " + std::to_string(index) + " (" + entry + "; " + plan.method + ": " +
           to_text(plan.lie) + " from call " + std::to_string(plan.from) + ")";
  }
  InverseMethod draw_inverse() {
    return kInverseMethods[pick(static_cast<int>(std::size(kInverseMethods)))];
  }

  void direct_case(int index) {
    const Index n = 1 + pick(4), m = 1 + pick(4);
    const Plan plan = draw_lie(kSimulatorMethods);
    const std::vector<std::string> ids = rule_ids(RuleKind::kDirect);
    const std::string id = ids[static_cast<std::size_t>(pick(static_cast<int>(ids.size())))];
    RuleSettings settings;
    if (id == "pg") settings["inverse"] = to_string(draw_inverse());
    if (id == "gd" || id == "momentum") settings["lr"] = 0.1;
    if (id == "adam") settings["lr"] = 0.05;
    const std::string inverse =
        id == "pg" ? " (" + settings.at("inverse").get<std::string>() + ")" : std::string();
    const std::string what = describe(index, "minimize " + id + inverse, plan);

    Conduct conduct;
    const Liar liar(plan, rng_(), conduct);
    const LyingSimulator physics(map(m, n), random(m, 1), liar, pick(2) == 0, pick(2) == 0);
    const Vector x_star = random(n, 1), x0 = random(n, 1);
    MinimizeOptions options;
    options.max_iterations = 5 + pick(30);
    options.loss_tolerance = pick(2) ? 1e-14 : 0.0;
    options.function_tolerance = pick(2) ? 1e-6 : 0.0;
    options.parameter_tolerance = pick(2) ? 1e-8 : 0.0;
    options.gradient_tolerance = pick(3) == 0 ? 1e-10 : 0.0;
    if (pick(4) == 0) options.max_evaluations = 5 + pick(200);
    const L2Loss loss;
    MinimizeSummary summary;
    const bool returned = survive(what, conduct, outcomes_, [&] {
      const Vector target = (map(m, n) * x_star).eval();  // any target of the right size
      const Objective objective(physics, loss, target);
      summary = minimize(*make_optimizer(id, settings), objective, x0, options);
    });
    if (!returned) return;
    EXPECT_TRUE(all_finite(summary.x)) << what;
    if (options.max_evaluations > 0) {
      EXPECT_LE(summary.counts.passes, options.max_evaluations) << what;
    }
    if (conduct.lied()) {
      EXPECT_FALSE(converged(summary.termination))
          << what << ": converged although the simulator lied in " << conduct.lied_in << ": "
          << summary.message;
      outcomes_.add("minimize, lied to: " + to_string(summary.termination));
    } else {
      outcomes_.add(std::string("minimize, ") +
                    (plan.lie == Lie::kNone ? "honest" : "lie never told") + ": " +
                    to_string(summary.termination));
    }
  }

  void local_inverse_case(int index) {
    const Index n = 1 + pick(4), m = 1 + pick(4);
    const Plan plan = draw_lie(kSimulatorMethods);
    LocalInverseOptions options;
    options.method = draw_inverse();
    options.max_iterations = 5 + pick(50);
    const std::string what = describe(index, "local_inverse " + to_string(options.method), plan);
    Conduct conduct;
    const Liar liar(plan, rng_(), conduct);
    const LyingSimulator physics(map(m, n), random(m, 1), liar, pick(2) == 0, pick(2) == 0);
    LocalInverseResult result;
    const Vector y = random(m, 1), x0 = random(n, 1);
    if (!survive(what, conduct, outcomes_,
                 [&] { result = local_inverse(physics, y, x0, Vector(), options); })) {
      return;
    }
    EXPECT_EQ(result.x.size(), n) << what;
    if (conduct.lied()) {
      EXPECT_FALSE(result.converged) << what << ": converged on a lie";
    }
    outcomes_.add(std::string("local_inverse: ") +
                  (result.converged ? "converged" : "not converged") +
                  (conduct.lied() ? " (lied to)" : ""));
  }

  void derivative_case(int index) {
    const Index n = 1 + pick(4), m = 1 + pick(4);
    const Plan plan = draw_lie(kSimulatorMethods);
    const std::string what = describe(index, "check_derivatives", plan);
    Conduct conduct;
    const Liar liar(plan, rng_(), conduct);
    const LyingSimulator physics(map(m, n), random(m, 1), liar, false, false);
    DerivativeCheck check;
    if (!survive(what, conduct, outcomes_,
                 [&] { check = check_derivatives(physics, random(n, 1)); })) {
      return;
    }
    // A NaN or Inf in what is compared fails the check.
    if (conduct.lied()) {
      EXPECT_FALSE(check.passed) << what << ": " << check.report();
    }
    outcomes_.add(std::string("check_derivatives: ") + (check.passed ? "passed" : "failed") +
                  (conduct.lied() ? " (lied to)" : ""));
  }

  void learning_case(int index) {
    const Index n = 1 + pick(3), m = 1 + pick(3), samples = 2 + pick(6);
    const bool network_lies = pick(2) == 0;
    const Plan plan = draw_lie(network_lies ? kNetworkMethods : kSimulatorMethods);
    const std::vector<std::string> ids = rule_ids(RuleKind::kLearning);
    const std::string id = ids[static_cast<std::size_t>(pick(static_cast<int>(ids.size())))];
    RuleSettings settings;
    if (settings_source(id) == "gn" || settings_source(id) == "hig") settings["lr"] = 0.1;
    if (id == "sip") {
      settings["inverse"] = to_string(draw_inverse());
      settings["inverse_iterations"] = 20;
    }
    const bool whole_run = pick(2) == 0;
    // In one case of four the physics VJPs of the stacked Jacobian run on two threads: a liar's
    // exception must cross them.
    set_jacobian_threads(pick(4) == 0 ? 2 : 1);
    const std::string what =
        describe(index, std::string(whole_run ? "train " : "train_step ") + id, plan);

    Conduct conduct;
    const Liar liar(plan, rng_(), conduct);
    const Liar honest({}, 0, conduct);
    const LyingSimulator physics(map(m, n), random(m, 1), network_lies ? honest : liar,
                                 pick(2) == 0, false);
    Mlp mlp({2, 4, n}, Activation::kTanh);
    mlp.initialize(rng_());
    LyingNetwork network(mlp, network_lies ? liar : honest);
    const L2Loss loss;
    const LearningProblem problem{&physics, &loss};
    Dataset data;
    data.inputs = random(2, samples);
    data.targets = map(m, n) * random(n, samples);
    const auto update = make_learning_update(id, settings);
    if (whole_run) {
      TrainerOptions options;
      options.batch_size = 1 + pick(static_cast<int>(samples));
      options.max_iterations = 1 + pick(4);
      TrainingSummary summary;
      if (!survive(what, conduct, outcomes_,
                   [&] { summary = train(network, *update, problem, data, nullptr, options); })) {
        return;
      }
      EXPECT_TRUE(all_finite(network.parameters())) << what;
      outcomes_.add("train: " + to_string(*summary.termination) +
                    (conduct.lied() ? " (lied to)" : ""));
      return;
    }
    StepState state;
    for (int k = 0; k < 3; ++k) {
      StepReport report;
      if (!survive(what, conduct, outcomes_,
                   [&] { report = train_step(network, *update, problem, data, state); })) {
        return;
      }
      EXPECT_TRUE(all_finite(network.parameters())) << what;
      outcomes_.add(std::string("train_step: ") + (report.applied() ? "applied" : "not applied") +
                    (conduct.lied() ? " (lied to)" : ""));
    }
  }

  std::mt19937_64 rng_;
  Outcomes outcomes_;
};

TEST(LyingModelsFuzz, EveryOutcomeIsADocumentedExceptionOrAnHonestSummary) {
  const std::uint64_t seed = environment_number("PHYSGRAD_FUZZ_SEED", kDefaultSeed);
  const int cases = static_cast<int>(environment_number("PHYSGRAD_FUZZ_CASES", kDefaultCases));
  const int threads = jacobian_threads();
  Fuzz fuzz(seed);
  for (int index = 0; index < cases; ++index) fuzz.one_case(index);
  set_jacobian_threads(threads);
  fuzz.outcomes().print(seed, cases);
  // The fuzz reached what it is about: lies caught by size, lies of value, the liar's own
  // exceptions of every kind, and honest runs that converge.
  const Outcomes& seen = fuzz.outcomes();
  EXPECT_GT(seen.count("exception: physgrad::Error naming the wrong size"), 0);
  EXPECT_GT(seen.count("exception: the liar's std::runtime_error, unchanged"), 0);
  EXPECT_GT(seen.count("exception: the liar's NotAnException, unchanged"), 0);
  EXPECT_GT(seen.count("exception: the liar's physgrad::Error, unchanged"), 0);
  EXPECT_GT(seen.count("minimize, lied to: numerical_failure"), 0);
  EXPECT_GT(seen.count("minimize, honest: converged"), 0);
}

}  // namespace
}  // namespace physgrad
