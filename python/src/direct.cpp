// Direct optimization from Python: minimize() of a Python simulator with any direct rule, the
// local inverse, and the rule catalogue.
#include <pybind11/functional.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "bindings.hpp"
#include "physgrad/catalogue.hpp"
#include "physgrad/error.hpp"
#include "physgrad/optim/minimize.hpp"
#include "physgrad/text.hpp"
#include "python_simulator.hpp"

namespace physgrad::python {

RuleSettings rule_settings(const py::dict& given) {
  RuleSettings settings;
  for (const auto& [key, value] : given) {
    const std::string name = py::str(key);
    const auto refuse = [&] {
      return Error("rule option " + name + ": " + std::string(py::str(py::repr(value))) +
                   " is not a number or a name");
    };
    if (py::isinstance<py::bool_>(value)) throw refuse();
    if (py::isinstance<py::str>(value)) {
      settings[name] = value.cast<std::string>();
    } else if (py::isinstance<py::int_>(value)) {
      settings[name] = to_integer(value, "rule option " + name,
                                  std::numeric_limits<long long>::min(),
                                  std::numeric_limits<long long>::max());
    } else {
      try {
        settings[name] = value.cast<double>();  // a float, or a NumPy number
      } catch (const py::cast_error&) {
        throw refuse();
      }
    }
  }
  return settings;
}

void check_rule_option_names(RuleKind kind, const std::string& id, const RuleSettings& settings) {
  const RuleInfo& rule = find_rule(kind, id);
  std::vector<std::string> known;
  for (const OptionDescription& option : rule_options(rule)) {
    known.push_back(option.name);
    if (!option.alias.empty()) known.push_back(option.alias);
  }
  std::sort(known.begin(), known.end());
  for (const auto& [name, value] : settings) {
    if (!std::binary_search(known.begin(), known.end(), name)) {
      throw Error(id + ": " + unknown_name_text("option", name, known));
    }
  }
}

double to_real(const py::handle& value, const std::string& what) {
  if (!py::isinstance<py::bool_>(value) && PyNumber_Check(value.ptr()) != 0 &&
      !PyComplex_Check(value.ptr())) {
    try {
      return value.cast<double>();
    } catch (const py::cast_error&) {
    }
  }
  throw Error(what + " is " + std::string(py::str(py::repr(value))) + ", expected a number");
}

py::dict counts_dict(const SimulatorCounts& c) {
  static const std::pair<const char*, long long SimulatorCounts::*> kinds[] = {
      {"passes", &SimulatorCounts::passes},       {"forward", &SimulatorCounts::forward},
      {"vjp", &SimulatorCounts::vjp},             {"jacobians", &SimulatorCounts::jacobians},
      {"hessians", &SimulatorCounts::hessians},   {"reversals", &SimulatorCounts::reversals},
      {"inverses", &SimulatorCounts::inverses}};
  py::dict d;
  for (const auto& [name, member] : kinds) d[name] = c.*member;
  return d;
}

namespace {

Vector optional_vector(const py::object& value, const char* name) {
  return value.is_none() ? Vector() : to_vector(value, "minimize", name);
}

// The Python simulator, the loss and the target of one minimize() call.
struct Problem {
  std::optional<PythonSimulator> simulator;
  L2Loss loss;
  Vector target;

  Problem(const py::object& sim, const Vector& x0, const py::object& target_value, double weight,
          CallbackErrors& errors)
      : loss(weight) {
    const Index m =
        target_value.is_none() ? -1 : to_vector(target_value, "minimize", "target").size();
    simulator.emplace(sim, x0.size(), m, x0, errors);
    target = target_value.is_none() ? Vector::Zero(simulator->output_dim())
                                    : to_vector(target_value, "minimize", "target");
  }
};

// The stopping rules, budgets and history limits given by keyword, as MinimizeOptions.
MinimizeOptions minimize_options(const py::dict& given) {
  MinimizeOptions options;
  const auto integer = [&](const char* name, long long lowest, long long highest) {
    return to_integer(given[name], std::string("minimize: ") + name, lowest, highest);
  };
  const auto real = [&](const char* name) {
    return to_real(given[name], std::string("minimize: ") + name);
  };
  constexpr long long kLongMax = std::numeric_limits<long long>::max();
  options.max_iterations =
      static_cast<int>(integer("max_iterations", 1, std::numeric_limits<int>::max()));
  options.max_evaluations = integer("max_evaluations", 0, kLongMax);
  options.max_history = integer("max_history", 2, kLongMax);
  options.max_history_values = integer("max_history_values", 2, kLongMax);
  options.loss_tolerance = real("loss_tolerance");
  options.relative_loss_tolerance = real("relative_loss_tolerance");
  options.gradient_tolerance = real("gradient_tolerance");
  options.function_tolerance = real("function_tolerance");
  options.parameter_tolerance = real("parameter_tolerance");
  options.max_seconds = real("max_seconds");
  return options;
}

// What an iteration callback returned as stop or go: True/False (also NumPy's), or None (go on).
bool callback_stops(const py::object& returned) {
  if (returned.is_none()) return false;
  if (py::isinstance<py::bool_>(returned) ||
      py::str(py::type::handle_of(returned).attr("__name__")).cast<std::string>() == "bool_") {
    return returned.cast<bool>();
  }
  throw Error("minimize: the callback returned " + std::string(py::str(py::repr(returned))) +
              " (" + std::string(py::str(py::type::handle_of(returned).attr("__name__"))) +
              "), expected True (stop), False or None (go on)");
}

// What minimize() returns to Python: the library's summary and the best iterate of the run (the
// lowest finite loss of any record, the start included), which a rule without a line search,
// Newton's, may have left behind.
struct PythonMinimizeResult : MinimizeSummary {
  Vector best_x;
  double best_loss = INFINITY;
  int best_iteration = 0;
};

PythonMinimizeResult run_minimize(const py::object& sim, const py::object& x0_value,
                             const std::string& rule, const py::object& target,
                             const py::object& loss_weight, const py::object& lower,
                             const py::object& upper, const py::object& x_scale,
                             const py::dict& stopping, const py::object& callback,
                             const std::string& differences, const py::dict& options) {
  const Vector x0 = to_vector(x0_value, "minimize", "x0");
  const RuleSettings rule_given = rule_settings(options);
  check_rule_option_names(RuleKind::kDirect, rule, rule_given);
  const std::unique_ptr<Optimizer> optimizer = make_optimizer(rule, rule_given);
  MinimizeOptions settings = minimize_options(stopping);
  const double weight = to_real(loss_weight, "minimize: loss_weight");
  const auto kind = PythonSimulator::parse_differences(differences);
  settings.lower = optional_vector(lower, "lower");
  settings.upper = optional_vector(upper, "upper");
  settings.x_scale = optional_vector(x_scale, "x_scale");

  std::optional<Problem> problem;
  CallbackErrors errors;  // the iteration is that of the last record, + 1 once it is handled
  PythonMinimizeResult result;
  settings.callback = [&](const IterationRecord& record) {
    if (record.loss < result.best_loss) {  // NaN never
      result.best_loss = record.loss;
      result.best_x = record.x;
      result.best_iteration = record.iteration;
    }
    errors.iteration = record.iteration;
    const bool stop = !callback.is_none() && call_python(errors, "callback", [&] {
      return callback_stops(callback(record.iteration, record.loss, to_numpy(record.x)));
    });
    errors.iteration = record.iteration + 1;
    return stop;
  };
  try {
    problem.emplace(sim, x0, target, weight, errors);
    problem->simulator->set_differences(kind);
    const Objective objective(*problem->simulator, problem->loss, problem->target);
    py::gil_scoped_release released;
    static_cast<MinimizeSummary&>(result) = minimize(*optimizer, objective, x0, settings);
  } catch (const CallbackFailed&) {
    raise_kept(errors, "rule " + rule + ", iteration " + std::to_string(errors.iteration));
  }
  result.counts = problem->simulator->actual(result.counts);
  if (result.best_x.size() == 0) {  // no finite loss recorded
    result.best_x = result.x;
    result.best_loss = result.loss;
  }
  return result;
}

py::dict run_local_inverse(const py::object& sim, const py::object& y_value,
                           const py::object& x0_value, const std::string& method,
                           const py::object& tolerance, const py::object& max_iterations,
                           const py::object& relative_tolerance,
                           const py::object& function_tolerance, const py::object& rcond,
                           const py::object& lower, const py::object& upper) {
  const Vector x0 = to_vector(x0_value, "local_inverse", "x0");
  const Vector y = to_vector(y_value, "local_inverse", "y");
  LocalInverseOptions options;
  options.method = parse_inverse_method(method);
  options.tolerance = to_real(tolerance, "local_inverse: tolerance");
  options.max_iterations = static_cast<int>(to_integer(
      max_iterations, "local_inverse: max_iterations", 1, std::numeric_limits<int>::max()));
  options.relative_tolerance = to_real(relative_tolerance, "local_inverse: relative_tolerance");
  options.function_tolerance = to_real(function_tolerance, "local_inverse: function_tolerance");
  options.rcond = to_real(rcond, "local_inverse: rcond");
  CallbackErrors errors;
  const PythonSimulator simulator(sim, x0.size(), y.size(), x0, errors);
  const Vector lo = optional_vector(lower, "lower"), hi = optional_vector(upper, "upper");
  const Domain domain(x0.size(), lo, hi, Vector());
  LocalInverseResult result;
  try {
    py::gil_scoped_release released;
    result = local_inverse(simulator, y, x0, Vector(), options, domain);
  } catch (const CallbackFailed&) {
    raise_kept(errors, "local inverse " + method);
  }
  py::dict out;
  out["x"] = to_numpy(result.x);
  out["residual"] = result.residual;
  out["iterations"] = result.iterations;
  out["evaluations"] = result.evaluations;
  out["counts"] = counts_dict(simulator.actual(result.counts));
  out["converged"] = result.converged;
  return out;
}

py::list rules(RuleKind kind) {
  py::list out;
  for (const RuleInfo& rule : rule_catalogue()) {
    if (rule.kind != kind) continue;
    py::dict d;
    d["id"] = rule.id;
    d["label"] = rule.label;
    d["formula"] = rule.formula;
    d["colour"] = rule.colour;
    d["defaults"] = rule_defaults_text(rule);
    out.append(d);
  }
  return out;
}

// The options of rule `id` of `kind` ("learning" or "direct") with the catalogue's defaults, by
// name as params() reports them: what physgrad.torch takes its keyword defaults from.
py::object rule_defaults(const std::string& id, const std::string& kind) {
  if (kind == "direct") return to_python(make_optimizer(id)->params());
  if (kind == "learning") return to_python(make_learning_update(id)->params());
  throw Error("rule_defaults: kind " + in_quotes(kind) + " is neither 'learning' nor 'direct'");
}

}  // namespace

void bind_direct(py::module_& m) {
  py::class_<PythonMinimizeResult>(m, "MinimizeResult",
                              "What minimize() returned: the final x, the history and the counts.")
      .def_property_readonly("x", [](const PythonMinimizeResult& s) { return to_numpy(s.x); })
      .def_readonly("loss", &MinimizeSummary::loss)
      .def_readonly("initial_loss", &MinimizeSummary::initial_loss)
      .def_property_readonly("termination",
                             [](const PythonMinimizeResult& s) { return to_string(s.termination); })
      .def_property_readonly("converged",
                             [](const PythonMinimizeResult& s) { return converged(s.termination); })
      .def_readonly("message", &MinimizeSummary::message)
      .def_readonly("iterations", &MinimizeSummary::iterations)
      .def_readonly("rejected_steps", &MinimizeSummary::rejected_steps)
      .def_readonly("evaluations", &MinimizeSummary::evaluations)
      .def_property_readonly("counts",
                             [](const PythonMinimizeResult& s) { return counts_dict(s.counts); })
      .def_readonly("wall_seconds", &MinimizeSummary::wall_seconds)
      .def_readonly("rule", &MinimizeSummary::optimizer)
      .def_property_readonly("params",
                             [](const PythonMinimizeResult& s) { return to_python(s.params); })
      .def_readonly("at_bounds", &MinimizeSummary::at_bounds)
      .def_readonly("history_dropped", &MinimizeSummary::history_dropped)
      .def_property_readonly("best_x",
                             [](const PythonMinimizeResult& s) { return to_numpy(s.best_x); })
      .def_readonly("best_loss", &PythonMinimizeResult::best_loss)
      .def_readonly("best_iteration", &PythonMinimizeResult::best_iteration)
      .def_property_readonly("history_iterations",
                             [](const PythonMinimizeResult& s) {
                               const auto size = static_cast<py::ssize_t>(s.history.size());
                               py::array_t<long long> out(size);
                               for (py::ssize_t i = 0; i < size; ++i)
                                 out.mutable_at(i) = s.history[static_cast<std::size_t>(i)].iteration;
                               return out;
                             })
      .def_property_readonly("loss_history",
                             [](const PythonMinimizeResult& s) {
                               Vector losses(static_cast<Index>(s.history.size()));
                               for (Index i = 0; i < losses.size(); ++i)
                                 losses(i) = s.history[static_cast<std::size_t>(i)].loss;
                               return to_numpy(losses);
                             })
      .def_property_readonly("x_history",
                             [](const PythonMinimizeResult& s) {
                               Matrix xs(static_cast<Index>(s.history.size()), s.x.size());
                               for (Index i = 0; i < xs.rows(); ++i)
                                 xs.row(i) = s.history[static_cast<std::size_t>(i)].x.transpose();
                               return to_numpy(xs);
                             })
      .def("brief_report", [](const PythonMinimizeResult& s) { return brief_report(s); })
      .def("full_report", [](const PythonMinimizeResult& s) { return full_report(s); })
      .def("__repr__", [](const PythonMinimizeResult& s) { return "<" + brief_report(s) + ">"; });

  m.def("_minimize", &run_minimize, py::arg("sim"), py::arg("x0"), py::arg("rule"),
        py::arg("target"), py::arg("loss_weight"), py::arg("lower"), py::arg("upper"),
        py::arg("x_scale"), py::arg("stopping"), py::arg("callback"), py::arg("differences"),
        py::arg("options"));
  m.def("_local_inverse", &run_local_inverse, py::arg("sim"), py::arg("y"), py::arg("x0"),
        py::arg("method"), py::arg("tolerance"), py::arg("max_iterations"),
        py::arg("relative_tolerance"), py::arg("function_tolerance"), py::arg("rcond"),
        py::arg("lower"), py::arg("upper"));
  m.def("direct_rules", [] { return rules(RuleKind::kDirect); },
        "The direct rules: id, label, formula, colour and defaults of each.");
  m.def("learning_rules", [] { return rules(RuleKind::kLearning); },
        "The learning rules: id, label, formula, colour and defaults of each.");
  m.def("rule_defaults", &rule_defaults, py::arg("rule"), py::arg("kind") = "learning",
        "The options of a rule with the catalogue's defaults, by name ({'lr': 1.0, ...}); kind "
        "'learning' or 'direct'.");
}

}  // namespace physgrad::python
