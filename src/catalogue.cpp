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

// The rule of `Rules` (classes deriving from Base) whose Options `options` holds, or the added
// direct rule; Error when none does.
template <class Base, class... Rules>
std::unique_ptr<Base> build(const AnyRuleOptions& options, Kind kind, RuleTypes<Rules...>) {
  std::unique_ptr<Base> rule;
  std::visit(
      [&rule](const auto& o) {
        using T = std::decay_t<decltype(o)>;
        if constexpr (std::is_same_v<T, AddedRuleOptions>) {
          if constexpr (std::is_same_v<Base, Optimizer>) rule = o.make_optimizer();
        } else {
          const auto make = [&]<class Rule>() {
            if constexpr (std::is_same_v<typename Rule::Options, T>) {
              rule = std::make_unique<Rule>(o);
            }
          };
          (make.template operator()<Rules>(), ...);
        }
      },
      options);
  if (!rule) throw wrong_kind(options, kind);
  return rule;
}

// The catalogue: the table below, then the rules added by add_direct_rule.
std::vector<RuleInfo>& catalogue_entries() {
  static std::vector<RuleInfo> rules = {
      {Kind::kDirect, "gd", "GD", "Δx = −η ∂L/∂x", "#1f77b4", GradientDescentOptions{}},
      {Kind::kDirect, "momentum", "Momentum", "v ← βv + ∂L/∂x, Δx = −η v", "#17becf",
       MomentumOptions{}},
      {Kind::kDirect, "adam", "Adam", "Δx = −η m̂/(√v̂ + ε)", "#ff7f0e", AdamOptions{}},
      {Kind::kDirect, "newton", "Newton", "Δx = −η H⁻¹ ∂L/∂x, exact Hessian", "#d62728",
       NewtonOptions{}},
      {Kind::kDirect, "bfgs", "BFGS", "Δx = −α B⁻¹ ∂L/∂x, α by a strong-Wolfe line search",
       "#9467bd", BfgsOptions{}},
      {Kind::kDirect, "lbfgs", "L-BFGS",
       "Δx = −α H̃ ∂L/∂x, two-loop recursion, strong-Wolfe line search", "#c5a3e0",
       LbfgsOptions{}},
      {Kind::kDirect, "gn", "Gauss-Newton", "Δx = −η (JᵀH_yJ)⁺ Jᵀ ∂L/∂y", "#8c564b",
       GaussNewtonOptions{}},
      {Kind::kDirect, "lm", "Levenberg-Marquardt",
       "Δx = −(A + μ diag A)⁻¹ Jᵀ ∂L/∂y, μ by gain ratio", "#e377c2",
       LevenbergMarquardtOptions{}},
      {Kind::kDirect, "ig", "IG", "Δx = J⁺ Δy, Δy = η (y* − y)", "#2ca02c",
       InverseGradientOptions{}},
      {Kind::kDirect, "pg", "PG", "Δx = P⁻¹(y + Δy; x) − x, Δy = η (y* − y)", "#bcbd22",
       PhysicalGradientOptions{}},
      {Kind::kLearning, "sgd", "SGD", "Δθ = −η ∇θL", "#6baed6", SgdOptions{}},
      {Kind::kLearning, "adam", "Adam", "Δθ = −η m̂/(√v̂ + ε) on ∇θL", "#ff7f0e",
       LearningAdamOptions{}},
      {Kind::kLearning, "gn", "Gauss-Newton",
       "Δθ = −η J⁺ ∂L/∂y, J the stacked Jacobian, σ ≤ τσ_max dropped", "#8c564b",
       HigOptions{.kappa = 1.0}},
      {Kind::kLearning, "hig", "HIG", "Δθ = −η V Σ^{−1/2} Uᵀ ∂L/∂y, J = UΣVᵀ, σ ≤ τσ_max dropped",
       "#00633a", HigOptions{}},
      {Kind::kLearning, "sip", "SIP", "x̃ = P⁻¹(y + ηΔy; x), Adam on ½‖f(in; θ) − x̃‖²",
       "#000000", SipOptions{}},
      {Kind::kLearning, "kfac", "K-FAC",
       "Δ[W b] = −η S⁻¹ ∇[W b] A⁻¹ per dense layer, JᵀJ ≈ A ⊗ S (running averages)", "#9e6b3b",
       KroneckerHigOptions{.kappa = 1.0}},
      {Kind::kLearning, "kfac-hig", "Kronecker HIG",
       "Δ[W b] = −η S^{−3/4} ∇[W b] A^{−3/4} per dense layer, JᵀJ ≈ A ⊗ S (running averages)",
       "#66c2a4", KroneckerHigOptions{}},
      {Kind::kLearning, "lanczos-gn", "Lanczos GN",
       "Δθ = −η Jᵀ (J Jᵀ)⁻¹ ∂L/∂y by q Lanczos steps on J Jᵀ, matrix-free", "#c49c94",
       LanczosHigOptions{.kappa = 1.0}},
      {Kind::kLearning, "lanczos-hig", "Lanczos HIG",
       "Δθ = −η Jᵀ (J Jᵀ)^{−3/4} ∂L/∂y by q Lanczos steps on J Jᵀ, matrix-free", "#2ca25f",
       LanczosHigOptions{}},
  };
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
  if (id == "kfac" || id == "lanczos-gn") return "gn";
  if (id == "kfac-hig" || id == "lanczos-hig") return "hig";
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
  return make_optimizer(with_settings(find_rule(Kind::kDirect, id), settings));
}

std::unique_ptr<LearningUpdate> make_learning_update(const AnyRuleOptions& options) {
  return build<LearningUpdate>(options, Kind::kLearning, LearningRuleTypes{});
}

std::unique_ptr<LearningUpdate> make_learning_update(const std::string& id,
                                                     const RuleSettings& settings) {
  return make_learning_update(with_settings(find_rule(Kind::kLearning, id), settings));
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
