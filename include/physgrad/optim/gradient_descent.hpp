// Gradient descent: Δx = −η ∂L/∂x.
// The baseline every inverted update is compared against; its steps scale with the square of
// the problem's sensitivity.
#pragma once

#include "physgrad/optim/optimizer.hpp"

namespace physgrad {

struct GradientDescentOptions {
  double lr = 0.01;  // η > 0
};

class GradientDescent final : public Optimizer {
 public:
  using Options = GradientDescentOptions;
  explicit GradientDescent(Options options = {});
  std::string id() const override { return "gd"; }
  nlohmann::json params() const override { return {{"lr", options_.lr}}; }

 private:
  Step propose(const Objective& objective, const Vector& x, const Domain& domain) override;
  Options options_;
};

}  // namespace physgrad
