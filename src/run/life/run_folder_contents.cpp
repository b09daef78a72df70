// What a committed run folder holds: config.json, metrics.csv, summary.json, figures and
// networks.json, written into the staging folder before commit (write_run_folder,
// run_folder.hpp); report.html beside them is written by the pages (report_page.hpp).
#include <set>

#include "physgrad/error.hpp"
#include "physgrad/io/atomic_file.hpp"
#include "physgrad/io/csv.hpp"
#include "physgrad/run/life/run_folder.hpp"
#include "physgrad/run/life/run_machine.hpp"

namespace physgrad::run {

namespace {

constexpr const char* kNetworksFile = "networks.json";

// A figure: NAME.svg, a plain file name that is not hidden.
bool is_figure_file(const std::string& name) {
  return name.size() > 4 && name.ends_with(".svg") && name[0] != '.' &&
         name.find('/') == std::string::npos;
}

CsvCell to_cell(const nlohmann::json& value) {
  if (value.is_number_integer()) return value.get<long long>();
  if (value.is_number()) return value.get<double>();
  if (value.is_string()) return value.get<std::string>();
  if (value.is_null()) return std::string();
  return value.dump();
}

}  // namespace

std::string metrics_csv(const RunContext& context) {
  std::vector<std::string> columns;
  std::set<std::string> seen;
  for (const nlohmann::json& row : context.metrics()) {
    // nlohmann::json sorts object keys; the fixed leading columns come first.
    for (const char* key : {"label", "optimizer", "iteration", "epoch", "wall_seconds"}) {
      if (row.contains(key) && seen.insert(key).second) columns.emplace_back(key);
    }
    for (const auto& [key, value] : row.items()) {
      if (seen.insert(key).second) columns.push_back(key);
    }
  }
  CsvTable table(columns);
  for (const nlohmann::json& row : context.metrics()) {
    std::vector<CsvCell> cells;
    for (const std::string& column : columns) {
      cells.push_back(row.contains(column) ? to_cell(row.at(column)) : CsvCell(std::string()));
    }
    table.add_row(std::move(cells));
  }
  return table.str();
}

nlohmann::json config_document(const Experiment& experiment, const Settings& settings,
                               const std::string& command_line) {
  return {{"experiment", experiment.name()},
          {"command", command_line},
          {"settings", settings.json()}};
}

RunSummary run_summary(const Experiment& experiment, const RunContext& context) {
  RunSummary summary{experiment.name(), context.runs(), std::nullopt, run_machine()};
  if (!context.message_figure().empty()) {
    const MessageMetric& metric = context.message_metric();
    summary.message = RunMessage{context.message_figure(), context.message(), metric.key,
                                 metric.text, metric.labels};
  }
  return summary;
}

bool is_result_file(const std::string& name) {
  return name == kConfigFile || name == kMetricsFile || name == kSummaryFile ||
         name == kNetworksFile || name == kReportFile || is_figure_file(name);
}

void write_run_folder(const FolderHandle& staging, const Experiment& experiment,
                      const Settings& settings, const RunContext& context,
                      const std::string& command_line, const RunSummary& summary) {
  write_file_atomic(staging, kConfigFile,
                    config_document(experiment, settings, command_line).dump(2) + "\n");
  write_file_atomic(staging, kMetricsFile, metrics_csv(context));
  write_file_atomic(staging, kSummaryFile, run_summary_json(summary).dump(2) + "\n");
  for (const RunContext::Figure& figure : context.figures()) {
    if (!is_figure_file(figure.file)) {
      throw Error("figure file '" + figure.file + "': expected a name NAME.svg");
    }
    write_file_atomic(staging, figure.file, figure.svg);
  }
  if (!context.networks().empty()) {
    write_file_atomic(staging, kNetworksFile,
                      nlohmann::json{{"networks", context.networks()}}.dump() + "\n");
  }
}

}  // namespace physgrad::run
