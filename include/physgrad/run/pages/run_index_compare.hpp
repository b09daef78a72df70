// The comparison of one experiment's run folders by one message metric on the index page
// (`physgrad report`): a table with a row per folder and compared label — the median over the
// runs that count, failed and unconverged runs apart and never ranked, rank r and × best = m / m₁
// among the folder's ranked labels — and the first folders' curves overlaid on the experiment's
// own axes, at most kIndexDrawnFolders folders and kIndexOverlaySeries curves a figure.
#pragma once

#include <algorithm>
#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "physgrad/report/html_report.hpp"
#include "physgrad/report/line_plot.hpp"
#include "physgrad/report/page_spool.hpp"
#include "physgrad/run/pages/run_index_folder.hpp"

namespace physgrad::run {

inline constexpr std::size_t kIndexDrawnFolders = 5;          // folders one overlay draws
inline constexpr std::size_t kIndexOverlaySeries = 32;        // curves one overlay draws
inline constexpr std::size_t kIndexOverlaidComparisons = 24;  // comparisons of a page with overlays
// Medians within this relative difference share a rank (and "best"): |a − b| ≤ tol·max(|a|, |b|).
inline constexpr double kIndexTieTolerance = 1e-9;
bool index_tied(double a, double b);

struct IndexComparison {
  std::string metric, metric_text;
  HtmlTable table;         // the header and caption; the rows are written to `rows`
  PageSpool::Part rows{};  // the rows of every folder, as HTML
  // Per axes, the drawn folders' curves (colour and dashes the rule's, marker shape the folder's).
  std::vector<std::pair<IndexAxes, std::vector<Series>>> figures{};
  std::vector<std::string> drawn{};  // the folders whose curves are overlaid, in order
  std::size_t curves_left_out = 0;   // curves of those folders beyond kIndexOverlaySeries
  bool overlays = false;             // one of the page's first kIndexOverlaidComparisons
  bool direct = false;               // direct runs: the curves are of one setting only
  std::string setting{};             // that setting, e.g. "alpha = 1"

  // True when `folder` is compared here: its message compares by this metric.
  bool compares(const IndexedFolder& folder) const;
  // True while a folder's curves would still be drawn: fewer folders drawn than an overlay
  // takes, and room for more curves.
  bool wants_curves() const {
    return overlays && drawn.size() < kIndexDrawnFolders &&
           std::all_of(figures.begin(), figures.end(),
                       [](const auto& f) { return f.second.size() < kIndexOverlaySeries; });
  }
};

// The comparison of the folder's experiment by the folder's message metric, empty.
IndexComparison new_index_comparison(const IndexedFolder& folder, bool overlays);
// The folder's rows of the comparison's table (its cells, links and colours); `defaults` are the
// experiment's default settings (null: unknown, every setting is listed as an option).
HtmlTable index_comparison_rows(const IndexComparison& c, const IndexedFolder& folder,
                                const nlohmann::json& defaults);
// Adds the folder's curves to the overlays while wants_curves() holds.
void overlay_index_curves(IndexComparison& c, const IndexedFolder& folder);
// The overlays of `experiment`'s comparison `c`, one a set of axes, each with its caption.
std::vector<HtmlFigure> index_overlays(const IndexComparison& c, const std::string& experiment);

}  // namespace physgrad::run
