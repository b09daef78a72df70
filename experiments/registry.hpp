// The reference experiments: each experiment's file defines its factory; registry.cpp lists them
// in display order (builtin_experiments()), and builtin_registry() is the Registry of them
// (physgrad/run/cases/registry.hpp) that the CLI, the Python module and the tests hand to run/.
#pragma once

#include <memory>
#include <vector>

#include "physgrad/run/cases/registry.hpp"

namespace physgrad::experiments {

// The reference experiments are written in the terms of the framework (namespace physgrad::run):
// its names are theirs. Transitional, for the front ends and tests that still name the
// framework's types through physgrad::experiments (experiments::Run, ex::Settings): new code
// names them physgrad::run::….
using namespace physgrad::run;

// The reference experiments, new, in display order: a program adds its own to these and builds
// its Registry of them all.
std::vector<std::unique_ptr<Experiment>> builtin_experiments();
// A Registry of builtin_experiments(), built once.
const Registry& builtin_registry();

std::unique_ptr<Experiment> make_scaled_toy();
std::unique_ptr<Experiment> make_sensitivity();
std::unique_ptr<Experiment> make_comparison();
std::unique_ptr<Experiment> make_hig_toy();
std::unique_ptr<Experiment> make_sin_rotation();
std::unique_ptr<Experiment> make_heat_inverse();
std::unique_ptr<Experiment> make_oscillators();
std::unique_ptr<Experiment> make_quantum_dipole();
std::unique_ptr<Experiment> make_poisson();
std::unique_ptr<Experiment> make_sip_poisson();
std::unique_ptr<Experiment> make_time_reversal();

}  // namespace physgrad::experiments
