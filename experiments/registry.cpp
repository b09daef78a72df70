#include "framework.hpp"
#include "registry.hpp"

namespace physgrad::experiments {

std::vector<std::unique_ptr<Experiment>> builtin_experiments() {
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
  list.push_back(make_sip_poisson());
  list.push_back(make_time_reversal());
  return list;
}

const Registry& builtin_registry() {
  static const Registry experiments(builtin_experiments());
  return experiments;
}

}  // namespace physgrad::experiments
