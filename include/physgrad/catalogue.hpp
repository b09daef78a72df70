// Rule catalogue — every update rule in one table (id, label, formula, colour, default options),
// direct and learning; the factories build a rule from it by id, or from a rule's full options.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "physgrad/learn/hig.hpp"
#include "physgrad/learn/learning_update.hpp"
#include "physgrad/learn/sgd.hpp"
#include "physgrad/learn/sip.hpp"
#include "physgrad/optim/adam.hpp"
#include "physgrad/optim/bfgs.hpp"
#include "physgrad/optim/gauss_newton.hpp"
#include "physgrad/optim/gradient_descent.hpp"
#include "physgrad/optim/inverse_gradient.hpp"
#include "physgrad/optim/lbfgs.hpp"
#include "physgrad/optim/levenberg_marquardt.hpp"
#include "physgrad/optim/momentum.hpp"
#include "physgrad/optim/newton.hpp"
#include "physgrad/optim/physical_gradient.hpp"

namespace physgrad {

// Direct rules move x (Optimizer, minimize()); learning rules move network weights θ
// (LearningUpdate, train()). "adam" and "gn" exist in both kinds.
enum class RuleKind { kDirect, kLearning };

// Every rule's full options; each struct's member initialisers are the one default of each
// option (AdamOptions serves the direct and the learning Adam).
using RuleOptions =
    std::variant<GradientDescentOptions, MomentumOptions, AdamOptions, NewtonOptions, BfgsOptions,
                 LbfgsOptions, GaussNewtonOptions, LevenbergMarquardtOptions,
                 InverseGradientOptions, PhysicalGradientOptions, SgdOptions, HigOptions,
                 SipOptions>;

struct RuleInfo {
  RuleKind kind;
  std::string id;       // short lower-case id, as --optimizers takes it
  std::string label;    // display name in tables and legends
  std::string formula;  // the update in one line
  std::string colour;   // "#rrggbb", the same in every figure
  RuleOptions defaults;
};

// Every rule: the direct ones, then the learning ones, each in display order.
const std::vector<RuleInfo>& rule_catalogue();
// The ids of one kind, in display order.
std::vector<std::string> rule_ids(RuleKind kind);
// Throws Error naming the id and the known ones of that kind.
const RuleInfo& find_rule(RuleKind kind, const std::string& id);

// Overrides of a rule's options, e.g. from the command line: a set field replaces the default
// of every rule that has that option, and a rule without it ignores it (so one RuleSettings can
// configure several rules).
struct RuleSettings {
  std::optional<double> lr = std::nullopt;  // step size η (bfgs, lbfgs: the first trial step;
                                            // sip: Adam's on the proxy loss)
  std::optional<double> beta = std::nullopt;     // momentum
  std::optional<double> beta1 = std::nullopt;    // adam, sip
  std::optional<double> beta2 = std::nullopt;    // adam, sip
  std::optional<double> epsilon = std::nullopt;  // adam, sip
  std::optional<double> rcond = std::nullopt;    // newton, gn, ig (direct); gn, hig (learning)
  std::optional<double> kappa = std::nullopt;    // gn, hig (learning): κ = 1 is Gauss-Newton
  std::optional<PinvBackend> backend = std::nullopt;     // gn, hig (learning)
  std::optional<PinvPrecision> precision = std::nullopt;      // gn, hig (learning)
  std::optional<PinvEigensolver> eigensolver = std::nullopt;  // gn, hig (learning)
  std::optional<int> memory = std::nullopt;              // lbfgs
  std::optional<double> c1 = std::nullopt;               // bfgs, lbfgs: Wolfe constants
  std::optional<double> c2 = std::nullopt;               // bfgs, lbfgs
  std::optional<double> initial_damping = std::nullopt;  // lm
  std::optional<double> min_damping = std::nullopt;      // lm
  std::optional<InverseMethod> inverse = std::nullopt;   // pg, sip: the local inverse
  // pg, sip: the numerical local inverse (LocalInverseOptions: tolerance, relative_tolerance,
  // function_tolerance, max_iterations, rcond)
  std::optional<double> inverse_tolerance = std::nullopt;
  std::optional<int> inverse_iterations = std::nullopt;
  std::optional<double> inverse_relative_tolerance = std::nullopt;
  std::optional<double> inverse_function_tolerance = std::nullopt;
  std::optional<double> inverse_rcond = std::nullopt;
  std::optional<double> y_step = std::nullopt;             // sip
};

// `options` with the settings that apply to it.
RuleOptions with_settings(RuleOptions options, const RuleSettings& settings);

// Every option of the rule with its default, "beta = 0.9, lr = 0.01" (params() of the rule built
// from its defaults).
std::string rule_defaults_text(const RuleInfo& rule);

// The rules of one kind as a Markdown table: id, rule, update, and every option with its default
// (the params() of the rule built from its defaults), as docs/update_rules.md shows them.
std::string rule_table_markdown(RuleKind kind);

// A direct rule from its full options (Error for a learning-only type: SgdOptions,
// HigOptions, SipOptions), or from its id with the catalogue's defaults and `settings`.
// Throws Error naming an unknown id or an out-of-range value.
std::unique_ptr<Optimizer> make_optimizer(const RuleOptions& options);
std::unique_ptr<Optimizer> make_optimizer(const std::string& id, const RuleSettings& settings = {});

// The same for learning rules (AdamOptions gives AdamUpdate; the direct-only types are an Error).
std::unique_ptr<LearningUpdate> make_learning_update(const RuleOptions& options);
std::unique_ptr<LearningUpdate> make_learning_update(const std::string& id,
                                                     const RuleSettings& settings = {});

}  // namespace physgrad
