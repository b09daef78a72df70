#include "physgrad/run/report_page.hpp"

#include <sstream>

#include "physgrad/report/html_report.hpp"

namespace physgrad::experiments {

namespace {

bool is_learning(const RunContext& context) {
  return !context.runs().empty() && context.runs().front().contains("seconds_per_part");
}

HtmlTable runs_table(const RunContext& context) {
  const bool learning = is_learning(context);
  HtmlTable table{{"run", "settings", learning ? "initial train loss" : "initial loss",
                   learning ? "final train loss" : "final loss", "iterations", "ended by",
                   learning ? "training s" : "wall s"},
                  {},
                  learning ? "Every run: the mean loss over the training set at the start and "
                             "after the last iteration (the Results above are on the test set), "
                             "the iterations made, what ended the run and its training time in "
                             "seconds (evaluations excluded)"
                           : "Every run: the loss L(x) at the start and at the end, the "
                             "iterations made, what ended the run and its wall-clock seconds"};
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

}  // namespace

std::string format_number(const nlohmann::json& value) {
  if (!value.is_number()) return value.is_null() ? "–" : value.dump();
  std::ostringstream out;
  out.precision(4);
  out << value.get<double>();
  return out.str();
}

std::string report_page_html(const Experiment& experiment, const Settings& settings,
                             const RunContext& context, const std::string& command_line) {
  std::vector<HtmlSection> sections;
  // The message figure first, in a section of its own, with its sentence under it.
  HtmlSection message{"", "", {}, {}}, figures{"Figures", "", {}, {}};
  for (const RunContext::Figure& figure : context.figures()) {
    const bool is_message = figure.file == context.message_figure();
    (is_message ? message : figures)
        .figures.push_back({figure.caption, figure.svg, figure.file,
                            is_message ? context.message() : std::string(), figure.row});
  }
  if (!message.figures.empty()) sections.push_back(std::move(message));
  HtmlSection results{"Results",
                      is_learning(context)
                          ? "Losses in these tables are measured on the test set (samples not "
                            "trained on) after the last iteration; the table of every run at the "
                            "end gives the training-set losses.\n\n"
                          : "",
                      {},
                      {}};
  for (const RunContext::Table& table : context.tables()) {
    results.tables.push_back({table.header, table.rows, table.title});
  }
  for (const std::string& note : context.notes()) results.text += note + "\n\n";
  sections.push_back(std::move(results));

  if (!figures.figures.empty()) sections.push_back(std::move(figures));
  sections.push_back({"Every run", "metrics.csv in this folder has every evaluation of every run.",
                      {runs_table(context)}, {}});
  sections.push_back({"Settings", "Command: " + command_line + "\n\n" + settings.json().dump(),
                      {}, {}});
  return html_report(experiment.name() + " — physgrad", experiment.description(), sections);
}

}  // namespace physgrad::experiments
