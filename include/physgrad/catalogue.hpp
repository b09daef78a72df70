// Rule catalogue — every update rule in one table (id, label, formula, colour, default options),
// direct and learning; the factories build a rule from it by id, or from a rule's full options.
#pragma once

#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "physgrad/learn/adam.hpp"
#include "physgrad/learn/hig.hpp"
#include "physgrad/learn/kronecker_hig.hpp"
#include "physgrad/learn/lanczos_hig.hpp"
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
#include "physgrad/rule_option.hpp"

namespace physgrad {

// Direct rules move x (Optimizer, minimize()); learning rules move network weights θ
// (LearningUpdate, train()). "adam" and "gn" exist in both kinds.
enum class RuleKind { kDirect, kLearning };

// The full options of any one rule: the options struct of one of the rule classes. Each struct's
// member initialisers are the one default of each option.
using AnyRuleOptions =
    std::variant<GradientDescentOptions, MomentumOptions, AdamOptions, NewtonOptions, BfgsOptions,
                 LbfgsOptions, GaussNewtonOptions, LevenbergMarquardtOptions,
                 InverseGradientOptions, PhysicalGradientOptions, SgdOptions,
                 LearningAdamOptions, HigOptions, SipOptions, KroneckerHigOptions,
                 LanczosHigOptions>;

struct RuleInfo {
  RuleKind kind;
  std::string id;       // short lower-case id, as --optimizers takes it
  std::string label;    // display name in tables and legends
  std::string formula;  // the update in one line
  std::string colour;   // "#rrggbb", the same in every figure
  AnyRuleOptions defaults;
};

// Every rule: the direct ones, then the learning ones, each in display order.
const std::vector<RuleInfo>& rule_catalogue();
// The ids of one kind, in display order.
std::vector<std::string> rule_ids(RuleKind kind);
// Throws Error naming the id and the known ones of that kind.
const RuleInfo& find_rule(RuleKind kind, const std::string& id);

// A learning run that Adam pretrains before its rule takes over (TrainerOptions::pretraining, the
// HIG paper's Adam→HIG) has the id "adam-<rule>" and the label "Adam→<the rule's label>".
inline constexpr const char* kPretrainingRule = "adam";
std::string pretrained_run_id(const std::string& rule);  // "adam-hig" for "hig"
// The learning rule that takes over in the pretrained run `id` ("hig" for "adam-hig"); empty
// when `id` is not a pretrained run's.
std::string pretrained_rule(const std::string& id);
// The label of learning run `id`: its rule's ("HIG"), or "Adam→HIG" for "adam-hig". Throws Error
// like find_rule for an id that is neither.
std::string learning_run_label(const std::string& id);

// The rule whose settings in an experiment (η, τ, batch) learning rule `id` takes where the
// experiment gives it none: the exact gn or hig for their structured approximations (kfac,
// lanczos-gn → gn; kfac-hig, lanczos-hig → hig), else `id` itself.
std::string settings_source(const std::string& id);

// Overrides of rules' options by name, e.g. {{"lr", 0.5}, {"inverse", "lbfgs"}} or from the
// command line; values as params() reports them (numbers; names for the choices). A name replaces
// the default of every rule that has that option and a rule without it ignores it (so one
// RuleSettings can configure several rules); a name no rule of the kind has is an Error.
using RuleSettings = std::map<std::string, nlohmann::json>;

// Every option of the rule, as its options struct describes it (descriptors()).
std::vector<OptionDescription> rule_options(const RuleInfo& rule);

// The names settings may give the rules of one kind (each option's name and alias), sorted.
std::vector<std::string> rule_option_names(RuleKind kind);

// One option as a front end offers it for every rule of `kind` that has it (by name or alias;
// every kind when none is given): the range all of them take, the help of the first, the ids.
struct SharedRuleOption {
  OptionDescription option;
  std::vector<std::string> rules;
};
SharedRuleOption shared_rule_option(const std::string& name,
                                    std::optional<RuleKind> kind = std::nullopt);

// The rule's defaults with the settings that apply to it. Throws Error naming a name no rule of
// the rule's kind has (unknown_name_error) or a value outside the option's range (rule, option,
// value and range).
AnyRuleOptions with_settings(const RuleInfo& rule, const RuleSettings& settings);

// Every option of the rule with its default, "beta = 0.9, lr = 0.01" (params() of the rule built
// from its defaults).
std::string rule_defaults_text(const RuleInfo& rule);

// The rules of one kind as a Markdown table: id, rule, update, and every option with its default
// (the params() of the rule built from its defaults), as docs/update_rules.md shows them.
std::string rule_table_markdown(RuleKind kind);

// A direct rule from its full options (Error for a learning-only type: SgdOptions,
// HigOptions, SipOptions), or from its id with the catalogue's defaults and `settings`
// (with_settings). Throws Error naming an unknown id, an unknown option or an out-of-range value.
std::unique_ptr<Optimizer> make_optimizer(const AnyRuleOptions& options);
std::unique_ptr<Optimizer> make_optimizer(const std::string& id, const RuleSettings& settings = {});

// The same for learning rules (the direct-only types are an Error).
std::unique_ptr<LearningUpdate> make_learning_update(const AnyRuleOptions& options);
std::unique_ptr<LearningUpdate> make_learning_update(const std::string& id,
                                                     const RuleSettings& settings = {});

}  // namespace physgrad
