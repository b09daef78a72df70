// BFGS — quasi-Newton steps Δx = α p, p = −H ∇L, with α from a strong-Wolfe line search and the
// inverse-Hessian update H₊ = (I − ρ s yᵀ) H (I − ρ y sᵀ) + ρ s sᵀ, ρ = 1/yᵀs (N&W eq. 6.17).
#pragma once

#include "physgrad/optim/quasi_newton.hpp"
#include "physgrad/rule_descriptor.hpp"
#include "physgrad/rule_option.hpp"

namespace physgrad {

struct BfgsOptions {
  double initial_step = 1.0;  // first trial α₀ of every line search (this rule's "lr"), > 0
  LineSearchOptions line_search{};

  // Each option once: name, member, range, help (params(), settings by name, validation).
  static const OptionList<BfgsOptions>& descriptors();
};

// H starts as I; just before the first update it is rescaled to (yᵀs / yᵀy) I (N&W eq. 6.20).
// Line search, restarts and the curvature test: see QuasiNewton.
class Bfgs final : public QuasiNewton {
 public:
  using Options = BfgsOptions;
  // Its rule in the catalogue (catalogue.hpp): id, label, formula, colour, defaults.
  static const RuleDescriptors<Options>& rules() {
    static const RuleDescriptors<Options> list = {
        {.id = "bfgs", .label = "BFGS",
         .formula = "Δx = −α B⁻¹ ∂L/∂x, α by a strong-Wolfe line search", .colour = "#9467bd"},
    };
    return list;
  }
  // Throws Error naming the field when an option is out of range.
  explicit Bfgs(Options options = {});

  std::string id() const override { return rules().front().id; }
  nlohmann::json params() const override { return option_values(options_); }

 private:
  Vector direction(const Vector& gradient) const override;
  bool has_curvature() const override { return updated_; }
  void clear_curvature() override;
  void add_pair(const Vector& s, const Vector& y) override;

  Options options_;
  Matrix h_;              // inverse-Hessian approximation H (empty: the identity)
  bool updated_ = false;  // false while H is the unscaled identity
};

}  // namespace physgrad
