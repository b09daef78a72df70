#include "experiment_list.hpp"

#include "physgrad/text.hpp"

namespace physgrad::experiments {

const std::vector<std::unique_ptr<Experiment>>& registry() {
  static const std::vector<std::unique_ptr<Experiment>> experiments = [] {
    std::vector<std::unique_ptr<Experiment>> list;
    list.push_back(make_scaled_toy());
    list.push_back(make_sensitivity());
    list.push_back(make_comparison());
    list.push_back(make_hig_toy());
    list.push_back(make_sin_rotation());
    list.push_back(make_heat_inverse());
    list.push_back(make_oscillators());
    list.push_back(make_quantum_dipole());
    list.push_back(make_poisson());
    list.push_back(make_time_reversal());
    return list;
  }();
  return experiments;
}

const Experiment& find_experiment(const std::string& name) {
  std::vector<std::string> known;
  for (const auto& experiment : registry()) {
    if (experiment->name() == name) return *experiment;
    known.push_back(experiment->name());
  }
  throw unknown_name_error("experiment", name, known);
}

}  // namespace physgrad::experiments
