// Inverse gradient (IG): Δx = J⁺ Δy with J = ∂P/∂x and Δy = η·(Newton step of L in y)
// (for L2: Δy = η(y* − y)); J⁺ is the truncated pseudo-inverse (σᵢ ≤ rcond·σ_max dropped).
#pragma once

#include "physgrad/linalg/power_pinv.hpp"
#include "physgrad/optim/optimizer.hpp"

namespace physgrad {

struct InverseGradientOptions {
  double lr = 1.0;       // η > 0, the fraction of the y-space Newton step
  double rcond = 1e-10;  // truncation of J's singular values, in [0, 1)
};

class InverseGradient final : public Optimizer {
 public:
  using Options = InverseGradientOptions;
  explicit InverseGradient(Options options = {});
  std::string id() const override { return "ig"; }
  nlohmann::json params() const override { return {{"lr", options_.lr}, {"rcond", options_.rcond}}; }

 private:
  Step propose(const Objective& objective, const Vector& x, const Domain& domain) override;
  Options options_;
};

// Δy = η·(Newton step of the loss in y) at y = P(x): the y-space target of IG, PG and SIP.
Vector y_step(const Objective& objective, const Vector& y, double lr);

}  // namespace physgrad
