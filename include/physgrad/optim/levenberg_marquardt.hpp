// Levenberg-Marquardt: Δx = −(A + μ·diag(A))⁻¹ Jᵀ ∂L/∂y with A = Jᵀ H_y J; a trial is accepted
// when the gain ratio ρ = (L(x) − L(x+Δx)) / (−gᵀΔx − ½ΔxᵀAΔx) > 0, and μ adapts by ρ (Nielsen).
#pragma once

#include "physgrad/optim/optimizer.hpp"
#include "physgrad/rule_descriptor.hpp"
#include "physgrad/rule_option.hpp"

namespace physgrad {

struct LevenbergMarquardtOptions {
  double initial_damping = 1e-3;  // μ₀ > 0, relative to diag(A) (Marquardt scaling)
  double min_damping = 1e-15;     // μ never drops below this (> 0)

  // Each option once: name, member, range, help (params(), settings by name, validation).
  static const OptionList<LevenbergMarquardtOptions>& descriptors();
};

// Bounds: variables held at a bound (Domain::free_variables) stay; the step in the others is cut
// to the box by projection and the gain ratio is that of the step taken. x_scale replaces the
// Marquardt scaling diag(A) by the trust region ‖Δx ⊘ s‖ (the damping μ·c·D⁻², c = max diag(DAD)
// at the first step).
class LevenbergMarquardt final : public Optimizer {
 public:
  using Options = LevenbergMarquardtOptions;
  // Its rule in the catalogue (catalogue.hpp): id, label, formula, colour, defaults.
  static const RuleDescriptors<Options>& rules() {
    static const RuleDescriptors<Options> list = {
        {.id = "lm", .label = "Levenberg-Marquardt",
         .formula = "Δx = −(A + μ diag A)⁻¹ Jᵀ ∂L/∂y, μ by gain ratio", .colour = "#e377c2",
         .derivative = RuleDerivative::kJacobian},
    };
    return list;
  }
  explicit LevenbergMarquardt(Options options = {});
  std::string id() const override { return rules().front().id; }
  nlohmann::json params() const override { return option_values(options_); }
  void reset() override;
  double damping() const { return mu_; }

 private:
  Step propose(const Objective& objective, const Vector& x, const Domain& domain) override;
  Options options_;
  double mu_ = 0;
  double nu_ = 2;    // growth factor of μ after consecutive rejections
  double unit_ = 0;  // with x_scale: the damping's unit, max diag(A_z) at the first step
};

}  // namespace physgrad
