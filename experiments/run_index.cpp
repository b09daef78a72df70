#include "run_index.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "physgrad/error.hpp"
#include "physgrad/json_file.hpp"
#include "physgrad/report/atomic_file.hpp"
#include "physgrad/report/colors.hpp"
#include "physgrad/report/csv.hpp"
#include "physgrad/report/html_report.hpp"
#include "physgrad/report/line_plot.hpp"
#include "physgrad/report/seed_band.hpp"
#include "report_page.hpp"
#include "run_folder.hpp"

namespace physgrad::experiments {

namespace fs = std::filesystem;

namespace {

struct IndexedFolder {
  std::string name;
  nlohmann::json summary;
  std::string command;
  std::optional<CsvData> metrics;
  bool has_report = false;
};

// All of a regular file of a run folder (never blocking on a FIFO), errors naming it.
std::string read_text(const fs::path& path) {
  try {
    return read_regular_file(path, std::size_t{1} << 32);
  } catch (const Error& e) {
    throw Error("report: '" + path.string() + "': " + e.what());
  }
}

nlohmann::json read_json(const fs::path& path) {
  const std::string text = read_text(path);
  try {
    return parse_json_text(text, 64);
  } catch (const Error& e) {
    throw Error("report: '" + path.string() + "': " + e.what());
  }
}

std::vector<IndexedFolder> find_run_folders(const fs::path& dir) {
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
    IndexedFolder folder;
    folder.name = path.filename().string();
    folder.summary = read_json(path / kSummaryFile);
    if (!folder.summary.is_object() || !folder.summary.value("runs", nlohmann::json()).is_array()) {
      throw Error("report: '" + (path / kSummaryFile).string() + "' has no list of runs");
    }
    std::error_code error;  // a link inside the folder that leads nowhere counts as absent
    if (fs::exists(path / kConfigFile, error)) {
      folder.command = read_json(path / kConfigFile).value("command", std::string());
    }
    if (fs::exists(path / "metrics.csv", error)) {
      try {
        folder.metrics = parse_csv(read_text(path / "metrics.csv"));
      } catch (const Error& e) {
        throw Error("report: '" + (path / "metrics.csv").string() + "': " + e.what());
      }
    }
    folder.has_report = fs::exists(path / "report.html", error);
    folders.push_back(std::move(folder));
  }
  return folders;
}

std::string text_of(const nlohmann::json& value) {
  return value.is_string() ? value.get<std::string>() : format_number(value);
}

double number_in(const nlohmann::json& object, const char* key) {
  const nlohmann::json value = object.is_object() ? object.value(key, nlohmann::json()) : nullptr;
  return value.is_number() ? value.get<double>() : NAN;
}

// One row per run folder and run label with its setting (the parameters that vary among that
// label's runs, seeds aside); the figures are medians over the seeds.
HtmlTable runs_table(const std::vector<IndexedFolder>& folders) {
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
    const std::string experiment = folder.summary.value("experiment", std::string("?"));
    const nlohmann::json& runs = folder.summary.at("runs");
    // The parameters that vary among the runs of each label (seed aside).
    std::map<std::string, std::vector<std::string>> varying;
    const auto params = [](const nlohmann::json& run) {
      const nlohmann::json p = run.value("params", nlohmann::json::object());
      return p.is_object() ? p : nlohmann::json::object();
    };
    for (const nlohmann::json& run : runs) {
      const std::string label = run.value("label", std::string("?"));
      const nlohmann::json own = params(run);
      for (const nlohmann::json& other : runs) {
        if (other.value("label", std::string("?")) != label) continue;
        const nlohmann::json others = params(other);
        for (const auto& [key, value] : own.items()) {
          auto& keys = varying[label];
          if (key != "seed" && others.value(key, nlohmann::json()) != value &&
              std::find(keys.begin(), keys.end(), key) == keys.end()) {
            keys.push_back(key);
          }
        }
      }
    }
    std::vector<std::pair<std::string, std::string>> groups;  // (label, setting), first seen
    std::map<std::pair<std::string, std::string>, std::vector<const nlohmann::json*>> members;
    for (const nlohmann::json& run : runs) {
      const std::string label = run.value("label", std::string("?"));
      std::string setting;
      for (const std::string& key : varying[label]) {
        setting += (setting.empty() ? "" : ", ") + key + " = " +
                   text_of(params(run).value(key, nlohmann::json()));
      }
      const auto key = std::make_pair(label, setting);
      if (members.find(key) == members.end()) groups.push_back(key);
      members[key].push_back(&run);
    }
    for (const auto& key : groups) {
      std::vector<double> loss, test, iterations, seconds;
      std::vector<std::string> ends;
      for (const nlohmann::json* run : members[key]) {
        loss.push_back(number_in(run->value("final", nlohmann::json()), "loss"));
        test.push_back(number_in(run->value("final", nlohmann::json()), "test_loss"));
        iterations.push_back(number_in(*run, "iterations"));
        seconds.push_back(number_in(*run, "wall_seconds"));
        const std::string end = run->value("termination", std::string("–"));
        if (std::find(ends.begin(), ends.end(), end) == ends.end()) ends.push_back(end);
      }
      std::string ended;
      for (const std::string& e : ends) ended += (ended.empty() ? "" : ", ") + e;
      const auto cell = [](double v) { return std::isnan(v) ? std::string("–") : text_of(v); };
      const auto whole = [&cell](double v) {
        return v == std::round(v) && std::abs(v) < 1e15 ? std::to_string(std::llround(v)) : cell(v);
      };
      table.rows.push_back({folder.name, experiment, key.first, key.second,
                            std::to_string(members[key].size()), cell(median(loss)),
                            cell(median(test)), whole(median(iterations)), ended,
                            cell(median(seconds))});
      table.links.push_back(std::vector<std::string>(table.header.size()));
      if (folder.has_report) table.links.back()[0] = folder.name + "/report.html";
    }
  }
  return table;
}

// Per run label of a folder, one curve (test loss vs training time) per seed.
std::map<std::string, std::vector<Curve>> curves_by_label(const CsvData& metrics,
                                                          std::vector<std::string>& order) {
  const std::size_t label = metrics.column("label"), seconds = metrics.column("wall_seconds"),
                    loss = metrics.column("test_loss"), seed = metrics.column("seed");
  const std::size_t n = metrics.columns.size();
  std::map<std::string, std::map<std::string, Curve>> by_label;
  if (label == n || seconds == n || loss == n) return {};
  for (const auto& row : metrics.rows) {
    if (by_label.find(row[label]) == by_label.end()) order.push_back(row[label]);
    Curve& c = by_label[row[label]][seed == n ? std::string() : row[seed]];
    c.x.push_back(std::strtod(row[seconds].c_str(), nullptr));
    c.y.push_back(std::strtod(row[loss].c_str(), nullptr));
  }
  std::map<std::string, std::vector<Curve>> out;
  for (auto& [name, seeds] : by_label) {
    for (auto& entry : seeds) out[name].push_back(std::move(entry.second));
  }
  return out;
}

// Per experiment with learning runs: the test loss of every run of every folder vs time.
std::vector<HtmlFigure> overlays(const std::vector<IndexedFolder>& folders) {
  std::vector<std::string> experiments;
  for (const IndexedFolder& f : folders) {
    const std::string e = f.summary.value("experiment", std::string("?"));
    if (std::find(experiments.begin(), experiments.end(), e) == experiments.end()) {
      experiments.push_back(e);
    }
  }
  std::vector<HtmlFigure> figures;
  for (const std::string& experiment : experiments) {
    std::vector<Series> series;
    std::size_t count = 0;
    for (const IndexedFolder& f : folders) {
      if (f.summary.value("experiment", std::string("?")) != experiment || !f.metrics) continue;
      std::vector<std::string> order;
      const auto curves = curves_by_label(*f.metrics, order);
      count += curves.empty() ? 0 : 1;
      for (const std::string& label : order) {
        const std::vector<Curve>& seeds = curves.at(label);
        Series s = median_band(f.name + ": " + label +
                                   (seeds.size() > 1
                                        ? ", median of " + std::to_string(seeds.size())
                                        : ""),
                               seeds, palette_color(series.size()), true);
        s.markers = true;
        s.dashed = count % 2 == 0;
        series.push_back(std::move(s));
      }
    }
    if (series.empty()) continue;
    LinePlotOptions options;
    options.title = experiment + ": test loss vs training time, every run folder";
    options.x_label = "training time (s, evaluations excluded)";
    options.y_label = "mean test loss";
    options.log_y = true;
    figures.push_back({experiment + ": the test loss of every run in " + std::to_string(count) +
                           " run folder" + (count == 1 ? "" : "s") +
                           " (line: median over seeds, band: their minimum to maximum; runs of "
                           "every second folder dashed).",
                       line_plot_svg(series, options)});
  }
  return figures;
}

}  // namespace

std::size_t write_run_index(const fs::path& dir) {
  std::error_code error;
  if (!fs::is_directory(dir, error)) {
    throw Error("report: '" + dir.string() + "' is not a directory");
  }
  const std::vector<IndexedFolder> folders = find_run_folders(dir);
  if (folders.empty()) {
    throw Error("report: '" + dir.string() + "' holds no run folder (a folder with summary.json)");
  }
  std::string commands;
  for (const IndexedFolder& f : folders) {
    if (!f.command.empty()) commands += f.name + ": " + f.command + "\n\n";
  }
  const std::vector<HtmlSection> sections = {
      {"Runs", "", {runs_table(folders)}, {}},
      {"Loss curves of all runs", "", {}, overlays(folders)},
      {"Commands", commands, {}, {}}};
  write_file_atomic(dir / "index.html",
                    html_report("Runs in " + dir.string() + " — physgrad",
                                std::to_string(folders.size()) + " run folders.", sections));
  return folders.size();
}

}  // namespace physgrad::experiments
