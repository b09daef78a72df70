// The parts of the extension module _physgrad, one per area of the Python API (docs/python.md):
// each adds its functions and classes to the module.
#pragma once

#include <pybind11/pybind11.h>

#include <nlohmann/json.hpp>
#include <string>

#include "physgrad/catalogue.hpp"
#include "physgrad/physics/checked_simulator.hpp"
#include "physgrad/run/cases/registry.hpp"

namespace physgrad::python {

void bind_direct(pybind11::module_& m);       // minimize, local_inverse, rules (direct.cpp)
void bind_learning(pybind11::module_& m);     // HIG/GN steps, reference steps (learning.cpp)
void bind_sip(pybind11::module_& m);          // SIP's options and targets (sip.cpp)
void bind_experiments(pybind11::module_& m);  // experiments and run folders (experiments.cpp)
void bind_own_experiments(pybind11::module_& m);  // LearningExperiment (own_experiments.cpp)
void bind_structured(pybind11::module_& m);  // kfac, lanczos options and steps (structured.cpp)

// The Registry of the reference experiments and of `own` (None, or a list of the script's
// physgrad.LearningExperiment): what a run, a resume or an index of them is given.
// (own_experiments.cpp)
run::Registry registry_with(const pybind11::object& own);
// Whether Ctrl-C stopped the run of one of `own`'s experiments that just ended (the flag taken).
bool own_interrupted(const pybind11::object& own);
// The names of `own`'s experiments, quoted: "'a', 'b'".
std::string own_names(const pybind11::object& own);
// Raises in Python the exception a callback of one of `own`'s experiments raised in the run that
// just ended (its message gains " (in CONTEXT, METHOD)"); returns when none did.
void raise_own_callback_error(const pybind11::object& own, const std::string& context);

// A JSON value as the Python value json.loads would give.
pybind11::object to_python(const nlohmann::json& value);

// Rule options given by keyword (**options), as RuleSettings: numbers and names, as params()
// reports them; Error for any other value. The catalogue then refuses an unknown name and a value
// outside the option's range. (direct.cpp)
RuleSettings rule_settings(const pybind11::dict& given);

// Refuses (Error "lm: unknown option 'lr' …") a setting that rule `id` of `kind` does not take:
// where one rule is named, an option of another rule is a mistake, not a setting to pass over.
void check_rule_option_names(RuleKind kind, const std::string& id, const RuleSettings& settings);

// A real number (int, float or a NumPy number; not a bool, text or complex); Error "WHAT is
// 'abc', expected a number" otherwise.
double to_real(const pybind11::handle& value, const std::string& what);

// The simulator's work by kind, {"passes": …, "forward": …, …}. (direct.cpp)
pybind11::dict counts_dict(const SimulatorCounts& counts);

}  // namespace physgrad::python
