#include "physgrad/catalogue.hpp"

#include <type_traits>

#include "physgrad/error.hpp"
#include "physgrad/learn/adam.hpp"
#include "physgrad/text.hpp"

namespace physgrad {

namespace {

using Kind = RuleKind;

// Applies the fields of `s` that `o` has (requires-expressions pick them at compile time).
template <typename Options>
void apply(Options& o, const RuleSettings& s) {
  const auto take = [](auto& field, const auto& value) {
    if (value) field = *value;
  };
  if constexpr (requires { o.lr; }) {
    take(o.lr, s.lr);
  } else if constexpr (requires { o.initial_step; }) {
    take(o.initial_step, s.lr);
  }
  if constexpr (requires { o.beta; }) take(o.beta, s.beta);
  if constexpr (requires { o.beta1; }) take(o.beta1, s.beta1);
  if constexpr (requires { o.beta2; }) take(o.beta2, s.beta2);
  if constexpr (requires { o.epsilon; }) take(o.epsilon, s.epsilon);
  if constexpr (requires { o.rcond; }) take(o.rcond, s.rcond);
  if constexpr (requires { o.kappa; }) take(o.kappa, s.kappa);
  if constexpr (requires { o.backend; }) take(o.backend, s.backend);
  if constexpr (requires { o.precision; }) take(o.precision, s.precision);
  if constexpr (requires { o.eigensolver; }) take(o.eigensolver, s.eigensolver);
  if constexpr (requires { o.memory; }) take(o.memory, s.memory);
  if constexpr (requires { o.line_search; }) {
    take(o.line_search.c1, s.c1);
    take(o.line_search.c2, s.c2);
  }
  if constexpr (requires { o.initial_damping; }) take(o.initial_damping, s.initial_damping);
  if constexpr (requires { o.min_damping; }) take(o.min_damping, s.min_damping);
  if constexpr (requires { o.inverse.method; }) {
    take(o.inverse.method, s.inverse);
    take(o.inverse.tolerance, s.inverse_tolerance);
    take(o.inverse.max_iterations, s.inverse_iterations);
    take(o.inverse.relative_tolerance, s.inverse_relative_tolerance);
    take(o.inverse.function_tolerance, s.inverse_function_tolerance);
    take(o.inverse.rcond, s.inverse_rcond);
  }
  if constexpr (requires { o.y_step; }) take(o.y_step, s.y_step);
  if constexpr (requires { o.adam; }) apply(o.adam, s);  // sip's Adam on the proxy loss
}

// Thrown when a factory gets the options of a rule of the other kind.
Error wrong_kind(const RuleOptions& options, Kind wanted) {
  std::vector<std::string> ids;
  for (const RuleInfo& rule : rule_catalogue()) {
    if (rule.defaults.index() == options.index()) ids.push_back(rule.id);
  }
  return Error(std::string(wanted == Kind::kDirect ? "make_optimizer" : "make_learning_update") +
               ": the options of " + comma_list(ids) + " make no " +
               (wanted == Kind::kDirect ? "direct" : "learning") + " rule");
}

}  // namespace

const std::vector<RuleInfo>& rule_catalogue() {
  static const std::vector<RuleInfo> rules = {
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
      {Kind::kLearning, "adam", "Adam", "Δθ = −η m̂/(√v̂ + ε) on ∇θL", "#ff7f0e", AdamOptions{}},
      {Kind::kLearning, "gn", "Gauss-Newton",
       "Δθ = −η J⁺ ∂L/∂y, J the stacked Jacobian, σ ≤ τσ_max dropped", "#8c564b",
       HigOptions{.kappa = 1.0}},
      {Kind::kLearning, "hig", "HIG", "Δθ = −η V Σ^{−1/2} Uᵀ ∂L/∂y, J = UΣVᵀ, σ ≤ τσ_max dropped",
       "#00633a", HigOptions{}},
      {Kind::kLearning, "sip", "SIP", "x̃ = P⁻¹(y + ηΔy; x), Adam on ½‖f(in; θ) − x̃‖²",
       "#000000", SipOptions{}},
  };
  return rules;
}

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

RuleOptions with_settings(RuleOptions options, const RuleSettings& settings) {
  std::visit([&settings](auto& o) { apply(o, settings); }, options);
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

std::unique_ptr<Optimizer> make_optimizer(const RuleOptions& options) {
  return std::visit(
      [&options](const auto& o) -> std::unique_ptr<Optimizer> {
        using T = std::decay_t<decltype(o)>;
        if constexpr (std::is_same_v<T, GradientDescentOptions>) {
          return std::make_unique<GradientDescent>(o);
        } else if constexpr (std::is_same_v<T, MomentumOptions>) {
          return std::make_unique<Momentum>(o);
        } else if constexpr (std::is_same_v<T, AdamOptions>) {
          return std::make_unique<Adam>(o);
        } else if constexpr (std::is_same_v<T, NewtonOptions>) {
          return std::make_unique<Newton>(o);
        } else if constexpr (std::is_same_v<T, BfgsOptions>) {
          return std::make_unique<Bfgs>(o);
        } else if constexpr (std::is_same_v<T, LbfgsOptions>) {
          return std::make_unique<Lbfgs>(o);
        } else if constexpr (std::is_same_v<T, GaussNewtonOptions>) {
          return std::make_unique<GaussNewton>(o);
        } else if constexpr (std::is_same_v<T, LevenbergMarquardtOptions>) {
          return std::make_unique<LevenbergMarquardt>(o);
        } else if constexpr (std::is_same_v<T, InverseGradientOptions>) {
          return std::make_unique<InverseGradient>(o);
        } else if constexpr (std::is_same_v<T, PhysicalGradientOptions>) {
          return std::make_unique<PhysicalGradient>(o);
        } else {
          throw wrong_kind(options, Kind::kDirect);
        }
      },
      options);
}

std::unique_ptr<Optimizer> make_optimizer(const std::string& id, const RuleSettings& settings) {
  return make_optimizer(with_settings(find_rule(Kind::kDirect, id).defaults, settings));
}

std::unique_ptr<LearningUpdate> make_learning_update(const RuleOptions& options) {
  return std::visit(
      [&options](const auto& o) -> std::unique_ptr<LearningUpdate> {
        using T = std::decay_t<decltype(o)>;
        if constexpr (std::is_same_v<T, SgdOptions>) {
          return std::make_unique<SgdUpdate>(o);
        } else if constexpr (std::is_same_v<T, AdamOptions>) {
          return std::make_unique<AdamUpdate>(o);
        } else if constexpr (std::is_same_v<T, HigOptions>) {
          return std::make_unique<HigUpdate>(o);
        } else if constexpr (std::is_same_v<T, SipOptions>) {
          return std::make_unique<SipUpdate>(o);
        } else {
          throw wrong_kind(options, Kind::kLearning);
        }
      },
      options);
}

std::unique_ptr<LearningUpdate> make_learning_update(const std::string& id,
                                                     const RuleSettings& settings) {
  return make_learning_update(with_settings(find_rule(Kind::kLearning, id).defaults, settings));
}

}  // namespace physgrad
