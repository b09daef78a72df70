// Experiments from Python: the registered experiments, and a run folder's metrics as arrays.
#include <pybind11/numpy.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "bindings.hpp"
#include "physgrad/run/registry.hpp"
#include "physgrad/error.hpp"
#include "physgrad/io/csv.hpp"
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
}

}  // namespace physgrad::python
