// Optimizer registry — builds any direct-optimization update rule from its short id, so the
// CLI, experiments and users name rules the same way (gd, momentum, adam, newton, ...).
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "physgrad/optim/local_inverse.hpp"
#include "physgrad/optim/optimizer.hpp"

namespace physgrad {

// Every id make_optimizer() knows, in a fixed display order.
const std::vector<std::string>& direct_optimizer_ids();
// A one-line description of the rule with its formula.
std::string describe_optimizer(const std::string& id);
// The display name ("Gauss-Newton" for "gn"); the id itself when unknown.
std::string optimizer_label(const std::string& id);

struct OptimizerSettings {
  // Step size η: the learning rate of gd/momentum/adam, the damping-free step factor of
  // newton/gn/ig/pg, the first trial step of the bfgs/lbfgs line search. Not used by lm.
  // Unset: the rule's library default.
  std::optional<double> lr;
  InverseMethod inverse = InverseMethod::kAuto;  // pg only
};

// Throws Error naming the id (and listing the known ones) when it is unknown, and naming the
// value when a setting is out of range.
std::unique_ptr<Optimizer> make_optimizer(const std::string& id,
                                          const OptimizerSettings& settings = {});

}  // namespace physgrad
