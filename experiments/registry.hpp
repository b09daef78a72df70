// The reference experiments: each experiment's file defines its factory; registry.cpp lists them
// in display order (builtin_experiments()), and builtin_registry() is the Registry of them
// (physgrad/run/cases/registry.hpp) that the CLI, the Python module and the tests hand to run/.
#pragma once

#include <memory>
#include <vector>

#include "physgrad/run/cases/registry.hpp"

namespace physgrad::experiments {

// The reference experiments, new, in display order: a program adds its own to these and builds
// its Registry of them all.
std::vector<std::unique_ptr<run::Experiment>> builtin_experiments();
// A Registry of builtin_experiments(), built once.
const run::Registry& builtin_registry();

std::unique_ptr<run::Experiment> make_scaled_toy();
std::unique_ptr<run::Experiment> make_sensitivity();
std::unique_ptr<run::Experiment> make_comparison();
std::unique_ptr<run::Experiment> make_hig_toy();
std::unique_ptr<run::Experiment> make_sin_rotation();
std::unique_ptr<run::Experiment> make_heat_inverse();
std::unique_ptr<run::Experiment> make_oscillators();
std::unique_ptr<run::Experiment> make_quantum_dipole();
std::unique_ptr<run::Experiment> make_poisson();
std::unique_ptr<run::Experiment> make_sip_poisson();
std::unique_ptr<run::Experiment> make_time_reversal();

}  // namespace physgrad::experiments
