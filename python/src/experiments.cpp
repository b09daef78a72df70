// Experiments from Python: the registered experiments (and a script's own, own_experiments.cpp)
// run, resumed and indexed, and a run folder's metrics as arrays.
#include <pybind11/numpy.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <utility>
#include <vector>

#include "bindings.hpp"
#include "physgrad/error.hpp"
#include "physgrad/io/csv.hpp"
#include "physgrad/io/json_file.hpp"
#include "registry.hpp"
#include "physgrad/run/run.hpp"
#include "physgrad/run/pages/run_index.hpp"
#include "physgrad/stop.hpp"
#include "python_simulator.hpp"

namespace physgrad::python {

namespace {

// What open_metrics and open_summary read at most: the limits `physgrad report` reads a run
// folder's files with (src/run/pages/run_index.cpp), so that a file of any size, a FIFO or a device
// neither fills the memory nor blocks.
constexpr std::size_t kMaxSummaryBytes = std::size_t{8} << 20;
constexpr std::size_t kMaxSummaryDepth = 64;
constexpr std::size_t kMaxMetricsBytes = std::size_t{32} << 20;

// The bytes of FOLDER/NAME, a regular file of at most `max_bytes`; Error "open_metrics:
// FOLDER/metrics.csv is a directory" (a FIFO, a device, too large, missing) otherwise.
std::string read_run_file(const char* who, const std::string& folder, const char* name,
                          std::size_t max_bytes) {
  const std::filesystem::path path = std::filesystem::path(folder) / name;
  try {
    py::gil_scoped_release released;
    return read_regular_file(path, max_bytes);
  } catch (const Error& e) {
    throw Error(std::string(who) + ": " + path.string() + " " + e.what());
  }
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
  const CsvData data =
      parse_csv(read_run_file("open_metrics", folder, "metrics.csv", kMaxMetricsBytes));
  py::dict out;
  for (std::size_t c = 0; c < data.columns.size(); ++c) {
    out[py::str(data.columns[c])] = column_values(data, c);
  }
  return out;
}

py::object open_summary(const std::string& folder) {
  const std::string text =
      read_run_file("open_summary", folder, "summary.json", kMaxSummaryBytes);
  try {
    return to_python(parse_json_text(text, kMaxSummaryDepth));
  } catch (const Error& e) {
    throw Error("open_summary: " + (std::filesystem::path(folder) / "summary.json").string() +
                ": " + e.what());
  }
}

// An option's value as the command line would give it: a list (or tuple) joins its items with
// commas, nested lists flattened. Read without recursion, with limits: nesting at most
// kMaxOptionDepth deep, a list that contains itself, or more than kMaxOptionText characters are
// an Error naming the option.
constexpr std::size_t kMaxOptionDepth = 32;
constexpr std::size_t kMaxOptionText = std::size_t{1} << 20;

std::string option_text(const std::string& name, const py::handle& value) {
  const auto is_list = [](const py::handle& v) {
    return py::isinstance<py::list>(v) || py::isinstance<py::tuple>(v);
  };
  if (!is_list(value)) return py::str(value).cast<std::string>();
  std::string text;
  bool first = true;
  // The lists being read, outermost first, each with the place of its next item.
  std::vector<std::pair<py::sequence, std::size_t>> open{
      {py::reinterpret_borrow<py::sequence>(value), 0}};
  while (!open.empty()) {
    auto& [list, next] = open.back();
    if (next == list.size()) {
      open.pop_back();
      continue;
    }
    const py::object item = list[next++];
    if (is_list(item)) {
      for (const auto& [outer, unused] : open) {
        if (outer.ptr() == item.ptr()) {
          throw Error("option " + name + ": the list contains itself");
        }
      }
      if (open.size() == kMaxOptionDepth) {
        throw Error("option " + name + ": lists nested deeper than " +
                    std::to_string(kMaxOptionDepth) + " levels");
      }
      open.emplace_back(py::reinterpret_borrow<py::sequence>(item), 0);
      continue;
    }
    text += (first ? "" : ",") + py::str(item).cast<std::string>();
    first = false;
    if (text.size() > kMaxOptionText) {
      throw Error("option " + name + ": more than " + std::to_string(kMaxOptionText) +
                  " characters");
    }
  }
  return text;
}

// `text` with the command that continues the run (`physgrad resume FOLDER`, which knows only
// the reference experiments) as the Python call that does, when the script has experiments of
// its own (`own` not None): physgrad.resume_experiment('FOLDER', experiments=[...]). FOLDER runs
// to the end of the text, or to " runs it again" (RunFolder::abandon's two forms).
std::string python_resume_text(const std::string& text, const py::object& own) {
  const std::string cli = "physgrad resume ";
  const std::size_t at = text.find(cli);
  const std::string names = at == std::string::npos ? "" : own_names(own);
  if (names.empty()) return text;
  const std::size_t start = at + cli.size();
  const std::size_t again = text.find(" runs it again", start);
  const std::size_t end = again == std::string::npos ? text.size() : again;
  const std::string folder = text.substr(start, end - start);
  const std::string call = "physgrad.resume_experiment(" +
                           py::repr(py::str(folder)).cast<std::string>() +
                           ", experiments=[...]) given the LearningExperiment " + names +
                           " again";
  return std::string(text).replace(at, end - at, call);
}

// What a run returns to Python: where it is, whether it finished, and its summary.json as a dict.
py::dict outcome_dict(const run::RunOutcome& outcome, const py::object& own) {
  py::dict out;
  out["folder"] = outcome.folder.string();
  out["finished"] = outcome.finished;
  out["report"] = outcome.report.string();
  out["stopped"] = python_resume_text(outcome.stopped, own);
  out["summary"] = !outcome.summary ? py::object(py::none())
                                     : py::module_::import("json").attr("loads")(
                                           run::run_summary_json(*outcome.summary).dump());
  return out;
}

// The hooks of a run called from Python: every progress line to `progress` (a callable, or None
// for silence, or True for the lines that stay — a run started or finished — on sys.stderr), and
// at each line a look at Python's pending signals: a Ctrl-C (KeyboardInterrupt) becomes the
// library's stop request, so that the run stops in order and keeps its checkpoint. The run
// itself releases the interpreter; each hook takes it back for its call.
struct PythonHooks {
  py::object progress;
  bool interrupted = false;

  run::RunHooks hooks() {
    run::RunHooks h;
    h.progress = [this](const std::string& line) { deliver(line, false); };
    h.progress_event = [this](const std::string& line) { deliver(line, true); };
    h.log = [this](const std::string& line) { deliver(line, true); };
    return h;
  }

  void deliver(const std::string& line, bool stays) {
    py::gil_scoped_acquire held;
    if (PyErr_CheckSignals() != 0) {
      // Only KeyboardInterrupt is taken here; another exception a signal handler raised is
      // dropped with the run's stop, which it asked for.
      PyErr_Clear();
      interrupted = true;
      request_stop();
    }
    if (progress.is_none()) return;
    if (py::isinstance<py::bool_>(progress)) {
      if (progress.cast<bool>() && stays) {
        py::module_::import("sys").attr("stderr").attr("write")(line + "\n");
      }
      return;
    }
    progress(line);
  }
};

// Raises KeyboardInterrupt naming the stopped run (and how to continue it) when Ctrl-C stopped
// it: seen by a progress hook, or by a callback of one of `own`'s experiments. The stop request
// is cleared whenever Ctrl-C made it, also when the run finished before it stopped.
py::dict finished_outcome(const run::RunOutcome& outcome, const PythonHooks& hooks,
                          const py::object& own) {
  const bool interrupted = own_interrupted(own) || hooks.interrupted;
  if (interrupted) clear_stop_request();
  if (interrupted && !outcome.finished) {
    const std::string message = python_resume_text(outcome.stopped, own);
    PyErr_SetString(PyExc_KeyboardInterrupt, message.c_str());
    throw py::error_already_set();
  }
  return outcome_dict(outcome, own);
}

// Runs experiment `name` (a reference experiment or one of `own`) with `options` (option name →
// value, as `physgrad run NAME --NAME VALUE`) into the run folder `out` (empty: --out, or a new
// runs/NAME-<timestamp>) through the library's run lifecycle (run/run.hpp).
py::dict run_experiment(const std::string& name, const py::dict& options, const std::string& out,
                        const py::object& progress, const py::object& own) {
  const run::Registry registry = registry_with(own);
  const run::Experiment& experiment = registry.find(name);
  std::vector<std::pair<std::string, std::string>> given;
  for (const auto& [key, value] : options) {
    const std::string key_text = py::str(key).cast<std::string>();
    given.emplace_back(key_text, option_text(key_text, value));
  }
  const run::Settings settings = run::resolve_settings(experiment, given);
  PythonHooks hooks{progress};
  run::RunOutcome outcome;
  try {
    py::gil_scoped_release released;
    outcome = run::Run::start(experiment, settings, out, hooks.hooks());
  } catch (const Error& e) {
    if (own_interrupted(own) || hooks.interrupted) clear_stop_request();
    const std::string message = python_resume_text(e.what(), own);
    raise_own_callback_error(own, "experiment " + name + ": " + message);
    if (message != e.what()) throw Error(message);
    throw;
  }
  return finished_outcome(outcome, hooks, own);
}

py::dict resume_experiment(const std::string& folder, const py::object& progress,
                           const py::object& own) {
  const run::Registry registry = registry_with(own);
  PythonHooks hooks{progress};
  run::RunOutcome outcome;
  try {
    py::gil_scoped_release released;
    outcome = run::Run::resume(registry, folder, hooks.hooks());
  } catch (const Error& e) {
    if (own_interrupted(own) || hooks.interrupted) clear_stop_request();
    const std::string message = python_resume_text(e.what(), own);
    raise_own_callback_error(own, "resume " + folder + ": " + message);
    if (message != e.what()) throw Error(message);
    throw;
  }
  return finished_outcome(outcome, hooks, own);
}

// `physgrad report FOLDER` with the reference experiments and `own`: {folders, page}; what is
// left out, one line each, on sys.stderr.
py::dict write_index(const std::string& folder, const py::object& own) {
  const run::Registry registry = registry_with(own);
  std::ostringstream warnings;
  run::RunIndex index;
  {
    py::gil_scoped_release released;
    index = run::write_run_index(registry, folder, warnings);
  }
  if (!warnings.str().empty()) {
    py::module_::import("sys").attr("stderr").attr("write")(warnings.str());
  }
  py::dict out;
  out["folders"] = index.folders;
  out["page"] = index.page.string();
  return out;
}

}  // namespace

void bind_experiments(py::module_& m) {
  m.def("experiments",
        [] {
          py::list out;
          for (const auto& e : experiments::builtin_registry()) {
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
        py::arg("out") = "", py::arg("progress") = true, py::arg("experiments") = py::none(),
        "Runs experiment NAME with options {name: value} (as `physgrad run NAME --name value`; a "
        "list is joined by commas) into the run folder `out`; returns {folder, finished, report, "
        "stopped, summary}. progress: True writes the lines that stay (a run started or "
        "finished, with the time left) to sys.stderr, None is silent, a callable gets every "
        "progress line. Ctrl-C stops the run in order (a learning run keeps its checkpoint) and "
        "raises KeyboardInterrupt naming the folder to resume. experiments: the script's own "
        "LearningExperiment objects, NAME among them or the reference experiments.");
  m.def("resume_experiment", &resume_experiment, py::arg("folder"), py::arg("progress") = true,
        py::arg("experiments") = py::none(),
        "Continues the unfinished run in `folder` (as `physgrad resume FOLDER`); progress, "
        "Ctrl-C and experiments as in run_experiment.");
  m.def("write_index", &write_index, py::arg("folder"), py::arg("experiments") = py::none(),
        "Writes FOLDER/index.html over the run folders in FOLDER (as `physgrad report FOLDER`); "
        "returns {folders, page}. experiments: as in run_experiment (their defaults are what "
        "the tables compare options with).");
}

}  // namespace physgrad::python
