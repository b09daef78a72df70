// The parts of the extension module _physgrad, one per area of the Python API (docs/python.md):
// each adds its functions and classes to the module.
#pragma once

#include <pybind11/pybind11.h>

#include <nlohmann/json.hpp>

namespace physgrad::python {

void bind_direct(pybind11::module_& m);       // minimize, local_inverse, rules (direct.cpp)
void bind_learning(pybind11::module_& m);     // the Jacobian step of HIG and GN (learning.cpp)
void bind_experiments(pybind11::module_& m);  // experiments and run folders (experiments.cpp)

// A JSON value as the Python value json.loads would give.
pybind11::object to_python(const nlohmann::json& value);

}  // namespace physgrad::python
