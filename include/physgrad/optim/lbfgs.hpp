// L-BFGS — BFGS from the last m curvature pairs: Δx = α p, p = −H ∇L, where H ∇L comes from the
// two-loop recursion with H₀ = γ I, γ = sᵀy / yᵀy of the newest pair (N&W Algorithm 7.4, eq. 7.20).
#pragma once

#include <deque>

#include "physgrad/optim/quasi_newton.hpp"
#include "physgrad/rule_descriptor.hpp"
#include "physgrad/rule_option.hpp"

namespace physgrad {

struct LbfgsOptions {
  int memory = 10;            // m ≥ 1 curvature pairs kept
  double initial_step = 1.0;  // first trial α₀ of every line search (this rule's "lr"), > 0
  LineSearchOptions line_search{};

  // Each option once: name, member, range, help (params(), settings by name, validation).
  static const OptionList<LbfgsOptions>& descriptors();
};

// Line search, restarts and the curvature test: see QuasiNewton.
class Lbfgs final : public QuasiNewton {
 public:
  using Options = LbfgsOptions;
  // Its rule in the catalogue (catalogue.hpp): id, label, formula, colour, defaults.
  static const RuleDescriptors<Options>& rules() {
    static const RuleDescriptors<Options> list = {
        {.id = "lbfgs", .label = "L-BFGS",
         .formula = "Δx = −α H̃ ∂L/∂x, two-loop recursion, strong-Wolfe line search",
         .colour = "#c5a3e0"},
    };
    return list;
  }
  // Throws Error naming the field when an option is out of range.
  explicit Lbfgs(Options options = {});

  std::string id() const override { return rules().front().id; }
  nlohmann::json params() const override { return option_values(options_); }

 private:
  struct Pair {
    Vector s, y;
    double rho;  // 1 / yᵀs
  };
  Vector direction(const Vector& gradient) const override;  // −H g by the two-loop recursion
  bool has_curvature() const override { return !pairs_.empty(); }
  void clear_curvature() override { pairs_.clear(); }
  void add_pair(const Vector& s, const Vector& y) override;

  Options options_;
  std::deque<Pair> pairs_;  // oldest first
};

}  // namespace physgrad
