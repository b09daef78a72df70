// What a committed run folder holds: metrics.csv, summary.json, figures and report.html, written
// into the staging folder before commit (write_run_folder, run_folder.hpp).
#include "physgrad/run/life/run_folder.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <set>

#include "physgrad/error.hpp"
#include "physgrad/io/atomic_file.hpp"
#include "physgrad/io/csv.hpp"
#include "physgrad/run/pages/report_page.hpp"
#include "physgrad/run/life/run_machine.hpp"

namespace physgrad::run {

namespace {

constexpr const char* kMetricsFile = "metrics.csv";
constexpr const char* kNetworksFile = "networks.json";
constexpr const char* kReportFile = "report.html";

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

// Whether the folder holding the run folder (staging is RUN/.staging) has an index.html.
bool run_index_beside(const FolderHandle& staging) {
  return ::faccessat(staging.fd(), "../../index.html", F_OK, 0) == 0;
}

}  // namespace

nlohmann::json config_document(const Experiment& experiment, const Settings& settings,
                               const std::string& command_line) {
  return {{"experiment", experiment.name()},
          {"command", command_line},
          {"settings", settings.json()}};
}

nlohmann::json summary_document(const Experiment& experiment, const RunContext& context) {
  nlohmann::json summary = {
      {"experiment", experiment.name()}, {"runs", context.runs()}, {"machine", run_machine()}};
  if (!context.message_figure().empty()) {
    const MessageMetric& metric = context.message_metric();
    summary["message"] = {{"figure", context.message_figure()},
                          {"sentence", context.message()},
                          {"metric", metric.key},
                          {"metric_text", metric.text},
                          {"labels", metric.labels}};
  }
  return summary;
}

bool is_result_file(const std::string& name) {
  return name == kConfigFile || name == kMetricsFile || name == kSummaryFile ||
         name == kNetworksFile || name == kReportFile || is_figure_file(name);
}

void write_run_folder(const FolderHandle& staging, const Experiment& experiment,
                      const Settings& settings, const RunContext& context,
                      const std::string& command_line, const nlohmann::json& summary) {
  write_file_atomic(staging, kConfigFile,
                    config_document(experiment, settings, command_line).dump(2) + "\n");
  const std::string metrics = metrics_csv(context);
  write_file_atomic(staging, kMetricsFile, metrics);
  write_file_atomic(staging, kSummaryFile, summary.dump(2) + "\n");
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
  write_file_atomic(staging, kReportFile,
                    report_page_html(experiment, settings, context, command_line,
                                     run_index_beside(staging),
                                     summary.value("machine", nlohmann::json::object()),
                                     metrics));
}

}  // namespace physgrad::run
