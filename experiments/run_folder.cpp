#include "run_folder.hpp"

#include <set>

#include "physgrad/error.hpp"
#include "physgrad/report/atomic_file.hpp"
#include "physgrad/report/csv.hpp"
#include "physgrad/report/html_report.hpp"

namespace physgrad::experiments {

namespace fs = std::filesystem;

namespace {

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

std::string format_number(const nlohmann::json& value) {
  if (!value.is_number()) return value.is_null() ? "–" : value.dump();
  std::ostringstream out;
  out.precision(4);
  out << value.get<double>();
  return out.str();
}

HtmlTable runs_table(const RunContext& context) {
  HtmlTable table{{"run", "settings", "initial loss", "final loss", "iterations", "end",
                   "wall s"},
                  {}};
  for (const nlohmann::json& run : context.runs()) {
    std::string params;
    for (const auto& [key, value] : run.at("params").items()) {
      params += (params.empty() ? "" : ", ") + key + " = " +
                (value.is_string() ? value.get<std::string>() : format_number(value));
    }
    table.rows.push_back({run.at("label").get<std::string>(), params,
                          format_number(run.at("initial").at("loss")),
                          format_number(run.at("final").at("loss")),
                          std::to_string(run.at("iterations").get<long long>()),
                          run.value("termination", std::string()),
                          format_number(run.at("wall_seconds"))});
  }
  return table;
}

std::string report_html(const Experiment& experiment, const Settings& settings,
                        const RunContext& context, const std::string& command_line) {
  std::vector<HtmlSection> sections;
  HtmlSection results{"Results", "", {}, {}};
  for (const RunContext::Table& table : context.tables()) {
    results.tables.push_back({table.header, table.rows});
  }
  for (const std::string& note : context.notes()) results.text += note + "\n\n";
  sections.push_back(std::move(results));

  HtmlSection figures{"Figures", "", {}, {}};
  for (const RunContext::Figure& figure : context.figures()) {
    figures.figures.push_back({figure.caption, figure.svg});
  }
  sections.push_back(std::move(figures));
  sections.push_back({"Every run", "Final figures per run; metrics.csv has every iterate.",
                      {runs_table(context)}, {}});
  sections.push_back({"Settings", "Command: " + command_line + "\n\n" + settings.json().dump(),
                      {}, {}});
  return html_report(experiment.name() + " — physgrad", experiment.description(), sections);
}

}  // namespace

nlohmann::json config_document(const Experiment& experiment, const Settings& settings,
                               const std::string& command_line) {
  return {{"experiment", experiment.name()},
          {"command", command_line},
          {"settings", settings.json()}};
}

nlohmann::json summary_document(const Experiment& experiment, const RunContext& context) {
  return {{"experiment", experiment.name()}, {"runs", context.runs()}};
}

void write_run_folder(const fs::path& staging, const Experiment& experiment,
                      const Settings& settings, const RunContext& context,
                      const std::string& command_line) {
  write_file_atomic(staging / kConfigFile,
                    config_document(experiment, settings, command_line).dump(2) + "\n");
  write_file_atomic(staging / "metrics.csv", metrics_csv(context));
  write_file_atomic(staging / kSummaryFile, summary_document(experiment, context).dump(2) + "\n");
  for (const RunContext::Figure& figure : context.figures()) {
    write_file_atomic(staging / figure.file, figure.svg);
  }
  if (!context.networks().empty()) {
    write_file_atomic(staging / "networks.json",
                      nlohmann::json{{"networks", context.networks()}}.dump() + "\n");
  }
  write_file_atomic(staging / "report.html",
                    report_html(experiment, settings, context, command_line));
}

}  // namespace physgrad::experiments
