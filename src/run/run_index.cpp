#include "physgrad/run/run_index.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "physgrad/catalogue.hpp"
#include "physgrad/error.hpp"
#include "physgrad/io/atomic_file.hpp"
#include "physgrad/io/csv.hpp"
#include "physgrad/io/json_file.hpp"
#include "physgrad/report/colors.hpp"
#include "physgrad/report/html_report.hpp"
#include "physgrad/report/line_plot.hpp"
#include "physgrad/report/seed_band.hpp"
#include "physgrad/run/learning_runs.hpp"
#include "physgrad/run/registry.hpp"
#include "physgrad/run/report_page.hpp"
#include "physgrad/run/run_folder.hpp"
#include "physgrad/text.hpp"

namespace physgrad::experiments {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// What is read of each run folder at most; the index says what it leaves out.
constexpr std::size_t kMaxJsonBytes = std::size_t{8} << 20;      // summary.json, config.json
constexpr std::size_t kMaxRuns = 10000;                          // runs of one summary.json
constexpr std::size_t kMaxMetricsBytes = std::size_t{32} << 20;  // metrics.csv
constexpr std::size_t kMaxMetricsRows = 200000;
constexpr std::size_t kMaxCurves = 256;  // (label, seed) curves of one metrics.csv

// A run of a summary.json: the fields the index shows.
struct IndexedRun {
  std::string label;
  std::string rule;                             // the rule's id ("optimizer"), or empty
  json params;                                  // an object
  double loss, test_loss, iterations, seconds;  // NaN when absent or null
  std::string termination;
  double metric = NAN;  // the folder's message metric (NaN when absent or not a number)
};

// One label's curves of the message metric vs training time, a curve per seed.
struct LabelCurves {
  std::string label;
  std::string rule;  // of the label's first row
  std::vector<Curve> seeds;
};

// What a folder's experiment said its message is (summary.json "message"); a folder without one
// is compared over every run by its final test loss, or its final loss when no run has a test
// loss.
struct IndexedMessage {
  std::string figure, sentence;
  std::string metric, metric_text;
  std::vector<std::string> labels;  // the runs compared; empty: every run

  bool compares(const std::string& label) const {
    return labels.empty() || std::find(labels.begin(), labels.end(), label) != labels.end();
  }
};

struct IndexedFolder {
  std::string name;  // as listed: any bytes but '/' and NUL
  std::string experiment;
  std::vector<IndexedRun> runs;
  IndexedMessage message;
  std::string command;
  json settings = json::object();  // config.json's "settings"
  std::vector<LabelCurves> curves;  // from metrics.csv, the compared labels in the file's order
  bool has_report = false;
};

json read_json(const fs::path& path) {
  return parse_json_text(read_regular_file(path, kMaxJsonBytes), 64);
}

// "a number", "an array", … for messages.
std::string a_type(const json& value) {
  return (value.is_array() || value.is_object() ? "an " : "a ") + std::string(value.type_name());
}

// A field of a JSON object (null when absent or null) of one type; Error "WHERE.KEY is a number,
// not text" when it has another.
const json* field(const json& object, const char* key, const std::string& where,
                  bool (json::*is_type)() const noexcept, const char* type) {
  const auto it = object.find(key);
  if (it == object.end() || it->is_null()) return nullptr;
  if (!((*it).*is_type)()) throw Error(where + key + " is " + a_type(*it) + ", not " + type);
  return &*it;
}

std::string text_field(const json& object, const char* key, const std::string& where,
                       const std::string& absent) {
  const json* value = field(object, key, where, &json::is_string, "text");
  return value ? value->get<std::string>() : absent;
}

double number_field(const json& object, const char* key, const std::string& where) {
  const json* value = field(object, key, where, &json::is_number, "a number");
  return value ? value->get<double>() : NAN;
}

const json& object_field(const json& object, const char* key, const std::string& where) {
  static const json empty = json::object();
  const json* value = field(object, key, where, &json::is_object, "an object");
  return value ? *value : empty;
}

// A number of a run for `key`: its "final" entry's, else its own (e.g. "iterations"); NaN when
// neither is a number.
double summary_number(const json& run, const std::string& key) {
  const auto final = run.find("final");
  if (final != run.end() && final->is_object()) {
    const auto value = final->find(key);
    if (value != final->end() && value->is_number()) return value->get<double>();
  }
  const auto value = run.find(key);
  return value != run.end() && value->is_number() ? value->get<double>() : NAN;
}

// The "message" of a summary.json; Error naming the field that is not of its type.
IndexedMessage read_message(const json& summary) {
  IndexedMessage message;
  const json* given = field(summary, "message", "", &json::is_object, "an object");
  if (!given) return message;
  message.figure = text_field(*given, "figure", "message.", "");
  message.sentence = text_field(*given, "sentence", "message.", "");
  const std::string metric = text_field(*given, "metric", "message.", "");
  if (!metric.empty()) {
    message.metric = metric;
    message.metric_text = text_field(*given, "metric_text", "message.", metric);
  }
  if (const json* labels = field(*given, "labels", "message.", &json::is_array, "an array")) {
    for (const json& label : *labels) {
      if (!label.is_string()) throw Error("message.labels holds " + a_type(label) + ", not text");
      message.labels.push_back(label.get<std::string>());
    }
  }
  return message;
}

// The experiment, message and runs of a summary.json; Error naming the field that is not of its
// type.
void read_summary(const json& summary, IndexedFolder& folder, std::vector<std::string>& notes,
                  const fs::path& file) {
  if (!summary.is_object() || !summary.contains("runs") || !summary.at("runs").is_array()) {
    throw Error("has no list of runs");
  }
  folder.experiment = text_field(summary, "experiment", "", "?");
  folder.message = read_message(summary);
  const json& runs = summary.at("runs");
  if (folder.message.metric.empty()) {
    const bool tested = std::any_of(runs.begin(), runs.end(), [](const json& run) {
      return run.is_object() && !std::isnan(summary_number(run, "test_loss"));
    });
    folder.message.metric = tested ? "test_loss" : "loss";
    folder.message.metric_text = tested ? "final test loss" : "final loss";
  }
  if (runs.size() > kMaxRuns) {
    notes.push_back(in_quotes(file.string()) + ": " + std::to_string(runs.size()) +
                    " runs, only the first " + std::to_string(kMaxRuns) + " are listed");
  }
  for (std::size_t k = 0; k < std::min(runs.size(), kMaxRuns); ++k) {
    const std::string where = "runs[" + std::to_string(k) + "]";
    const json& run = runs[k];
    if (!run.is_object()) {
      throw Error(where + " is " + a_type(run) + ", not an object");
    }
    const json& final = object_field(run, "final", where + ".");
    folder.runs.push_back({text_field(run, "label", where + ".", "?"),
                           text_field(run, "optimizer", where + ".", ""),
                           object_field(run, "params", where + "."),
                           number_field(final, "loss", where + ".final."),
                           number_field(final, "test_loss", where + ".final."),
                           number_field(run, "iterations", where + "."),
                           number_field(run, "wall_seconds", where + "."),
                           text_field(run, "termination", where + ".", "–"),
                           summary_number(run, folder.message.metric)});
  }
}

// The curves of the message metric of a metrics.csv, per compared label and seed (of its first
// kMaxMetricsRows rows, at most kMaxCurves curves); none when it lacks the label, wall_seconds or
// metric column.
std::vector<LabelCurves> read_curves(const fs::path& file, const IndexedMessage& message,
                                     std::vector<std::string>& notes) {
  const CsvData metrics = parse_csv(
      read_regular_file(file, kMaxMetricsBytes),
      {{"label", "optimizer", "seed", "wall_seconds", message.metric}, kMaxMetricsRows});
  if (metrics.rows_left_out > 0) {
    notes.push_back(in_quotes(file.string()) + ": " +
                    std::to_string(metrics.rows.size() + metrics.rows_left_out) +
                    " rows, only the first " + std::to_string(metrics.rows.size()) + " are drawn");
  }
  const std::size_t n = metrics.columns.size(), label = metrics.column("label"),
                    rule = metrics.column("optimizer"), seed = metrics.column("seed"),
                    seconds = metrics.column("wall_seconds"),
                    value = metrics.column(message.metric);
  std::vector<LabelCurves> curves;
  if (label == n || seconds == n || value == n) return curves;
  std::map<std::string, std::size_t> labels;  // label → its place in curves
  // (label, seed) → the places of its curve: its label's in curves, its own in that label's seeds
  std::map<std::pair<std::string, std::string>, std::pair<std::size_t, std::size_t>> places;
  std::size_t rows_left_out = 0;
  for (const std::vector<std::string>& row : metrics.rows) {
    if (!message.compares(row[label])) continue;
    const auto key = std::make_pair(row[label], seed == n ? std::string() : row[seed]);
    auto place = places.find(key);
    if (place == places.end()) {
      if (places.size() == kMaxCurves) {
        ++rows_left_out;
        continue;
      }
      const auto at = labels.try_emplace(row[label], curves.size()).first;
      if (at->second == curves.size()) {
        curves.push_back({row[label], rule == n ? std::string() : row[rule], {}});
      }
      std::vector<Curve>& seeds = curves[at->second].seeds;
      place = places.emplace(key, std::make_pair(at->second, seeds.size())).first;
      seeds.emplace_back();
    }
    Curve& curve = curves[place->second.first].seeds[place->second.second];
    curve.x.push_back(std::strtod(row[seconds].c_str(), nullptr));
    curve.y.push_back(std::strtod(row[value].c_str(), nullptr));
  }
  if (rows_left_out > 0) {
    notes.push_back(in_quotes(file.string()) + ": more than " + std::to_string(kMaxCurves) +
                    " curves (label and seed), the " + std::to_string(rows_left_out) +
                    " rows of the others are not drawn");
  }
  return curves;
}

// A run folder as the index shows it, adding what it cuts short to `notes`. Throws Error naming
// the file (and field) when its summary.json or config.json cannot be shown; a metrics.csv that
// cannot be read leaves out the folder's curves only.
IndexedFolder read_folder(const fs::path& path, std::vector<std::string>& notes) {
  IndexedFolder folder;
  folder.name = path.filename().string();
  std::vector<std::string> cut;  // noted only when the folder is shown
  const auto reading = [](const fs::path& file, const auto& read) {
    try {
      read();
    } catch (const Error& e) {
      throw Error(in_quotes(file.string()) + ": " + e.what());
    }
  };
  const fs::path summary = path / kSummaryFile, config = path / kConfigFile,
                 metrics = path / "metrics.csv";
  reading(summary, [&] { read_summary(read_json(summary), folder, cut, summary); });
  std::error_code error;  // a link inside the folder that leads nowhere counts as absent
  if (fs::exists(config, error)) {
    reading(config, [&] {
      const json settings = read_json(config);
      if (!settings.is_object()) throw Error("holds " + a_type(settings) + ", not an object");
      folder.command = text_field(settings, "command", "", "");
      folder.settings = object_field(settings, "settings", "");
    });
  }
  if (fs::exists(metrics, error)) {
    try {
      folder.curves = read_curves(metrics, folder.message, cut);
    } catch (const Error& e) {
      cut.push_back(in_quotes(metrics.string()) + ": " + e.what() +
                    "; its loss curves are not drawn");
    }
  }
  folder.has_report = fs::exists(path / "report.html", error);
  notes.insert(notes.end(), cut.begin(), cut.end());
  return folder;
}

// The run folders directly in `dir` (folders with a summary.json), by name; those that cannot be
// shown are noted instead.
std::vector<IndexedFolder> find_run_folders(const fs::path& dir, std::vector<std::string>& notes) {
  std::vector<fs::path> paths;
  // Entries that cannot be followed (a looping or dangling link) are not run folders.
  for (const fs::directory_entry& entry : fs::directory_iterator(dir)) {
    std::error_code error;
    if (entry.is_directory(error) && fs::exists(entry.path() / kSummaryFile, error)) {
      paths.push_back(entry.path());
    }
  }
  std::sort(paths.begin(), paths.end());
  std::vector<IndexedFolder> folders;
  for (const fs::path& path : paths) {
    try {
      folders.push_back(read_folder(path, notes));
    } catch (const Error& e) {
      notes.push_back(std::string(e.what()) + "; the folder is left out");
    }
  }
  return folders;
}

std::string text_of(const json& value) {
  return value.is_string() ? value.get<std::string>() : format_number(value);
}

// The keys of the runs' params (seed aside) whose values are not the same in every run — a key
// some runs lack counts — in the order they first appear.
std::vector<std::string> varying_keys(const std::vector<const IndexedRun*>& runs) {
  struct Seen {
    const json* first;
    std::size_t count;
    bool differs;
  };
  std::map<std::string, Seen> seen;
  std::vector<std::string> keys;
  for (const IndexedRun* run : runs) {
    for (auto it = run->params.begin(); it != run->params.end(); ++it) {
      if (it.key() == "seed") continue;
      const auto [at, added] = seen.try_emplace(it.key(), Seen{&it.value(), 0, false});
      if (added) keys.push_back(it.key());
      ++at->second.count;
      at->second.differs = at->second.differs || *at->second.first != it.value();
    }
  }
  std::erase_if(keys, [&](const std::string& key) {
    const Seen& s = seen.at(key);
    return !s.differs && s.count == runs.size();
  });
  return keys;
}

// A group of runs as a table row shows it: its medians (NaN when none) and how the runs ended.
struct RunGroup {
  double metric, loss, test_loss, iterations, seconds;
  std::string ended;    // the distinct terminations, in the order first seen
  bool failed = false;  // a run stopped on a non-finite value or diverged
};

RunGroup summarize(const std::vector<const IndexedRun*>& runs) {
  std::vector<double> metric, loss, test, iterations, seconds;
  std::vector<std::string> ends;
  bool failed = false;
  for (const IndexedRun* run : runs) {
    metric.push_back(run->metric);
    loss.push_back(run->loss);
    test.push_back(run->test_loss);
    iterations.push_back(run->iterations);
    seconds.push_back(run->seconds);
    if (std::find(ends.begin(), ends.end(), run->termination) == ends.end()) {
      ends.push_back(run->termination);
    }
    failed = failed || run->termination == "numerical_failure" || run->termination == "diverged";
  }
  return {median(metric), median(loss), median(test), median(iterations), median(seconds),
          comma_list(ends), failed};
}

// A table cell: "–" for NaN.
std::string cell(double value) { return std::isnan(value) ? std::string("–") : text_of(value); }

// One row per run folder and run label with its setting (the parameters that vary among that
// label's runs, seeds aside); the figures are medians over the seeds. Linear in the runs (up to
// the logarithms of the maps).
HtmlTable every_run_table(const std::vector<IndexedFolder>& folders) {
  HtmlTable table{{"run folder", "experiment", "run", "setting", "runs", "final loss",
                   "final test loss", "iterations", "ended by", "seconds"},
                  {},
                  "Every run of every run folder (runs: how many, e.g. seeds), with the median "
                  "over them: the final loss "
                  "(learning runs: the mean over the training set; direct optimization: L(x)), "
                  "the final mean loss over the test set where there is one, the iterations "
                  "made, what ended the runs and the training time in seconds (evaluations "
                  "excluded; direct optimization: wall-clock seconds). A folder's name links to "
                  "its report.",
                  {}};
  for (const IndexedFolder& folder : folders) {
    std::map<std::string, std::vector<const IndexedRun*>> by_label;
    for (const IndexedRun& run : folder.runs) by_label[run.label].push_back(&run);
    std::map<std::string, std::vector<std::string>> varying;
    for (const auto& [label, runs] : by_label) varying[label] = varying_keys(runs);

    std::vector<std::pair<std::string, std::string>> groups;  // (label, setting), first seen
    std::map<std::pair<std::string, std::string>, std::vector<const IndexedRun*>> members;
    for (const IndexedRun& run : folder.runs) {
      std::string setting;
      for (const std::string& key : varying[run.label]) {
        setting +=
            (setting.empty() ? "" : ", ") + key + " = " + text_of(run.params.value(key, json()));
      }
      auto key = std::make_pair(run.label, setting);
      std::vector<const IndexedRun*>& group = members[key];
      if (group.empty()) groups.push_back(std::move(key));
      group.push_back(&run);
    }
    for (const auto& key : groups) {
      const std::vector<const IndexedRun*>& runs = members[key];
      const RunGroup g = summarize(runs);
      const auto whole = [](double v) {
        return v == std::round(v) && std::abs(v) < 1e15 ? std::to_string(std::llround(v)) : cell(v);
      };
      table.rows.push_back({folder.name, folder.experiment, key.first, key.second,
                            std::to_string(runs.size()), cell(g.loss), cell(g.test_loss),
                            whole(g.iterations), g.ended, cell(g.seconds)});
      table.links.push_back(std::vector<std::string>(table.header.size()));
      if (folder.has_report) table.links.back()[0] = folder.name + "/report.html";
    }
  }
  return table;
}

// The colour rule `id` has in every figure (the catalogue's; a pretrained run's, color_for's),
// or a palette colour for an id that names no rule.
std::string rule_colour(const std::string& id, std::size_t fallback) {
  for (const RuleInfo& rule : rule_catalogue()) {
    if (rule.id == id) return rule.colour;
  }
  if (!pretrained_rule(id).empty()) return color_for(id);
  return palette_color(fallback);
}

// The settings of experiment `name` when no option is given, or null for a name this program
// does not know.
json default_settings(const std::string& name) {
  for (const auto& experiment : registry()) {
    if (experiment->name() == name) return resolve_settings(*experiment, {}).json();
  }
  return nullptr;
}

// "lr = 0.01, iters = 300": the settings that differ from `baseline`, but those that do not change
// what a run computes (where it is written, threads, checkpoints) and the rules (a column of
// their own).
std::string differing_options(const json& settings, const json& baseline) {
  static const std::vector<std::string> kNotCompared = {
      "out", "threads", "checkpoint-every", "checkpoint-seconds", "distributed-gram-rows",
      "optimizers"};
  const auto text = [](const json& value) {
    if (value.is_null()) return std::string("unset");
    if (!value.is_array()) return text_of(value);
    std::string out;
    for (const json& item : value) out += (out.empty() ? "" : ",") + text_of(item);
    return out;
  };
  std::string out;
  for (auto it = settings.begin(); it != settings.end(); ++it) {
    if (std::find(kNotCompared.begin(), kNotCompared.end(), it.key()) != kNotCompared.end()) {
      continue;
    }
    const json base = baseline.is_object() ? baseline.value(it.key(), json()) : json();
    if (it.value() == base) continue;
    out += (out.empty() ? "" : ", ") + it.key() + " = " + text(it.value());
  }
  return out;
}

// A median with the range of the values it is taken over: "12", "30 (5–1000)", "–" for none.
std::string median_with_range(const std::vector<double>& values) {
  std::vector<double> finite;
  for (double v : values) {
    if (std::isfinite(v)) finite.push_back(v);
  }
  if (finite.empty()) return "–";
  const auto [lo, hi] = std::minmax_element(finite.begin(), finite.end());
  const std::string m = text_of(median(finite));
  return *lo == *hi ? m : m + " (" + text_of(*lo) + "–" + text_of(*hi) + ")";
}

// One experiment's folders compared by one message metric: a row per folder and compared run
// label (the median over its runs, e.g. seeds or settings, with their range, and its multiple of
// the folder's lowest), and the metric of every compared run vs training time overlaid.
void add_comparison(HtmlSection& section, const std::vector<const IndexedFolder*>& folders,
                    const json& baseline) {
  const IndexedMessage& message = folders.front()->message;
  HtmlTable table{{"run folder", "options", "rule", "runs", message.metric_text, "× lowest",
                   "ended by", "seconds"},
                  {},
                  "By " + message.metric_text + " (lower is better): per run folder and rule, "
                  "the median over its runs with their range in brackets, and the multiple of "
                  "the folder's lowest among rules none of whose runs failed. Options: the "
                  "settings that differ from the experiment's defaults. Seconds: the median "
                  "training time.",
                  {},
                  {}};
  std::vector<Series> series;
  std::size_t drawn = 0;  // folders with curves, for alternating dashes
  for (const IndexedFolder* folder : folders) {
    const std::string options = differing_options(folder->settings, baseline);
    std::vector<std::string> labels;
    std::map<std::string, std::vector<const IndexedRun*>> by_label;
    for (const IndexedRun& run : folder->runs) {
      if (!message.compares(run.label)) continue;
      std::vector<const IndexedRun*>& runs = by_label[run.label];
      if (runs.empty()) labels.push_back(run.label);
      runs.push_back(&run);
    }
    // The lowest median among rules none of whose runs failed (a run that stopped on a
    // non-finite value or diverged is not the best, whatever its metric reads).
    std::vector<RunGroup> groups;
    double lowest = INFINITY;
    for (const std::string& label : labels) {
      groups.push_back(summarize(by_label[label]));
      const RunGroup& g = groups.back();
      if (!g.failed && std::isfinite(g.metric)) lowest = std::min(lowest, g.metric);
    }
    for (std::size_t k = 0; k < labels.size(); ++k) {
      const std::vector<const IndexedRun*>& runs = by_label[labels[k]];
      std::vector<double> values;
      for (const IndexedRun* run : runs) values.push_back(run->metric);
      const double m = groups[k].metric;
      const std::string multiple = !std::isfinite(m) ? "–"
                                   : m == lowest     ? "best"
                                   : lowest > 0      ? text_of(m / lowest) + "×"
                                                     : "–";
      table.rows.push_back({folder->name, options, labels[k], std::to_string(runs.size()),
                            median_with_range(values), multiple, groups[k].ended,
                            cell(groups[k].seconds)});
      table.links.push_back(std::vector<std::string>(table.header.size()));
      if (folder->has_report) table.links.back()[0] = folder->name + "/report.html";
      table.colours.push_back(std::vector<std::string>(table.header.size()));
      table.colours.back()[2] = rule_colour(runs.front()->rule, k);
    }
    if (folder->curves.empty()) continue;
    ++drawn;
    for (const LabelCurves& label : folder->curves) {
      Series curve = median_band(
          folder->name + ": " + label.label +
              (label.seeds.size() > 1 ? ", median of " + std::to_string(label.seeds.size()) : ""),
          label.seeds, rule_colour(label.rule, series.size()), true);
      curve.markers = true;
      curve.dashed = drawn % 2 == 0;
      mark_if_diverging(curve);
      series.push_back(std::move(curve));
    }
  }
  section.tables.push_back(std::move(table));
  if (series.empty()) return;
  LinePlotOptions options;
  options.title = section.heading + ": " + message.metric_text + " vs training time";
  options.x_label = "training time (s, evaluations excluded)";
  options.y_label = message.metric_text;
  options.log_y = true;
  section.figures.push_back(
      {section.heading + ": the " + message.metric_text + " of every compared run in " +
           std::to_string(drawn) + " run folder" + (drawn == 1 ? "" : "s") +
           " (colour: the rule's, as in the reports; line: median over seeds, band: their "
           "minimum to maximum; runs of every second folder dashed).",
       line_plot_svg(series, options)});
}

// Per experiment, in the order the folders list them: the message of each of its folders, and
// the folders compared by the metric their messages compare (one table per metric when folders
// of different versions compare different ones).
std::vector<HtmlSection> comparisons(const std::vector<IndexedFolder>& folders) {
  std::vector<std::string> experiments;
  for (const IndexedFolder& f : folders) {
    if (std::find(experiments.begin(), experiments.end(), f.experiment) == experiments.end()) {
      experiments.push_back(f.experiment);
    }
  }
  std::vector<HtmlSection> sections;
  for (const std::string& experiment : experiments) {
    HtmlSection section{experiment, "", {}, {}};
    std::vector<std::pair<std::string, std::string>> metrics;  // (key, text), first seen
    const IndexedFolder* first = nullptr;
    for (const IndexedFolder& f : folders) {
      if (f.experiment != experiment) continue;
      if (!first) first = &f;
      if (!f.message.sentence.empty()) section.text += f.name + ": " + f.message.sentence + "\n\n";
      const auto metric = std::make_pair(f.message.metric, f.message.metric_text);
      if (std::find(metrics.begin(), metrics.end(), metric) == metrics.end()) {
        metrics.push_back(metric);
      }
    }
    json baseline = default_settings(experiment);
    if (baseline.is_null()) baseline = first->settings;
    for (const auto& metric : metrics) {
      std::vector<const IndexedFolder*> members;
      for (const IndexedFolder& f : folders) {
        if (f.experiment == experiment &&
            std::make_pair(f.message.metric, f.message.metric_text) == metric) {
          members.push_back(&f);
        }
      }
      add_comparison(section, members, baseline);
    }
    sections.push_back(std::move(section));
  }
  return sections;
}

}  // namespace

std::size_t write_run_index(const fs::path& dir, std::ostream& warnings) {
  std::error_code error;
  if (!fs::is_directory(dir, error)) {
    throw Error("report: '" + dir.string() + "' is not a directory");
  }
  std::vector<std::string> notes;
  const std::vector<IndexedFolder> folders = find_run_folders(dir, notes);
  if (folders.empty()) {
    throw Error("report: '" + dir.string() + "' holds no run folder (a folder with summary.json)" +
                (notes.empty() ? "" : " that can be read: " + notes.front()));
  }
  for (const std::string& note : notes) {
    warnings << "physgrad: warning: report: " << one_line(note) << '\n';
  }
  std::string left_out;
  for (const std::string& note : notes) left_out += note + "\n\n";
  std::string commands;
  for (const IndexedFolder& f : folders) {
    if (!f.command.empty()) commands += f.name + ": " + f.command + "\n\n";
  }
  std::vector<HtmlSection> sections;
  if (!notes.empty()) sections.push_back({"Left out", left_out, {}, {}});
  for (HtmlSection& section : comparisons(folders)) sections.push_back(std::move(section));
  sections.push_back({"Every run", "", {every_run_table(folders)}, {}});
  sections.push_back({"Commands", commands, {}, {}});
  write_file_atomic(dir / "index.html",
                    html_report("Runs in " + dir.string() + " — physgrad",
                                std::to_string(folders.size()) + " run folders" +
                                    (notes.empty() ? "."
                                                   : "; some of what they hold is left out, "
                                                     "as listed below."),
                                sections));
  return folders.size();
}

}  // namespace physgrad::experiments
