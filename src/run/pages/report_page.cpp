#include "physgrad/run/pages/report_page.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <charconv>
#include <cmath>

#include "physgrad/error.hpp"
#include "physgrad/io/atomic_file.hpp"
#include "physgrad/report/compare_view.hpp"
#include "physgrad/report/html_report.hpp"
#include "physgrad/run/pages/run_compare_data.hpp"
#include "physgrad/run/life/run_folder.hpp"
#include "physgrad/run/life/run_machine.hpp"

namespace physgrad::run {

namespace {

constexpr const char* kReportCompareText =
    "Every run of this folder (each label and seed), from metrics.csv: pick runs and the metric, "
    "click a legend entry to hide a run, drag a box or turn the wheel to zoom (double-click "
    "resets), read the shown runs' values at the pointer, log y, x per second, EMA smoothing, "
    "CSV download of the shown curves. At most 2000 points per run (every k-th row kept).";

// The links to the folder's files and, when it exists, to the index of the folder above.
std::vector<HtmlLink> report_links(const RunContext& context, bool index_exists) {
  std::vector<HtmlLink> links = {{"metrics.csv (every evaluation)", "metrics.csv"},
                                 {"summary.json (how each run ended)", kSummaryFile},
                                 {"config.json (the settings)", kConfigFile}};
  if (!context.networks().empty()) {
    links.push_back({"networks.json (the trained networks)", "networks.json"});
  }
  if (index_exists) {  // a link to nothing until `physgrad report` writes the index
    links.push_back({"index of the run folders (physgrad report)", "index.html", true});
  }
  return links;
}

// A text as one shell word: unchanged when it needs no quotes, else in single quotes.
std::string shell_word(const std::string& text) {
  const bool plain = !text.empty() && text.find_first_not_of(
                                          "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz"
                                          "0123456789._,/:=+-@%") == std::string::npos;
  if (plain) return text;
  std::string out = "'";
  for (const char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

// Every option with the value the run had and the default, those changed first marked.
HtmlTable report_options_table(const Experiment& experiment, const Settings& settings) {
  HtmlTable table{{"option", "value", "default"},
                  {},
                  "The options of this run (config.json holds them as given to rerun it); the "
                  "default is the value when the option is not given"};
  for (const OptionSpec& spec : all_options(experiment)) {
    const nlohmann::json value = settings.json().value(spec.name, nlohmann::json());
    table.rows.push_back({"--" + spec.name, option_value_text(value),
                          spec.default_text.empty() ? "unset" : spec.default_text});
  }
  return table;
}

bool is_learning(const RunContext& context) {
  return !context.runs().empty() && context.runs().front().seconds_per_part.has_value();
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
  for (const RunEntry& run : context.runs()) {
    // A run that --time ended before a step that would not have fit says so.
    std::string ended = run.termination;
    if (run.message.rfind("time limit: next step would overrun", 0) == 0) {
      ended += " (next step would overrun)";
    }
    std::string params;
    for (const auto& [key, value] : run.params.items()) {
      params += (params.empty() ? "" : ", ") + key + " = " +
                (value.is_string() ? value.get<std::string>() : format_number(value));
    }
    table.rows.push_back({run.label, params, format_number(run.initial.loss),
                          format_number(run.final.loss), std::to_string(run.iterations), ended,
                          format_number(run.wall_seconds)});
  }
  return table;
}

// Whether the folder holding the run folder (staging is RUN/.staging) has an index.html.
bool run_index_beside(const FolderHandle& staging) {
  return ::faccessat(staging.fd(), "../../index.html", F_OK, 0) == 0;
}

}  // namespace

void write_report_file(const FolderHandle& staging, const Experiment& experiment,
                       const Settings& settings, const RunContext& context,
                       const std::string& command_line, const RunSummary& summary) {
  write_file_atomic(staging, kReportFile,
                    report_page_html(experiment, settings, context, command_line,
                                     run_index_beside(staging),
                                     summary.machine.is_null() ? nlohmann::json::object()
                                                               : summary.machine,
                                     metrics_csv(context)));
}

std::string format_number(const nlohmann::json& value) {
  if (!value.is_number()) return value.is_null() ? "–" : value.dump();
  if (value.is_number_integer()) return value.dump();  // a seed 12345, never 1.234e+04
  return format_value(value.get<double>());
}

std::string option_value_text(const nlohmann::json& value) {
  if (value.is_null()) return "unset";
  if (value.is_string()) return value.get<std::string>();
  if (value.is_boolean()) return value.get<bool>() ? "true" : "false";
  if (value.is_number_integer()) return value.dump();
  if (value.is_number()) {
    const double v = value.get<double>();
    // Whole numbers as integers (10000, never 1e+04), others as the shortest text that reads
    // back to the same double.
    if (std::isfinite(v) && v == std::floor(v) && std::abs(v) < 1e15) {
      return std::to_string(static_cast<long long>(v));
    }
    char text[32];
    const auto end = std::to_chars(text, text + sizeof text, v).ptr;
    return std::string(text, end);
  }
  std::string out;
  for (const nlohmann::json& item : value) {
    if (!out.empty()) out += ',';
    out += option_value_text(item);
  }
  return out;
}

std::string reproduce_command(const Experiment& experiment, const Settings& settings) {
  std::string out = "physgrad run " + experiment.name();
  for (const OptionSpec& spec : all_options(experiment)) {
    if (spec.name == "out") continue;  // a fresh folder under runs/ each time
    const nlohmann::json value = settings.json().value(spec.name, nlohmann::json());
    if (value.is_null()) continue;
    out += " --" + spec.name + " " + shell_word(option_value_text(value));
  }
  return out;
}

std::string report_page_html(const Experiment& experiment, const Settings& settings,
                             const RunContext& context, const std::string& command_line,
                             bool index_exists, const nlohmann::json& machine_json,
                             std::string_view metrics) {
  // The interactive comparison over the folder's runs, after the static sections; what it leaves
  // out is said under "Every run". A metrics.csv beyond its limits (e.g. a header of 2·10⁵
  // columns) leaves the page without it, with the reason: the results are written either way.
  std::vector<std::string> left_out;
  std::string runs;
  try {
    if (!metrics.empty()) runs = compare_runs_json(experiment.name(), metrics, left_out);
  } catch (const Error& e) {
    runs.clear();
    left_out.push_back(std::string("The interactive comparison is left out: ") + e.what() + ".");
  }
  std::vector<HtmlSection> sections;
  // The message figure first, its sentence above it, so that the sentence is on the first
  // screen; then what the page is of, when, by what and on what machine, and the links.
  HtmlSection message{"", "", {}, {}}, figures{"Figures", "", {}, {}};
  for (const RunContext::Figure& figure : context.figures()) {
    const bool is_message = figure.file == context.message_figure();
    (is_message ? message : figures)
        .figures.push_back({figure.caption, figure.svg, figure.file,
                            is_message ? context.message() : std::string(), figure.row});
  }
  const std::string machine = run_machine_text(machine_json);
  const bool leads = !message.figures.empty();
  if (leads) sections.push_back(std::move(message));
  sections.push_back({"", (leads ? experiment.description() + "\n\n" : std::string()) +
                              "Written " + utc_minute_now() + " by physgrad " +
                              PHYSGRAD_VERSION + " (" + machine +
                              "); the command and every option are under Settings at the end.",
                      {}, {}, report_links(context, index_exists)});
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
  std::string left_out_text;
  for (const std::string& note : left_out) left_out_text += note + "\n\n";
  sections.push_back({"Every run", left_out_text, {runs_table(context)}, {},
                      {{"metrics.csv: every evaluation of every run", "metrics.csv"}}});
  sections.push_back({"Settings",
                      "physgrad " + std::string(PHYSGRAD_VERSION) + ", report written " +
                          utc_minute_now() + ".\n\nMachine: " + machine +
                          ".\n\nTo run it again (into a new folder under runs/): " +
                          reproduce_command(experiment, settings) + "\n\nCommand as typed: " +
                          (command_line.empty() ? "(not recorded)" : command_line),
                      {report_options_table(experiment, settings)},
                      {},
                      {{"config.json", kConfigFile}}});
  const std::string compare =
      runs.empty() ? std::string()
                   : compare_section_open("Interactive comparison", kReportCompareText) +
                         "{\"runs\":[" + runs + "]}" + compare_section_close();
  return html_report(experiment.name() + " — physgrad", leads ? "" : experiment.description(),
                     sections, compare, runs.empty() ? std::string() : compare_csp());
}

}  // namespace physgrad::run
