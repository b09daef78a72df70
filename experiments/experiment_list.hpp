// Factories of the built-in experiments; registry.cpp lists them in display order.
#pragma once

#include <memory>

#include "physgrad/run/experiment.hpp"

namespace physgrad::experiments {

// Every registered experiment, in display order.
const std::vector<std::unique_ptr<Experiment>>& registry();
// Throws Error "unknown experiment 'x' (known: ...)".
const Experiment& find_experiment(const std::string& name);


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
