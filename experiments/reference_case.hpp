// The learning problem of a reference experiment at one batch, built by the experiment's own
// setup code: its simulator, loss, initial network, the first B training samples and the
// per-rule defaults. What `physgrad bench` and the micro-benchmarks time.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "physgrad/run/learning_runs.hpp"
#include "physgrad/train/trainer.hpp"

namespace physgrad::experiments {

struct ReferenceCase {
  std::shared_ptr<const Simulator> physics;
  std::shared_ptr<const Loss> loss;
  Mlp network;    // initialized from the seed, as the experiment's runs start
  Dataset batch;  // the first B samples of the experiment's training set
  std::map<std::string, RuleDefaults> defaults;  // lr, batch and τ of each rule

  LearningProblem problem() const { return {physics.get(), loss.get()}; }
};

// hig-toy (λ = 0.01), oscillators (paper variant), quantum-dipole, poisson (8×8).
const std::vector<std::string>& reference_case_names();

// NAME's problem with a batch of `batch` samples; seed as --seed of `physgrad run`. Throws
// Error for an unknown NAME (listing the known ones) or batch < 1.
ReferenceCase reference_case(const std::string& name, Index batch, std::uint64_t seed = 0);

// Rule `id` with the case's step size, τ and SIP step for it (the rule's own defaults where
// the case has none). Throws Error for an unknown id.
std::unique_ptr<LearningUpdate> make_reference_update(const ReferenceCase& reference,
                                                      const std::string& id);
// The case's batch size for rule `id` (32 where it has none).
Index reference_batch(const ReferenceCase& reference, const std::string& id);

// The parts, one per experiment file (defined there).
ReferenceCase hig_toy_reference(Index batch, std::uint64_t seed);
ReferenceCase oscillators_reference(Index batch, std::uint64_t seed);
ReferenceCase quantum_dipole_reference(Index batch, std::uint64_t seed);
ReferenceCase poisson_reference(Index batch, std::uint64_t seed);

}  // namespace physgrad::experiments
