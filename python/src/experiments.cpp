// Experiments from Python: the registered experiments, and a run folder's metrics as arrays.
#include <pybind11/numpy.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "bindings.hpp"
#include "physgrad/error.hpp"
#include "physgrad/io/csv.hpp"
#include "physgrad/run/registry.hpp"
#include "physgrad/run/run.hpp"
#include "python_simulator.hpp"

namespace physgrad::python {

namespace {

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot read " + path.string());
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// A column as float64 when every cell is a number (nan, inf and empty cells read as NaN), else
// as a list of its texts.
py::object column_values(const CsvData& data, std::size_t column) {
  Vector numbers(static_cast<Index>(data.rows.size()));
  for (std::size_t r = 0; r < data.rows.size(); ++r) {
    const std::string& cell = data.rows[r][column];
    char* end = nullptr;
    const double value = cell.empty() ? std::nan("") : std::strtod(cell.c_str(), &end);
    if (!cell.empty() && (end == cell.c_str() || *end != '\0')) {
      py::list texts;
      for (const auto& row : data.rows) texts.append(row[column]);
      return texts;
    }
    numbers(static_cast<Index>(r)) = value;
  }
  return to_numpy(numbers);
}

py::dict open_metrics(const std::string& folder) {
  const CsvData data = parse_csv(read_text(std::filesystem::path(folder) / "metrics.csv"));
  py::dict out;
  for (std::size_t c = 0; c < data.columns.size(); ++c) {
    out[py::str(data.columns[c])] = column_values(data, c);
  }
  return out;
}

py::object open_summary(const std::string& folder) {
  const std::string text = read_text(std::filesystem::path(folder) / "summary.json");
  return py::module_::import("json").attr("loads")(text);
}

// An option's value as the command line would give it: a list joins its items with commas.
std::string option_text(const py::handle& value) {
  if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value)) {
    std::string text;
    for (const py::handle item : value) text += (text.empty() ? "" : ",") + option_text(item);
    return text;
  }
  return py::str(value).cast<std::string>();
}

// What a run returns to Python: where it is, whether it finished, and its summary.json as a dict.
py::dict outcome_dict(const experiments::RunOutcome& outcome) {
  py::dict out;
  out["folder"] = outcome.folder.string();
  out["finished"] = outcome.finished;
  out["report"] = outcome.report.string();
  out["stopped"] = outcome.stopped;
  out["summary"] = outcome.summary.is_null()
                       ? py::object(py::none())
                       : py::module_::import("json").attr("loads")(outcome.summary.dump());
  return out;
}

// Runs experiment `name` with `options` (option name → value, as `physgrad run NAME --NAME VALUE`)
// into the run folder `out` (empty: --out, or a new runs/NAME-<timestamp>) through the library's
// run lifecycle (run/run.hpp), without progress output.
py::dict run_experiment(const std::string& name, const py::dict& options, const std::string& out) {
  const experiments::Experiment& experiment = experiments::registry().find(name);
  std::vector<std::pair<std::string, std::string>> given;
  for (const auto& [key, value] : options) {
    given.emplace_back(py::str(key).cast<std::string>(), option_text(value));
  }
  const experiments::Settings settings = experiments::resolve_settings(experiment, given);
  experiments::RunOutcome outcome;
  {
    py::gil_scoped_release released;
    outcome = experiments::Run::start(experiment, settings, out);
  }
  return outcome_dict(outcome);
}

py::dict resume_experiment(const std::string& folder) {
  experiments::RunOutcome outcome;
  {
    py::gil_scoped_release released;
    outcome = experiments::Run::resume(folder);
  }
  return outcome_dict(outcome);
}

}  // namespace

void bind_experiments(py::module_& m) {
  m.def("experiments",
        [] {
          py::list out;
          for (const auto& e : experiments::registry()) {
            py::dict d;
            d["name"] = e->name();
            d["description"] = e->description();
            out.append(d);
          }
          return out;
        },
        "The registered experiments: name and description of each.");
  m.def("open_metrics", &open_metrics, py::arg("folder"),
        "A run folder's metrics.csv as {column: array} (a text column as a list).");
  m.def("open_summary", &open_summary, py::arg("folder"),
        "A run folder's summary.json as a dict.");
  m.def("run_experiment", &run_experiment, py::arg("name"), py::arg("options") = py::dict(),
        py::arg("out") = "",
        "Runs experiment NAME with options {name: value} (as `physgrad run NAME --name value`; a "
        "list is joined by commas) into the run folder `out`; returns {folder, finished, report, "
        "stopped, summary}.");
  m.def("resume_experiment", &resume_experiment, py::arg("folder"),
        "Continues the unfinished run in `folder` (as `physgrad resume FOLDER`).");
}

}  // namespace physgrad::python
