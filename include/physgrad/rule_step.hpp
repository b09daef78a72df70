// Step — what one update rule proposes: Δx for a direct rule (Optimizer) or Δθ for a learning
// rule (LearningUpdate), with its status and the cost of finding it; the caller sets x ← x + Δx.
#pragma once

#include <string>
#include <utility>

#include "physgrad/types.hpp"

namespace physgrad {

// What a rule proposes, a direct rule (Optimizer, optim/optimizer.hpp) for x or a learning rule
// (LearningUpdate, learn/learning_update.hpp) for the network weights θ.
struct Step {
  enum class Status {
    kOk,        // delta is the proposed update; for a direct rule x + delta lies in the box
    kRejected,  // a trial was tried and rejected (trust region); x stays, the iteration counts;
                // delta is the rejected trial (minimize() tests its length, as Ceres does), or
                // empty when the trial's loss was not finite (no length to test)
    kFailed,    // the rule cannot continue (e.g. no acceptable step length)
  };
  Step(Vector step = {}, Status how = Status::kOk, std::string why = {}, int spent = 0)
      : delta(std::move(step)), status(how), message(std::move(why)), evaluations(spent) {}

  Vector delta;          // Δx or Δθ
  Status status = Status::kOk;
  std::string message;   // why, when failed or (a learning rule) when delta is not finite
  int evaluations = 0;   // objective evaluations the step spent (value or value+gradient)
  double jacobian_seconds = 0;   // time spent forming J, J Jᵀ or JᵀJ, if any
  double inversion_seconds = 0;  // time spent in the (pseudo-)inversion, if any
};

}  // namespace physgrad
