#include "physgrad/catalogue.hpp"

#include <algorithm>
#include <set>
#include <type_traits>

#include "physgrad/error.hpp"
#include "physgrad/text.hpp"

namespace physgrad {

namespace {

using Kind = RuleKind;

// The descriptions of every option of `options`' type.
template <typename Options>
std::vector<OptionDescription> descriptions(const Options& /*options*/) {
  return {Options::descriptors().begin(), Options::descriptors().end()};
}

std::vector<OptionDescription> descriptions(const AddedRuleOptions& options) {
  return options.descriptions();
}

// Thrown when a factory gets the options of a rule of the other kind.
Error wrong_kind(const AnyRuleOptions& options, Kind wanted) {
  std::vector<std::string> ids;
  for (const RuleInfo& rule : rule_catalogue()) {
    if (rule.defaults.index() == options.index()) ids.push_back(rule.id);
  }
  return Error(std::string(wanted == Kind::kDirect ? "make_optimizer" : "make_learning_update") +
               ": the options of " + comma_list(ids) + " make no " +
               (wanted == Kind::kDirect ? "direct" : "learning") + " rule");
}

// Rule `Rule` built from `options`: as the catalogue id `id` when its class has several ids
// (a constructor from (Options, id)), else from the options alone.
template <class Rule>
std::unique_ptr<Rule> built_as(const typename Rule::Options& options, const std::string& id) {
  if constexpr (std::is_constructible_v<Rule, const typename Rule::Options&, const std::string&>) {
    return std::make_unique<Rule>(options, id);
  } else {
    return std::make_unique<Rule>(options);
  }
}

// The rule of `Rules` (classes deriving from Base) whose Options `options` holds, or the added
// direct rule, built as the catalogue id `id` (empty: the id of its options); Error when none
// does, or when the rule built reports another id than `id`.
template <class Base, class... Rules>
std::unique_ptr<Base> build(const AnyRuleOptions& options, Kind kind, RuleTypes<Rules...>,
                            const std::string& id = {}) {
  std::unique_ptr<Base> rule;
  std::visit(
      [&rule, &id](const auto& o) {
        using T = std::decay_t<decltype(o)>;
        if constexpr (std::is_same_v<T, AddedRuleOptions>) {
          if constexpr (std::is_same_v<Base, Optimizer>) rule = o.make_optimizer();
        } else {
          const auto make = [&]<class Rule>() {
            if constexpr (std::is_same_v<typename Rule::Options, T>) rule = built_as<Rule>(o, id);
          };
          (make.template operator()<Rules>(), ...);
        }
      },
      options);
  if (!rule) throw wrong_kind(options, kind);
  if (!id.empty() && rule->id() != id) {
    throw Error("the rule built as " + in_quotes(id) + " reports the id " + in_quotes(rule->id()));
  }
  return rule;
}

// The catalogue's entries of each rule class of `Rules`, in their order, each class's rules() in
// theirs.
template <Kind kind, class... Rules>
void append_rules(std::vector<RuleInfo>& entries, RuleTypes<Rules...>) {
  using Base = std::conditional_t<kind == Kind::kDirect, Optimizer, LearningUpdate>;
  const auto append = [&entries]<class Rule>() {
    static_assert(std::is_base_of_v<Base, Rule>, "a rule class in the other kind's list");
    for (const RuleDescriptor<typename Rule::Options>& rule : Rule::rules()) {
      entries.push_back(RuleInfo{kind, rule.id, rule.label, rule.formula, rule.colour,
                                 rule.defaults, rule.derivative, rule.settings_from,
                                 rule.pretrained_colour});
    }
  };
  (append.template operator()<Rules>(), ...);
}

// The catalogue: the rules the classes of both lists describe, then those add_direct_rule added.
std::vector<RuleInfo>& catalogue_entries() {
  static std::vector<RuleInfo> rules = [] {
    std::vector<RuleInfo> entries;
    append_rules<Kind::kDirect>(entries, DirectRuleTypes{});
    append_rules<Kind::kLearning>(entries, LearningRuleTypes{});
    return entries;
  }();
  return rules;
}

}  // namespace

const std::vector<RuleInfo>& rule_catalogue() { return catalogue_entries(); }

std::vector<std::string> rule_ids(Kind kind) {
  std::vector<std::string> ids;
  for (const RuleInfo& rule : rule_catalogue()) {
    if (rule.kind == kind) ids.push_back(rule.id);
  }
  return ids;
}

const RuleInfo& find_rule(Kind kind, const std::string& id) {
  for (const RuleInfo& rule : rule_catalogue()) {
    if (rule.kind == kind && rule.id == id) return rule;
  }
  throw unknown_name_error(kind == Kind::kDirect ? "optimizer" : "learning update", id,
                           rule_ids(kind));
}

std::string pretrained_run_id(const std::string& rule) {
  return std::string(kPretrainingRule) + "-" + rule;
}

std::string pretrained_rule(const std::string& id) {
  const std::string prefix = pretrained_run_id("");
  if (id.size() <= prefix.size() || id.compare(0, prefix.size(), prefix) != 0) return {};
  const std::string rule = id.substr(prefix.size());
  const std::vector<std::string> ids = rule_ids(Kind::kLearning);
  return std::find(ids.begin(), ids.end(), rule) != ids.end() ? rule : std::string();
}

std::string learning_run_label(const std::string& id) {
  const std::string rule = pretrained_rule(id);
  if (rule.empty()) return find_rule(Kind::kLearning, id).label;
  return find_rule(Kind::kLearning, kPretrainingRule).label + "→" +
         find_rule(Kind::kLearning, rule).label;
}

std::string settings_source(const std::string& id) {
  for (const RuleInfo& rule : rule_catalogue()) {
    if (rule.kind == Kind::kLearning && rule.id == id && !rule.settings_from.empty()) {
      return rule.settings_from;
    }
  }
  return id;
}

std::vector<OptionDescription> rule_options(const RuleInfo& rule) {
  return std::visit([](const auto& o) { return descriptions(o); }, rule.defaults);
}

std::vector<std::string> rule_option_names(Kind kind) {
  std::set<std::string> names;
  for (const RuleInfo& rule : rule_catalogue()) {
    if (rule.kind != kind) continue;
    for (const OptionDescription& option : rule_options(rule)) {
      names.insert(option.name);
      if (!option.alias.empty()) names.insert(option.alias);
    }
  }
  return {names.begin(), names.end()};
}

std::vector<std::string> grouped_rule_options(Kind kind, OptionGroup group) {
  std::vector<std::string> names;
  for (const RuleInfo& rule : rule_catalogue()) {
    if (rule.kind != kind) continue;
    for (const OptionDescription& option : rule_options(rule)) {
      if (option.group == group &&
          std::find(names.begin(), names.end(), option.name) == names.end()) {
        names.push_back(option.name);
      }
    }
  }
  return names;
}

SharedRuleOption shared_rule_option(const std::string& name, std::optional<Kind> kind) {
  SharedRuleOption shared;
  shared.option.name = name;
  for (const RuleInfo& rule : rule_catalogue()) {
    if (kind && rule.kind != *kind) continue;
    for (const OptionDescription& option : rule_options(rule)) {
      if (option.name != name && option.alias != name) continue;
      shared.option.range =
          shared.rules.empty() ? option.range : shared.option.range.common(option.range);
      if (shared.option.help.empty() && option.name == name) shared.option.help = option.help;
      if (std::find(shared.rules.begin(), shared.rules.end(), rule.id) == shared.rules.end()) {
        shared.rules.push_back(rule.id);
      }
    }
  }
  if (shared.rules.empty()) throw Error("no rule has the option " + in_quotes(name));
  return shared;
}

AnyRuleOptions with_settings(const RuleInfo& rule, const RuleSettings& settings) {
  const std::vector<std::string> known = rule_option_names(rule.kind);
  for (const auto& [name, value] : settings) {
    if (!std::binary_search(known.begin(), known.end(), name)) {
      throw unknown_name_error("rule option", name, known);
    }
  }
  AnyRuleOptions options = rule.defaults;
  std::visit(
      [&](auto& o) {
        if constexpr (std::is_same_v<std::decay_t<decltype(o)>, AddedRuleOptions>) {
          o = o.with(rule.id, settings);
        } else {
          apply_settings(rule.id, o, settings);
        }
      },
      options);
  return options;
}

std::string rule_defaults_text(const RuleInfo& rule) {
  const nlohmann::json params = rule.kind == Kind::kDirect
                                    ? make_optimizer(rule.defaults)->params()
                                    : make_learning_update(rule.defaults)->params();
  std::string text;
  for (const auto& [name, value] : params.items()) {
    text += (text.empty() ? "" : ", ") + name + " = " +
            (value.is_string() ? value.get<std::string>() : value.dump());
  }
  return text;
}

std::string rule_table_markdown(Kind kind) {
  std::string table = "| id | rule | update | options (defaults) |\n|---|---|---|---|\n";
  for (const RuleInfo& rule : rule_catalogue()) {
    if (rule.kind != kind) continue;
    table += "| `" + rule.id + "` | " + rule.label + " | " + rule.formula + " | " +
             rule_defaults_text(rule) + " |\n";
  }
  return table;
}

std::unique_ptr<Optimizer> make_optimizer(const AnyRuleOptions& options) {
  return build<Optimizer>(options, Kind::kDirect, DirectRuleTypes{});
}

std::unique_ptr<Optimizer> make_optimizer(const std::string& id, const RuleSettings& settings) {
  return build<Optimizer>(with_settings(find_rule(Kind::kDirect, id), settings), Kind::kDirect,
                          DirectRuleTypes{}, id);
}

std::unique_ptr<LearningUpdate> make_learning_update(const AnyRuleOptions& options) {
  return build<LearningUpdate>(options, Kind::kLearning, LearningRuleTypes{});
}

std::unique_ptr<LearningUpdate> make_learning_update(const std::string& id,
                                                     const RuleSettings& settings) {
  return build<LearningUpdate>(with_settings(find_rule(Kind::kLearning, id), settings),
                               Kind::kLearning, LearningRuleTypes{}, id);
}

AddedRule::AddedRule(RuleInfo rule) : id_(rule.id) {
  std::vector<RuleInfo>& rules = catalogue_entries();
  for (const RuleInfo& known : rules) {
    if (known.kind == Kind::kDirect && known.id == id_) {
      throw Error("add_direct_rule: the direct rules have the id " + in_quotes(id_) + " already");
    }
  }
  const std::string built = make_optimizer(rule.defaults)->id();
  if (built != id_) {
    throw Error("add_direct_rule: the rule added as " + in_quotes(id_) + " reports the id " +
                in_quotes(built));
  }
  // After the last direct rule, so each kind stays in display order.
  auto after = rules.begin();
  for (auto it = rules.begin(); it != rules.end(); ++it) {
    if (it->kind == Kind::kDirect) after = it + 1;
  }
  rules.insert(after, std::move(rule));
}

AddedRule::~AddedRule() {
  std::erase_if(catalogue_entries(),
                [this](const RuleInfo& r) { return r.kind == Kind::kDirect && r.id == id_; });
}

}  // namespace physgrad
