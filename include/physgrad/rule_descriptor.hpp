// Rule descriptor — what a rule says of itself beside its options: id, label, formula (the update
// in one line), colour, default Options, the derivative a step forms and whose settings it takes.
#pragma once

#include <string>
#include <vector>

#include "physgrad/text.hpp"

namespace physgrad {

// Direct rules move x (Optimizer, minimize()); learning rules move network weights θ
// (LearningUpdate, train()). "adam" and "gn" exist in both kinds.
enum class RuleKind { kDirect, kLearning };

// What one step of a rule forms of the physics' derivatives beyond the loss and its gradient:
// what sizes its widest simulator call and its largest matrix.
enum class RuleDerivative {
  kGradient,  // nothing more (first-order, quasi-Newton, y-space and inverse-simulator rules)
  // The whole Jacobian, inverted whole: direct, J of x (one sample per input in one simulator
  // call); learning, the batch's stacked Jacobian with its Gram or normal matrix.
  kJacobian,
  kHessian,           // the Hessian by differences of gradients (two samples per input)
  kJacobianProducts,  // products with the stacked Jacobian (Kronecker factors, Lanczos steps)
};

// One rule of the catalogue as its class describes it. A class lists one descriptor per
// catalogue id it is built as (rules()): HigUpdate is gn (κ = 1) and hig (κ = ½), each with its
// own defaults.
template <class Options>
struct RuleDescriptor {
  std::string id;       // short lower-case id, as --optimizers takes it
  std::string label;    // display name in tables and legends
  std::string formula;  // the update in one line
  std::string colour;   // "#rrggbb", the same in every figure and for the same id in both kinds
  Options defaults{};   // the options the catalogue builds it with
  RuleDerivative derivative = RuleDerivative::kGradient;
  // The exact rule whose settings in an experiment (η, τ, batch) this structured approximation
  // takes where the experiment gives it none (kfac → gn); empty: its own.
  std::string settings_from{};
  // "#rrggbb" of the run Adam pretrains before this learning rule takes over (Adam→HIG), where it
  // has one of its own; empty: the rule's colour darkened (run/rule_colors.hpp).
  std::string pretrained_colour{};
};

template <class Options>
using RuleDescriptors = std::vector<RuleDescriptor<Options>>;

// The descriptor of `rules` with the id `id`, or null.
template <class Options>
const RuleDescriptor<Options>* find_descriptor(const RuleDescriptors<Options>& rules,
                                               const std::string& id) {
  for (const RuleDescriptor<Options>& rule : rules) {
    if (rule.id == id) return &rule;
  }
  return nullptr;
}

// The id a rule of a class listing `rules` reports when built as `id`: `id` itself when one of
// them has it, `fallback` when it is empty; Error naming an id none of them has.
template <class Options>
std::string listed_rule_id(const RuleDescriptors<Options>& rules, const std::string& id,
                           const std::string& fallback) {
  if (id.empty()) return fallback;
  if (find_descriptor(rules, id) != nullptr) return id;
  std::vector<std::string> known;
  for (const RuleDescriptor<Options>& rule : rules) known.push_back(rule.id);
  throw unknown_name_error("rule id", id, known);
}

}  // namespace physgrad
