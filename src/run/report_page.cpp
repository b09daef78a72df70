#include "physgrad/run/report_page.hpp"

#include <chrono>
#include <ctime>
#include <sstream>

#include "physgrad/report/html_report.hpp"
#include "physgrad/run/run_folder.hpp"

namespace physgrad::run {

namespace {

// "2026-11-27 08:40 UTC": now.
std::string report_time_now() {
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm utc{};
  ::gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%d %H:%M UTC", &utc);
  return text;
}

// The links to the folder's files and to the index of the folder above (`physgrad report`).
std::vector<HtmlLink> report_links(const RunContext& context) {
  std::vector<HtmlLink> links = {{"metrics.csv (every evaluation)", "metrics.csv"},
                                 {"summary.json (how each run ended)", kSummaryFile},
                                 {"config.json (the settings)", kConfigFile}};
  if (!context.networks().empty()) {
    links.push_back({"networks.json (the trained networks)", "networks.json"});
  }
  links.push_back({"index of the run folders (physgrad report)", "index.html", true});
  return links;
}

// A setting's value as the table of options shows it: lists joined by commas, "unset" for none.
std::string report_option_text(const nlohmann::json& value) {
  if (value.is_null()) return "unset";
  if (value.is_string()) return value.get<std::string>();
  if (!value.is_array()) return format_number(value);
  std::string out;
  for (const nlohmann::json& item : value) {
    if (!out.empty()) out += ',';
    out += report_option_text(item);
  }
  return out;
}

// Every option with the value the run had and the default, those changed first marked.
HtmlTable report_options_table(const Experiment& experiment, const Settings& settings) {
  HtmlTable table{{"option", "value", "default"},
                  {},
                  "The options of this run (config.json holds them as given to rerun it); the "
                  "default is the value when the option is not given"};
  for (const OptionSpec& spec : all_options(experiment)) {
    const nlohmann::json value = settings.json().value(spec.name, nlohmann::json());
    table.rows.push_back({"--" + spec.name, report_option_text(value),
                          spec.default_text.empty() ? "unset" : spec.default_text});
  }
  return table;
}

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
  // What the page is of, when and by what, and the links to the folder's files.
  sections.push_back({"", "Written " + report_time_now() + " by physgrad " + PHYSGRAD_VERSION +
                              "; the command and every option are under Settings at the end.",
                      {}, {}, report_links(context)});
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
  sections.push_back({"Every run", "", {runs_table(context)}, {},
                      {{"metrics.csv: every evaluation of every run", "metrics.csv"}}});
  sections.push_back({"Settings",
                      "physgrad " + std::string(PHYSGRAD_VERSION) + ", report written " +
                          report_time_now() + ".\n\nCommand: " +
                          (command_line.empty() ? "(not recorded)" : command_line),
                      {report_options_table(experiment, settings)},
                      {},
                      {{"config.json", kConfigFile}}});
  return html_report(experiment.name() + " — physgrad", experiment.description(), sections);
}

}  // namespace physgrad::run
