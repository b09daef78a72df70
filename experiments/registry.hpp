// The reference experiments: each experiment's file defines its factory; registry.cpp lists
// them in display order as registry() (physgrad/run/registry.hpp).
#pragma once

#include <memory>

#include "physgrad/run/registry.hpp"

namespace physgrad::experiments {

std::unique_ptr<Experiment> make_scaled_toy();
std::unique_ptr<Experiment> make_sensitivity();
std::unique_ptr<Experiment> make_comparison();
std::unique_ptr<Experiment> make_hig_toy();
std::unique_ptr<Experiment> make_sin_rotation();
std::unique_ptr<Experiment> make_heat_inverse();
std::unique_ptr<Experiment> make_oscillators();
std::unique_ptr<Experiment> make_quantum_dipole();
std::unique_ptr<Experiment> make_poisson();
std::unique_ptr<Experiment> make_time_reversal();

}  // namespace physgrad::experiments
