// Reading one run folder for the index: summary.json and config.json (run_index_summary.cpp),
// then the compared runs' curves from metrics.csv, each file bounded.
#include "physgrad/run/pages/run_index_folder.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <map>

#include "physgrad/error.hpp"
#include "physgrad/io/csv.hpp"
#include "physgrad/io/json_file.hpp"
#include "physgrad/report/seed_band.hpp"
#include "physgrad/run/life/run_folder.hpp"
#include "physgrad/text.hpp"

namespace physgrad::run {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr std::size_t kMaxJsonBytes = std::size_t{8} << 20;      // summary.json, config.json
constexpr std::size_t kMaxMetricsBytes = std::size_t{32} << 20;  // metrics.csv
constexpr std::size_t kMaxMetricsRows = 200000;
constexpr std::size_t kCurvePoints = 300;

using RunRecord = IndexedRun;

// The axes the folder's compared runs are drawn on: learning runs against updates and time,
// direct ones against simulator passes (when that is what the message counts) or iterations —
// never wall time, which timing noise decides for runs of microseconds.
std::vector<IndexAxes> index_axes_of(const IndexedFolder& folder) {
  const std::string& metric = folder.message.metric;
  std::string y_text = folder.message.metric_text;
  // A curve over updates is neither a median of finals nor final: "median final test loss at
  // λ = 1" is drawn as "test loss at λ = 1".
  static const std::string kDropped[] = {"median ", "final "};
  for (const std::string& prefix : kDropped) {
    if (y_text.rfind(prefix, 0) == 0) y_text = y_text.substr(prefix.size());
  }
  if (folder.learning) {
    return {{"iteration", "updates (iterations)", metric, y_text},
            {"wall_seconds", "training time (s, evaluations excluded)", metric, y_text}};
  }
  const bool by_passes = metric == "simulator_passes";
  const std::string y = is_cost_metric(metric) ? "loss" : metric;
  return {{by_passes ? "simulator_passes" : "iteration",
           by_passes ? "simulator passes (forward, VJP, reversal)" : "iterations", y,
           y == "loss" ? "loss L(x)" : y_text, by_passes}};
}

bool index_same_value(const std::string& cell, const json& value) {
  if (value.is_string()) return cell == value.get<std::string>();
  if (!value.is_number()) return false;
  char* end = nullptr;
  const double v = std::strtod(cell.c_str(), &end);
  return end != cell.c_str() && v == value.get<double>();
}

// The compared runs' curves of metrics.csv on each of the folder's axes: per label the median
// and band over its seeds; for direct runs only the rows of the first run's setting.
void add_index_curves(IndexedFolder& folder, const fs::path& file, const RunRecord* first,
                const std::vector<std::string>& setting_keys, std::vector<std::string>& notes) {
  const std::vector<IndexAxes> all_axes = index_axes_of(folder);
  std::vector<std::string> wanted = {"label", "optimizer", "seed"};
  for (const IndexAxes& a : all_axes) wanted.insert(wanted.end(), {a.x, a.y});
  wanted.insert(wanted.end(), setting_keys.begin(), setting_keys.end());
  CsvData metrics =
      parse_csv(read_regular_file(file, kMaxMetricsBytes), {wanted, kMaxMetricsRows});
  if (metrics.rows_left_out > 0) {
    notes.push_back(in_quotes(file.string()) + ": " +
                    std::to_string(metrics.rows.size() + metrics.rows_left_out) +
                    " rows, only the first " + std::to_string(metrics.rows.size()) + " are drawn");
  }
  const std::size_t n = metrics.columns.size(), label = metrics.column("label"),
                    seed = metrics.column("seed");
  if (label == n) return;
  std::vector<std::pair<std::size_t, json>> setting;  // column, the first run's value
  for (const std::string& key : setting_keys) {
    if (metrics.column(key) != n) setting.emplace_back(metrics.column(key), first->params.at(key));
  }
  std::map<std::pair<std::string, std::string>, std::size_t> places;  // (label, seed) → curve
  std::vector<std::pair<std::string, std::vector<std::vector<Curve>>>> curves;  // per curve: axes
  std::size_t rows_left_out = 0;
  for (std::vector<std::string>& row : metrics.rows) {
    row[label] = index_clipped(std::move(row[label]), kIndexMaxName);  // as the summary's labels
    if (!folder.message.compares(row[label])) continue;
    if (!std::all_of(setting.begin(), setting.end(),
                     [&](const auto& s) { return index_same_value(row[s.first], s.second); })) {
      continue;
    }
    const auto key = std::make_pair(row[label], seed == n ? std::string() : row[seed]);
    auto place = places.find(key);
    if (place == places.end()) {
      if (places.size() == kIndexMaxCurves) {
        ++rows_left_out;
        continue;
      }
      place = places.emplace(key, curves.size()).first;
      curves.push_back({row[label], std::vector<std::vector<Curve>>(all_axes.size(),
                                                                    std::vector<Curve>(1))});
    }
    for (std::size_t a = 0; a < all_axes.size(); ++a) {
      const std::size_t x = metrics.column(all_axes[a].x), y = metrics.column(all_axes[a].y);
      if (x == n || y == n) continue;
      Curve& curve = curves[place->second].second[a].front();
      curve.x.push_back(std::strtod(row[x].c_str(), nullptr));
      curve.y.push_back(std::strtod(row[y].c_str(), nullptr));
    }
  }
  if (rows_left_out > 0) {
    notes.push_back(in_quotes(file.string()) + ": more than " + std::to_string(kIndexMaxCurves) +
                    " curves (label and seed), the " + std::to_string(rows_left_out) +
                    " rows of the others are not drawn");
  }
  for (std::size_t a = 0; a < all_axes.size(); ++a) {
    std::vector<Series> drawn;
    std::vector<std::string> labels;  // in the file's order
    for (const auto& [name, per_axes] : curves) {
      if (std::find(labels.begin(), labels.end(), name) == labels.end()) labels.push_back(name);
    }
    for (const std::string& name_of : labels) {
      std::vector<Curve> seeds;
      for (const auto& [name, per_axes] : curves) {
        if (name == name_of && !per_axes[a].front().x.empty()) seeds.push_back(per_axes[a].front());
      }
      if (seeds.empty()) continue;
      Series s = median_band(name_of, seeds, "", true, kCurvePoints);
      if (seeds.size() > 1) s.label += ", median of " + std::to_string(seeds.size());
      drawn.push_back(std::move(s));
    }
    if (!drawn.empty()) folder.curves.emplace_back(all_axes[a], std::move(drawn));
  }
}

json read_index_json(const fs::path& path) {
  return parse_json_text(read_regular_file(path, kMaxJsonBytes), 64);
}

}  // namespace

IndexedFolder read_index_folder(const fs::path& path, std::vector<std::string>& notes,
                                const std::function<bool(const IndexedFolder&)>& draw) {
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
  std::vector<RunRecord> runs;
  reading(summary,
          [&] { runs = read_index_summary(read_index_json(summary), folder, cut, summary); });
  std::error_code error;  // a link inside the folder that leads nowhere counts as absent
  if (fs::exists(config, error)) {
    reading(config, [&] { read_index_config(read_index_json(config), folder, cut, config); });
  }
  add_index_rows(folder, runs, cut, summary);
  add_index_compared(folder, runs, cut, summary);
  // Direct runs: the settings a rule ran at (params that vary among one label's runs, e.g. α).
  std::vector<std::string> setting_keys;
  if (!folder.learning) {
    std::map<std::string, std::vector<const RunRecord*>> by_label;
    for (const RunRecord& run : runs) by_label[run.label].push_back(&run);
    for (const auto& [label, members] : by_label) {
      for (const std::string& key : index_varying_keys(members, true)) {
        if (std::find(setting_keys.begin(), setting_keys.end(), key) == setting_keys.end() &&
            std::all_of(runs.begin(), runs.end(),
                        [&](const RunRecord& r) { return r.params.contains(key); })) {
          setting_keys.push_back(key);
        }
      }
    }
  }
  if (!runs.empty()) {
    folder.first_setting = index_clipped(index_setting(runs.front(), setting_keys), kIndexMaxName);
  }
  if (draw(folder) && fs::exists(metrics, error)) {
    try {
      add_index_curves(folder, metrics, runs.empty() ? nullptr : &runs.front(), setting_keys,
                       cut);
    } catch (const Error& e) {
      cut.push_back(in_quotes(metrics.string()) + ": " + e.what() +
                    "; its loss curves are not drawn");
    }
  }
  folder.has_report = fs::exists(path / "report.html", error);
  notes.insert(notes.end(), cut.begin(), cut.end());
  return folder;
}

}  // namespace physgrad::run
