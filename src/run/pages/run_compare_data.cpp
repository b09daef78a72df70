#include "physgrad/run/pages/run_compare_data.hpp"

#include <cmath>
#include <cstdlib>
#include <map>
#include <nlohmann/json.hpp>

#include "physgrad/io/csv.hpp"
#include "physgrad/report/compare_view.hpp"
#include "physgrad/text.hpp"

namespace physgrad::run {

namespace {

// The cell as a number: a whole cell strtod reads (nan and inf included); false otherwise.
bool compare_cell_number(const std::string& cell, double& value) {
  if (cell.empty()) return false;
  char* end = nullptr;
  value = std::strtod(cell.c_str(), &end);
  return end == cell.c_str() + cell.size();
}

struct CompareRun {
  std::string label, seed;
  std::vector<std::size_t> rows;
  double last_iteration = -INFINITY;
};

// The indices kept of n rows: every k-th and the last, at most kCompareMaxPoints.
std::vector<std::size_t> compare_thinned(std::size_t n) {
  std::vector<std::size_t> kept;
  if (n == 0) return kept;
  const std::size_t k =
      n <= kCompareMaxPoints ? 1 : (n - 1 + kCompareMaxPoints - 3) / (kCompareMaxPoints - 2);
  for (std::size_t i = 0; i < n; i += k) kept.push_back(i);
  if (kept.back() != n - 1) kept.push_back(n - 1);
  return kept;
}

}  // namespace

std::string compare_runs_json(const std::string& group, std::string_view csv_text,
                              std::vector<std::string>& notes) {
  const CsvData csv = parse_csv(csv_text, {{}, 200000});
  if (csv.rows_left_out > 0) {
    notes.push_back(std::to_string(csv.rows.size() + csv.rows_left_out) +
                    " rows, only the first " + std::to_string(csv.rows.size()) +
                    " are in the interactive comparison");
  }
  const std::size_t n = csv.columns.size(), label = csv.column("label"),
                    seed = csv.column("seed"), iteration = csv.column("iteration");
  std::vector<bool> numeric(n, true);
  for (const auto& row : csv.rows) {
    for (std::size_t c = 0; c < n; ++c) {
      double v = 0;
      if (numeric[c] && !row[c].empty() && !compare_cell_number(row[c], v)) numeric[c] = false;
    }
  }
  std::vector<CompareRun> runs;
  std::map<std::pair<std::string, std::string>, std::size_t> open;  // (label, seed) → run
  std::size_t left_out = 0;
  for (std::size_t r = 0; r < csv.rows.size(); ++r) {
    const auto& row = csv.rows[r];
    const auto key = std::make_pair(label == n ? std::string() : row[label],
                                    seed == n ? std::string() : row[seed]);
    double it = 0;
    const bool has_it = iteration != n && compare_cell_number(row[iteration], it);
    auto at = open.find(key);
    if (at == open.end() || (has_it && it <= runs[at->second].last_iteration)) {
      if (runs.size() == kCompareMaxRuns) {
        ++left_out;
        continue;
      }
      open[key] = runs.size();
      runs.push_back({key.first, key.second, {}, -INFINITY});
      at = open.find(key);
    }
    runs[at->second].rows.push_back(r);
    if (has_it) runs[at->second].last_iteration = it;
  }
  if (left_out > 0) {
    notes.push_back("more than " + std::to_string(kCompareMaxRuns) + " runs, the " +
                    std::to_string(left_out) + " rows of the others are not in the interactive "
                    "comparison");
  }
  std::string out;
  for (const CompareRun& run : runs) {
    nlohmann::json columns = nlohmann::json::object();
    const std::vector<std::size_t> kept = compare_thinned(run.rows.size());
    for (std::size_t c = 0; c < n; ++c) {
      if (!numeric[c] || c == seed || c == label) continue;
      nlohmann::json values = nlohmann::json::array();
      for (const std::size_t k : kept) {
        double v = NAN;
        compare_cell_number(csv.rows[run.rows[k]][c], v);
        values.push_back(std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr));
      }
      columns[shown_text(csv.columns[c])] = std::move(values);
    }
    // Names as the page's text shows them (U+FFFD for what is hidden), every non-ASCII
    // character a \u escape.
    const nlohmann::json object = {{"g", shown_text(group)}, {"l", shown_text(run.label)},
                                   {"s", shown_text(run.seed)},
                                   {"c", std::move(columns)}};
    if (!out.empty()) out += ',';
    out += json_for_script(object.dump(-1, ' ', true, nlohmann::json::error_handler_t::replace));
  }
  return out;
}

}  // namespace physgrad::run
