#include "physgrad/run/cases/registry.hpp"

#include "physgrad/error.hpp"
#include "physgrad/text.hpp"

namespace physgrad::run {

Registry::Registry(std::vector<std::unique_ptr<Experiment>> experiments)
    : experiments_(std::move(experiments)) {
  for (std::size_t i = 0; i < experiments_.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      if (experiments_[i]->name() == experiments_[j]->name()) {
        throw Error("registry: two experiments are named " + in_quotes(experiments_[i]->name()));
      }
    }
  }
}

const Experiment& Registry::find(const std::string& name) const {
  std::vector<std::string> known;
  for (const auto& experiment : experiments_) {
    if (experiment->name() == name) return *experiment;
    known.push_back(experiment->name());
  }
  throw unknown_name_error("experiment", name, known);
}

std::vector<std::string> Registry::reference_names() const {
  std::vector<std::string> names;
  for (const auto& experiment : experiments_) {
    const auto* learning = dynamic_cast<const LearningExperiment*>(experiment.get());
    if (learning != nullptr && learning->reference(1, 0)) names.push_back(experiment->name());
  }
  return names;
}

ReferenceCase Registry::reference(const std::string& name, Index batch, std::uint64_t seed) const {
  if (batch < 1) throw Error("batch must be ≥ 1, got " + std::to_string(batch));
  for (const auto& experiment : experiments_) {
    const auto* learning = dynamic_cast<const LearningExperiment*>(experiment.get());
    if (learning == nullptr || experiment->name() != name) continue;
    if (std::optional<ReferenceCase> found = learning->reference(batch, seed)) return *found;
  }
  throw unknown_name_error("reference configuration", name, reference_names());
}

}  // namespace physgrad::run
