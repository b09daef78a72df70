#include "reference_case.hpp"

#include "physgrad/error.hpp"
#include "physgrad/text.hpp"

namespace physgrad::experiments {

const std::vector<std::string>& reference_case_names() {
  static const std::vector<std::string> names = {"hig-toy", "oscillators", "quantum-dipole",
                                                 "poisson"};
  return names;
}

ReferenceCase reference_case(const std::string& name, Index batch, std::uint64_t seed) {
  if (batch < 1) throw Error("batch must be ≥ 1, got " + std::to_string(batch));
  if (name == "hig-toy") return hig_toy_reference(batch, seed);
  if (name == "oscillators") return oscillators_reference(batch, seed);
  if (name == "quantum-dipole") return quantum_dipole_reference(batch, seed);
  if (name == "poisson") return poisson_reference(batch, seed);
  throw unknown_name_error("reference configuration", name, reference_case_names());
}

namespace {

RuleDefaults rule_defaults(const ReferenceCase& reference, const std::string& id) {
  const auto found = reference.defaults.find(id);
  return found == reference.defaults.end() ? RuleDefaults{} : found->second;
}

}  // namespace

std::unique_ptr<LearningUpdate> make_reference_update(const ReferenceCase& reference,
                                                      const std::string& id) {
  return make_learning_update(id, rule_defaults(reference, id).settings);
}

Index reference_batch(const ReferenceCase& reference, const std::string& id) {
  return rule_defaults(reference, id).batch.value_or(TrainerOptions{}.batch_size);
}

}  // namespace physgrad::experiments
