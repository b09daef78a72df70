// Rule catalogue — every update rule, direct and learning, as its class describes itself (rules():
// id, label, formula, colour, defaults); the factories build a rule by id or from its full options.
#pragma once

#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
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
#include "physgrad/rule_descriptor.hpp"
#include "physgrad/rule_option.hpp"

namespace physgrad {

// The rule classes of each kind (RuleKind, rule_descriptor.hpp), one list each: the catalogue,
// the options variant below and the factories (make_optimizer, make_learning_update) are built
// from them. Each class has an Options struct listing its options (descriptors()), a constructor
// from it and its rules() (RuleDescriptor: id, label, formula, colour, defaults, …), one per
// catalogue id; a class with several (HigUpdate: gn, hig) also has a constructor from
// (Options, id) and reports the id it was built as. A new rule is its header and one entry here.
template <class... Rules>
struct RuleTypes {};
using DirectRuleTypes =
    RuleTypes<GradientDescent, Momentum, Adam, Newton, Bfgs, Lbfgs, GaussNewton,
              LevenbergMarquardt, InverseGradient, PhysicalGradient>;
using LearningRuleTypes = RuleTypes<SgdUpdate, AdamUpdate, HigUpdate, SipUpdate,
                                    KroneckerHigUpdate, LanczosHigUpdate>;

// Overrides of rules' options by name, e.g. {{"lr", 0.5}, {"inverse", "lbfgs"}} or from the
// command line; values as params() reports them (numbers; names for the choices). A name replaces
// the default of every rule that has that option and a rule without it ignores it (so one
// RuleSettings can configure several rules); a name no rule of the kind has is an Error.
using RuleSettings = std::map<std::string, nlohmann::json>;

// Sets each option of `options` that `settings` names, by its name or else its alias; a value
// outside the option's range is an Error naming `rule` (set_option). Other names are passed over.
template <class Options>
void apply_settings(const std::string& rule, Options& options, const RuleSettings& settings) {
  for (const RuleOption<Options>& option : Options::descriptors()) {
    auto found = settings.find(option.name);
    if (found == settings.end() && !option.alias.empty()) found = settings.find(option.alias);
    if (found != settings.end()) set_option(rule, option, options, found->second);
  }
}

// The options of a direct rule added to the catalogue while the program runs (add_direct_rule):
// the rule's own options struct behind an interface that lists its options, sets them by name
// and builds the rule. A value: copies share the options, which are never changed in place.
class AddedRuleOptions {
 public:
  template <class Rule>
  static AddedRuleOptions of(const typename Rule::Options& options) {
    return AddedRuleOptions(std::make_shared<const Model<Rule>>(options));
  }
  std::vector<OptionDescription> descriptions() const { return model_->descriptions(); }
  // These options with `settings` applied (apply_settings, naming `rule`).
  AddedRuleOptions with(const std::string& rule, const RuleSettings& settings) const {
    return AddedRuleOptions(model_->with(rule, settings));
  }
  std::unique_ptr<Optimizer> make_optimizer() const { return model_->make(); }

 private:
  struct Concept {
    virtual ~Concept() = default;
    virtual std::vector<OptionDescription> descriptions() const = 0;
    virtual std::shared_ptr<const Concept> with(const std::string& rule,
                                                const RuleSettings& settings) const = 0;
    virtual std::unique_ptr<Optimizer> make() const = 0;
  };
  template <class Rule>
  struct Model final : Concept {
    explicit Model(typename Rule::Options o) : options(std::move(o)) {}
    std::vector<OptionDescription> descriptions() const override {
      const auto& list = Rule::Options::descriptors();
      return {list.begin(), list.end()};
    }
    std::shared_ptr<const Concept> with(const std::string& rule,
                                        const RuleSettings& settings) const override {
      typename Rule::Options changed = options;
      apply_settings(rule, changed, settings);
      return std::make_shared<const Model>(std::move(changed));
    }
    std::unique_ptr<Optimizer> make() const override { return std::make_unique<Rule>(options); }
    typename Rule::Options options;
  };
  explicit AddedRuleOptions(std::shared_ptr<const Concept> model) : model_(std::move(model)) {}
  std::shared_ptr<const Concept> model_;
};

namespace catalogue_detail {
template <class Direct, class Learning>
struct OptionsOf;
template <class... Direct, class... Learning>
struct OptionsOf<RuleTypes<Direct...>, RuleTypes<Learning...>> {
  using type = std::variant<typename Direct::Options..., typename Learning::Options...,
                            AddedRuleOptions>;
};
}  // namespace catalogue_detail

// Any rule's full options: the Options of each class of both lists, in their order, or those of
// an added rule. Each struct's member initialisers are the one default of each option.
using AnyRuleOptions = catalogue_detail::OptionsOf<DirectRuleTypes, LearningRuleTypes>::type;

// One rule of the catalogue: its class's RuleDescriptor with its kind, the defaults as any rule's.
struct RuleInfo {
  RuleKind kind;
  std::string id;       // short lower-case id, as --optimizers takes it
  std::string label;    // display name in tables and legends
  std::string formula;  // the update in one line
  std::string colour;   // "#rrggbb", the same in every figure
  AnyRuleOptions defaults;
  RuleDerivative derivative = RuleDerivative::kGradient;
  std::string settings_from{};      // RuleDescriptor::settings_from
  std::string pretrained_colour{};  // RuleDescriptor::pretrained_colour
};

// Every rule: the direct ones, then the learning ones, each in the order of its RuleTypes list
// (and of each class's rules()).
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
// experiment gives it none: its descriptor's settings_from (kfac, lanczos-gn → gn; kfac-hig,
// lanczos-hig → hig), else `id` itself (also for an id that names no learning rule).
std::string settings_source(const std::string& id);

// An experiment's choice for learning rule `id` from `table` (its choices keyed by rule id): the
// entry of `id`, else that of settings_source(id); null when neither has one.
template <class Value>
const Value* experiment_setting(const std::map<std::string, Value>& table, const std::string& id) {
  auto found = table.find(id);
  if (found == table.end()) found = table.find(settings_source(id));
  return found == table.end() ? nullptr : &found->second;
}

// Every option of the rule, as its options struct describes it (descriptors()).
std::vector<OptionDescription> rule_options(const RuleInfo& rule);

// The names settings may give the rules of one kind (each option's name and alias), sorted.
std::vector<std::string> rule_option_names(RuleKind kind);

// The names of the options of group `group` (OptionGroup, rule_option.hpp) the rules of one
// kind declare, each once, in the catalogue's order and each rule's: the flags a front end
// offers for all those rules at once.
std::vector<std::string> grouped_rule_options(RuleKind kind, OptionGroup group);

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
// Built by id, a rule reports that id: make_learning_update("gn", {{"kappa", 0.5}}) is gn with
// κ = ½ (params() shows κ); built from full options, a class of several ids reports the one of
// its options (HigOptions: κ = 1 gn, else hig).
std::unique_ptr<Optimizer> make_optimizer(const AnyRuleOptions& options);
std::unique_ptr<Optimizer> make_optimizer(const std::string& id, const RuleSettings& settings = {});

// The same for learning rules (the direct-only types are an Error).
std::unique_ptr<LearningUpdate> make_learning_update(const AnyRuleOptions& options);
std::unique_ptr<LearningUpdate> make_learning_update(const std::string& id,
                                                     const RuleSettings& settings = {});

// A direct rule added to the catalogue (add_direct_rule) for as long as this handle lives; its
// destructor takes the rule out again.
class AddedRule {
 public:
  // Throws Error when the direct rules have the id already or the rule built from the defaults
  // reports another id().
  explicit AddedRule(RuleInfo rule);
  ~AddedRule();
  AddedRule(const AddedRule&) = delete;
  AddedRule& operator=(const AddedRule&) = delete;
  const std::string& id() const { return id_; }

 private:
  std::string id_;
};

// Adds the direct rule class `Rule` after the other direct rules, as its one descriptor
// (Rule::rules()) says: `Rule` derives from Optimizer, is built from its Options, and the Options
// struct lists its options (descriptors()). While the handle lives, make_optimizer by id,
// find_rule, rule_ids, the option names, the tables and the figures' colours (color_for) know it,
// as they know the built-in rules. Throws Error when Rule::rules() does not list one rule.
// Not thread-safe: add rules before other threads read the catalogue; adding or removing one
// moves the entries (references into rule_catalogue() taken before are invalid).
template <class Rule>
[[nodiscard]] AddedRule add_direct_rule() {
  const RuleDescriptors<typename Rule::Options>& rules = Rule::rules();
  if (rules.size() != 1) {
    throw Error("add_direct_rule: the class lists " + std::to_string(rules.size()) +
                " rules, not one");
  }
  const RuleDescriptor<typename Rule::Options>& rule = rules.front();
  return AddedRule(RuleInfo{RuleKind::kDirect, rule.id, rule.label, rule.formula, rule.colour,
                            AddedRuleOptions::of<Rule>(rule.defaults), rule.derivative,
                            rule.settings_from, rule.pretrained_colour});
}

// The same for a class without rules(): its descriptor given, the defaults Rule::Options{}.
template <class Rule>
[[nodiscard]] AddedRule add_direct_rule(std::string id, std::string label, std::string formula,
                                        std::string colour) {
  return AddedRule(RuleInfo{RuleKind::kDirect, std::move(id), std::move(label),
                            std::move(formula), std::move(colour),
                            AddedRuleOptions::of<Rule>(typename Rule::Options{})});
}

}  // namespace physgrad
