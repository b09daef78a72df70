// One comparison of the index page (run_index_compare.hpp): its table rows per folder and its
// overlays of the first folders' curves.
#include "physgrad/run/pages/run_index_compare.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include "physgrad/catalogue.hpp"
#include "physgrad/report/colors.hpp"
#include "physgrad/run/cases/rule_colors.hpp"
#include "physgrad/report/plot_marks.hpp"
#include "physgrad/report/significant.hpp"

namespace physgrad::run {

using nlohmann::json;

namespace {

// The colour rule `id` has in every figure (the catalogue's; a pretrained run's, color_for's),
// or a palette colour for an id that names no rule.
std::string rule_colour(const std::string& id, std::size_t fallback) {
  const auto& rules = rule_catalogue();
  const bool known = !pretrained_rule(id).empty() ||
                     std::any_of(rules.begin(), rules.end(),
                                 [&](const RuleInfo& rule) { return rule.id == id; });
  return known ? color_for(id) : palette_color(fallback);
}

// Dashed as in the reports: a pretrained run, and PG through a numerical local inverse.
bool rule_dashed(const ComparedGroup& group) {
  if (!pretrained_rule(group.rule).empty()) return true;
  return group.rule == "pg" && group.label.find(" inverse)") != std::string::npos &&
         group.label.find("analytic") == std::string::npos;
}

// "lr = 0.01, iters = 300": the settings that differ from `defaults` (every setting when they
// are null), but those that do not change what a run computes (where it is written, threads,
// checkpoints) and the rules (a column of their own); cut at kIndexMaxName bytes.
std::string differing_options(const json& settings, const json& defaults) {
  static const std::vector<std::string> kNotCompared = {
      "out", "threads", "checkpoint-every", "checkpoint-seconds", "distributed-gram-rows",
      "optimizers"};
  const auto text = [](const json& value) {
    if (value.is_null()) return std::string("unset");
    if (!value.is_array()) return value.is_object() ? value.dump() : index_text(value);
    std::string out;
    for (const json& item : value) {
      out += (out.empty() ? "" : ",") + (item.is_string() || item.is_number() ? index_text(item)
                                                                              : item.dump());
    }
    return out;
  };
  std::string out;
  for (auto it = settings.begin(); it != settings.end() && out.size() <= kIndexMaxName; ++it) {
    if (std::find(kNotCompared.begin(), kNotCompared.end(), it.key()) != kNotCompared.end()) {
      continue;
    }
    if (defaults.is_object() && it.value() == defaults.value(it.key(), json())) continue;
    out += (out.empty() ? "" : ", ") + it.key() + " = " + text(it.value());
  }
  return index_clipped(std::move(out), kIndexMaxName);
}

// "1 of 4 failed, 1 did not converge, 1 diverging (loss above its start), 1 never switched from
// Adam"; empty when every run counts.
std::string apart_text(const ComparedGroup& g) {
  std::string out;
  if (g.failed > 0) out = std::to_string(g.failed) + " of " + std::to_string(g.runs) + " failed";
  if (g.unreached > 0) {
    out += (out.empty() ? std::to_string(g.unreached) + " of " + std::to_string(g.runs)
                        : ", " + std::to_string(g.unreached)) +
           " did not converge";
  }
  if (g.diverging > 0) {
    out += (out.empty() ? std::to_string(g.diverging) + " of " + std::to_string(g.runs)
                        : ", " + std::to_string(g.diverging)) +
           " diverging (loss above its start)";
  }
  if (g.unswitched > 0) {
    out += (out.empty() ? std::to_string(g.unswitched) + " of " + std::to_string(g.runs)
                        : ", " + std::to_string(g.unswitched)) +
           " never switched from Adam";
  }
  return out;
}

}  // namespace

bool index_tied(double a, double b) {
  return std::abs(a - b) <= kIndexTieTolerance * std::max(std::abs(a), std::abs(b));
}

bool IndexComparison::compares(const IndexedFolder& folder) const {
  return metric == folder.message.metric && metric_text == folder.message.metric_text;
}

IndexComparison new_index_comparison(const IndexedFolder& folder, bool overlays) {
  const std::string& text = folder.message.metric_text;
  IndexComparison c;
  c.metric = folder.message.metric;
  c.metric_text = text;
  c.table = {{"run folder", "options", "rule", "runs", text, "apart", "rank", "× best", "ended by",
              "seconds"},
             {},
             "By " + text + " (lower is better): per run folder and rule, the median over its "
             "runs (seeds, settings) that count, with their range in brackets and the digits "
             "their spread supports. Apart: runs that failed (a non-finite value, a failure, "
             "divergence) or, where the metric is a cost, did not converge (diverging: ended above "
             "the start); they are not in the "
             "median, and a rule with any is not ranked. Rank and × best: among the folder's "
             "ranked rules; medians within a relative 1e-9 of each other share a rank. "
             "Options: the settings that differ from the experiment's defaults "
             "(every setting for an experiment this program does not know). Seconds: the median "
             "time of a run.",
             {},
             {}};
  c.overlays = overlays;
  c.direct = !folder.learning;
  c.setting = folder.first_setting;
  return c;
}

HtmlTable index_comparison_rows(const IndexComparison& c, const IndexedFolder& folder,
                                const json& defaults) {
  HtmlTable table{c.table.header, {}, "", {}, {}};
  const std::string options = differing_options(folder.settings, defaults);
  std::vector<std::size_t> ranked;
  for (std::size_t k = 0; k < folder.compared.size(); ++k) {
    if (folder.compared[k].ranked()) ranked.push_back(k);
  }
  std::sort(ranked.begin(), ranked.end(), [&](std::size_t a, std::size_t b) {
    return folder.compared[a].metric.median < folder.compared[b].metric.median;
  });
  std::map<std::size_t, std::size_t> rank;  // group → rank (ties share one)
  for (std::size_t r = 0; r < ranked.size(); ++r) {
    const bool tie = r > 0 && index_tied(folder.compared[ranked[r - 1]].metric.median,
                                          folder.compared[ranked[r]].metric.median);
    rank[ranked[r]] = tie ? rank[ranked[r - 1]] : r + 1;
  }
  for (std::size_t k = 0; k < folder.compared.size(); ++k) {
    const ComparedGroup& g = folder.compared[k];
    const bool is_ranked = rank.contains(k);
    std::string times = "–";
    if (is_ranked && rank[k] == 1) {  // every rule tied with the lowest is best
      times = "best";
    } else if (is_ranked && folder.compared[ranked.front()].metric.median > 0) {
      times = ratio_text(g.metric, folder.compared[ranked.front()].metric) + "×";
    }
    table.rows.push_back({folder.name, options, g.label, std::to_string(g.runs),
                          median_and_range(g.metric), apart_text(g),
                          is_ranked ? std::to_string(rank[k]) : "not ranked", times, g.ended,
                          median_and_range(g.seconds)});
    table.links.push_back(std::vector<std::string>(table.header.size()));
    if (folder.has_report) table.links.back()[0] = folder.name + "/report.html";
    table.colours.push_back(std::vector<std::string>(table.header.size()));
    table.colours.back()[2] = rule_colour(g.rule, k);
  }
  return table;
}

void overlay_index_curves(IndexComparison& c, const IndexedFolder& folder) {
  if (folder.curves.empty() || !c.wants_curves()) return;
  const int shape = static_cast<int>(c.drawn.size()) % plot::kShapes;
  c.drawn.push_back(folder.name);
  std::size_t left_out = 0;  // the most curves of one axes not drawn
  for (const auto& [axes, curves] : folder.curves) {
    std::map<std::string, int> variants;  // curves of each rule so far (e.g. PG's inverses)
    auto figure = std::find_if(c.figures.begin(), c.figures.end(),
                               [&](const auto& f) { return f.first.x == axes.x; });
    if (figure == c.figures.end()) figure = c.figures.insert(c.figures.end(), {axes, {}});
    std::size_t skipped = 0;
    for (const Series& curve : curves) {
      if (figure->second.size() >= kIndexOverlaySeries) {
        ++skipped;
        continue;
      }
      const auto group = std::find_if(folder.compared.begin(), folder.compared.end(),
                                      [&](const ComparedGroup& g) {
                                        return curve.label.rfind(g.label, 0) == 0;
                                      });
      Series s = curve;
      s.label = folder.name + ": " + curve.label;
      s.markers = true;
      s.shape = shape;
      if (group != folder.compared.end()) {
        s.color = rule_colour(group->rule, figure->second.size());
        // The rule's dashes; a further variant of the rule in the folder, dashes of its own.
        const int variant = variants[group->rule]++;
        s.dashed = variant > 0 || rule_dashed(*group);
        s.dash_pattern = variant;
        if (group->switched_at >= 0 && axes.x == "iteration") {
          const double at = static_cast<double>(group->switched_at);
          double y = NAN;  // the median where the rule took over
          for (std::size_t i = 0; i < s.x.size() && s.x[i] <= at; ++i) y = s.y[i];
          s.marks.push_back({at, y, "switched from Adam after " +
                                        std::to_string(group->switched_at)});
        }
        if (group->failed > 0) s.end_label = std::to_string(group->failed) + " failed";
        // A rule with a failed or diverging run never sets the axis range (as in the reports).
        s.sets_range = group->failed == 0 && group->diverging == 0;
      }
      figure->second.push_back(std::move(s));
    }
    left_out = std::max(left_out, skipped);
  }
  c.curves_left_out += left_out;
}

std::vector<HtmlFigure> index_overlays(const IndexComparison& c, const std::string& experiment) {
  static const char* const kShapeNames[] = {"●", "□", "△", "◇", "▽"};
  std::string folders;
  for (std::size_t k = 0; k < c.drawn.size(); ++k) {
    folders += (k ? ", " : "") + std::string(kShapeNames[k % plot::kShapes]) + " " + c.drawn[k];
  }
  std::string later;
  if (c.drawn.size() == kIndexDrawnFolders) later = "; later folders are in the table only";
  if (c.curves_left_out > 0) {
    later += "; " + std::to_string(c.curves_left_out) + " curves of these folders beyond the " +
             std::to_string(kIndexOverlaySeries) + " a figure draws are in the table only";
  }
  std::vector<HtmlFigure> figures;
  for (const auto& [axes, series] : c.figures) {
    LinePlotOptions options;
    options.title = experiment + ": " + axes.y_text + " vs " + axes.x_text;
    options.x_label = axes.x_text;
    options.y_label = axes.y_text;
    options.log_y = true;
    options.log_x = axes.log_x;
    figures.push_back(
        {experiment + ": the " + axes.y_text + " of every compared run against " + axes.x_text +
             (c.direct && !c.setting.empty() ? ", at " + c.setting : "") +
             ". Colour and dashes: the rule's, as in the reports (a further variant of a rule, "
             "e.g. PG with another inverse, dashes of its own); marker shape: the run folder (" +
             folders + later + "); line: median over seeds, band: their minimum to maximum; ◆: "
             "where a pretrained run switched from Adam to its rule.",
         line_plot_svg(series, options)});
  }
  return figures;
}

}  // namespace physgrad::run
