// The extension module _physgrad: the library's errors as Python exceptions, then each part.
#include <pybind11/pybind11.h>

#include "bindings.hpp"
#include "physgrad/error.hpp"

namespace physgrad::python {

pybind11::object to_python(const nlohmann::json& value) {
  return pybind11::module_::import("json").attr("loads")(value.dump());
}

}  // namespace physgrad::python

PYBIND11_MODULE(_physgrad, m) {
  m.doc() = "physgrad: inversion-based optimization (the compiled part; see physgrad)";
  m.attr("__version__") = PHYSGRAD_VERSION;  // the project's version (CMakeLists.txt)
  // Bad input (a size, a range, an unknown name) is a ValueError; numbers that cannot be worked
  // with (NaN, no convergence) an ArithmeticError. The most derived is registered last.
  static pybind11::exception<physgrad::Error> error(m, "Error", PyExc_ValueError);
  static pybind11::exception<physgrad::NumericalError> numerical(m, "NumericalError",
                                                                 PyExc_ArithmeticError);
  pybind11::register_exception_translator([](std::exception_ptr thrown) {
    try {
      if (thrown) std::rethrow_exception(thrown);
    } catch (const physgrad::NumericalError& e) {
      numerical(e.what());
    } catch (const physgrad::Error& e) {
      error(e.what());
    }
  });
  physgrad::python::bind_direct(m);
  physgrad::python::bind_learning(m);
  physgrad::python::bind_sip(m);
  physgrad::python::bind_experiments(m);
  physgrad::python::bind_own_experiments(m);
  physgrad::python::bind_structured(m);
}
