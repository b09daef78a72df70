// The index page of a folder of run folders: the folders are read one at a time
// (run_index_folder.hpp) and only their digests' table rows and the first folders' curves are
// kept, so that memory does not grow with what each folder holds.
#include "physgrad/run/run_index.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "physgrad/catalogue.hpp"
#include "physgrad/error.hpp"
#include "physgrad/io/atomic_file.hpp"
#include "physgrad/report/colors.hpp"
#include "physgrad/report/html_report.hpp"
#include "physgrad/report/line_plot.hpp"
#include "physgrad/report/plot_marks.hpp"
#include "physgrad/run/registry.hpp"
#include "physgrad/run/run_folder.hpp"
#include "physgrad/run/run_index_folder.hpp"
#include "physgrad/text.hpp"

namespace physgrad::experiments {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr std::size_t kDrawnFolders = 5;  // folders whose curves one figure overlays

// The colour rule `id` has in every figure (the catalogue's; a pretrained run's, color_for's),
// or a palette colour for an id that names no rule.
std::string rule_colour(const std::string& id, std::size_t fallback) {
  for (const RuleInfo& rule : rule_catalogue()) {
    if (rule.id == id) return rule.colour;
  }
  if (!pretrained_rule(id).empty()) return color_for(id);
  return palette_color(fallback);
}

// Dashed as in the reports: a pretrained run, and PG through a numerical local inverse.
bool rule_dashed(const ComparedGroup& group) {
  if (!pretrained_rule(group.rule).empty()) return true;
  return group.rule == "pg" && group.label.find(" inverse)") != std::string::npos &&
         group.label.find("analytic") == std::string::npos;
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
    if (!value.is_array()) return index_text(value);
    std::string out;
    for (const json& item : value) out += (out.empty() ? "" : ",") + index_text(item);
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

// "1 of 4 failed, 1 did not converge"; empty when every run counts.
std::string apart_text(const ComparedGroup& g) {
  std::string out;
  if (g.failed > 0) out = std::to_string(g.failed) + " of " + std::to_string(g.runs) + " failed";
  if (g.unreached > 0) {
    out += (out.empty() ? std::to_string(g.unreached) + " of " + std::to_string(g.runs)
                        : ", " + std::to_string(g.unreached)) +
           " did not converge";
  }
  return out;
}

// The comparison of one experiment's folders by one message metric: the table (a row per folder
// and compared label) and the overlays of the first folders' curves, one per axes.
struct Comparison {
  std::string metric, metric_text;
  json baseline;
  HtmlTable table;
  std::vector<std::pair<IndexAxes, std::vector<Series>>> figures;
  std::vector<std::string> drawn;  // the folders whose curves are overlaid, with their shapes
  bool direct_setting = false;     // direct runs: the curves are of the first setting only
  std::string setting;
};

struct ExperimentSection {
  std::string name, sentences;
  std::vector<Comparison> comparisons;
};

Comparison new_comparison(const IndexedFolder& folder, const json& baseline) {
  const std::string& text = folder.message.metric_text;
  return {folder.message.metric,
          text,
          baseline,
          {{"run folder", "options", "rule", "runs", text, "apart", "rank", "× best", "ended by",
            "seconds"},
           {},
           "By " + text + " (lower is better): per run folder and rule, the median over its runs "
           "(seeds, settings) that count, with their range in brackets and the digits their "
           "spread supports. Apart: runs that failed (a non-finite value, a failure, divergence)"
           " or, where the metric is a cost, did not converge; they are not in the median, and "
           "a rule with any is not ranked. Rank and × best: among the folder's ranked rules. "
           "Options: the settings that differ from the experiment's defaults. Seconds: the "
           "median time of a run.",
           {},
           {}},
          {},
          {},
          !folder.learning,
          folder.first_setting};
}

// The folder's rows of the comparison and, while fewer than kDrawnFolders are overlaid, its
// curves (colour and dashes the rule's, the marker shape the folder's).
void add_to(Comparison& c, const IndexedFolder& folder) {
  const std::string options = differing_options(folder.settings, c.baseline);
  std::vector<std::size_t> ranked;
  for (std::size_t k = 0; k < folder.compared.size(); ++k) {
    if (folder.compared[k].ranked()) ranked.push_back(k);
  }
  std::sort(ranked.begin(), ranked.end(), [&](std::size_t a, std::size_t b) {
    return folder.compared[a].metric.median < folder.compared[b].metric.median;
  });
  std::map<std::size_t, std::size_t> rank;  // group → rank (ties share one)
  for (std::size_t r = 0; r < ranked.size(); ++r) {
    const bool tie = r > 0 && folder.compared[ranked[r]].metric.median ==
                                  folder.compared[ranked[r - 1]].metric.median;
    rank[ranked[r]] = tie ? rank[ranked[r - 1]] : r + 1;
  }
  for (std::size_t k = 0; k < folder.compared.size(); ++k) {
    const ComparedGroup& g = folder.compared[k];
    const bool is_ranked = rank.contains(k);
    std::string times = "–";
    if (is_ranked && rank[k] == 1) {
      times = "best";
    } else if (is_ranked && folder.compared[ranked.front()].metric.median > 0) {
      times = ratio_text(g.metric, folder.compared[ranked.front()].metric) + "×";
    }
    c.table.rows.push_back({folder.name, options, g.label, std::to_string(g.runs),
                            median_and_range(g.metric), apart_text(g),
                            is_ranked ? std::to_string(rank[k]) : "not ranked", times, g.ended,
                            median_and_range(g.seconds)});
    c.table.links.push_back(std::vector<std::string>(c.table.header.size()));
    if (folder.has_report) c.table.links.back()[0] = folder.name + "/report.html";
    c.table.colours.push_back(std::vector<std::string>(c.table.header.size()));
    c.table.colours.back()[2] = rule_colour(g.rule, k);
  }
  if (folder.curves.empty() || c.drawn.size() >= kDrawnFolders) return;
  const int shape = static_cast<int>(c.drawn.size()) % plot::kShapes;
  c.drawn.push_back(folder.name);
  for (const auto& [axes, curves] : folder.curves) {
    auto figure = std::find_if(c.figures.begin(), c.figures.end(),
                               [&](const auto& f) { return f.first.x == axes.x; });
    if (figure == c.figures.end()) figure = c.figures.insert(c.figures.end(), {axes, {}});
    for (const Series& curve : curves) {
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
        s.dashed = rule_dashed(*group);
        if (group->switched_at >= 0 && axes.x == "iteration") {
          double y = NAN;  // the median where the rule took over
          for (std::size_t i = 0; i < s.x.size() && s.x[i] <= static_cast<double>(group->switched_at); ++i) y = s.y[i];
          s.marks.push_back({static_cast<double>(group->switched_at), y,
                             "switched from Adam after " + std::to_string(group->switched_at)});
        }
        if (group->failed > 0) s.end_label = std::to_string(group->failed) + " failed";
      }
      figure->second.push_back(std::move(s));
    }
  }
}

// The page's sections of one experiment: each folder's sentence, then per metric its table and
// figures.
HtmlSection section_of(const ExperimentSection& e) {
  HtmlSection section{e.name, e.sentences, {}, {}};
  static const char* const kShapeNames[] = {"●", "□", "△", "◇", "▽"};
  for (const Comparison& c : e.comparisons) {
    section.tables.push_back(c.table);
    std::string folders;
    for (std::size_t k = 0; k < c.drawn.size(); ++k) {
      folders += (k ? ", " : "") + std::string(kShapeNames[k % plot::kShapes]) + " " + c.drawn[k];
    }
    for (const auto& [axes, series] : c.figures) {
      LinePlotOptions options;
      options.title = e.name + ": " + axes.y_text + " vs " + axes.x_text;
      options.x_label = axes.x_text;
      options.y_label = axes.y_text;
      options.log_y = true;
      options.log_x = axes.log_x;
      section.figures.push_back(
          {e.name + ": the " + axes.y_text + " of every compared run against " + axes.x_text +
               (c.direct_setting && !c.setting.empty() ? ", at " + c.setting : "") +
               ". Colour and dashes: the rule's, as in the reports; marker shape: the run "
               "folder (" + folders + (c.drawn.size() == kDrawnFolders ? "; later folders are "
               "in the table only" : "") + "); line: median over seeds, band: their minimum to "
               "maximum; ◆: where a pretrained run switched from Adam to its rule.",
           line_plot_svg(series, options)});
    }
  }
  return section;
}

// The run folders directly in `dir` (folders with a summary.json), by name.
std::vector<fs::path> run_folder_paths(const fs::path& dir) {
  std::vector<fs::path> paths;
  // Entries that cannot be followed (a looping or dangling link) are not run folders.
  for (const fs::directory_entry& entry : fs::directory_iterator(dir)) {
    std::error_code error;
    if (entry.is_directory(error) && fs::exists(entry.path() / kSummaryFile, error)) {
      paths.push_back(entry.path());
    }
  }
  std::sort(paths.begin(), paths.end());
  return paths;
}

HtmlTable every_run_table() {
  return {{"run folder", "experiment", "run", "setting", "runs", "final loss", "final test loss",
           "iterations", "ended by", "seconds"},
          {},
          "Every run of every run folder (runs: how many, e.g. seeds), with the median over "
          "them (the digits their spread supports): the final loss (learning runs: the mean "
          "over the training set; direct optimization: L(x)), the final mean loss over the test "
          "set where there is one, the iterations made, what ended the runs and the time in "
          "seconds (learning: training, evaluations excluded; direct optimization: wall-clock). "
          "A folder's name links to its report.",
          {}};
}

void add_every_run(HtmlTable& table, const IndexedFolder& folder) {
  const auto cell = [](const Spread& s) { return with_digits(s.median, digits_for(s)); };
  for (const EveryRunRow& row : folder.rows) {
    table.rows.push_back({folder.name, folder.experiment, row.label, row.setting,
                          std::to_string(row.runs), cell(row.loss), cell(row.test_loss),
                          cell(row.iterations), row.ended, cell(row.seconds)});
    table.links.push_back(std::vector<std::string>(table.header.size()));
    if (folder.has_report) table.links.back()[0] = folder.name + "/report.html";
  }
}

}  // namespace

RunIndex write_run_index(const fs::path& dir, std::ostream& warnings) {
  std::error_code error;
  if (!fs::is_directory(dir, error)) {
    throw Error("report: '" + dir.string() + "' is not a directory");
  }
  std::vector<std::string> notes;
  std::vector<ExperimentSection> experiments;
  std::map<std::string, json> baselines;
  std::map<std::string, std::size_t> drawn;  // folders with curves read, per experiment
  HtmlTable every_run = every_run_table();
  std::string commands;
  std::size_t shown = 0;
  for (const fs::path& path : run_folder_paths(dir)) {
    IndexedFolder folder;
    try {
      folder = read_index_folder(path, notes, [&](const std::string& experiment) {
        return drawn[experiment]++ < 2 * kDrawnFolders;  // a metric may take several
      });
    } catch (const Error& e) {
      notes.push_back(std::string(e.what()) + "; the folder is left out");
      continue;
    }
    ++shown;
    auto e = std::find_if(experiments.begin(), experiments.end(),
                          [&](const ExperimentSection& s) { return s.name == folder.experiment; });
    if (e == experiments.end()) {
      e = experiments.insert(experiments.end(), {folder.experiment, "", {}});
      json baseline = default_settings(folder.experiment);
      baselines[folder.experiment] = baseline.is_null() ? folder.settings : baseline;
    }
    if (!folder.message.sentence.empty()) {
      e->sentences += folder.name + ": " + folder.message.sentence + "\n\n";
    }
    auto c = std::find_if(e->comparisons.begin(), e->comparisons.end(), [&](const Comparison& x) {
      return x.metric == folder.message.metric && x.metric_text == folder.message.metric_text;
    });
    if (c == e->comparisons.end()) {
      c = e->comparisons.insert(e->comparisons.end(),
                                new_comparison(folder, baselines[folder.experiment]));
    }
    add_to(*c, folder);
    add_every_run(every_run, folder);
    if (!folder.command.empty()) commands += folder.name + ": " + folder.command + "\n\n";
  }
  if (shown == 0) {
    throw Error("report: '" + dir.string() + "' holds no run folder (a folder with summary.json)" +
                (notes.empty() ? "" : " that can be read: " + notes.front()));
  }
  for (const std::string& note : notes) {
    warnings << "physgrad: warning: report: " << one_line(note) << '\n';
  }
  std::string left_out;
  for (const std::string& note : notes) left_out += note + "\n\n";
  std::vector<HtmlSection> sections;
  if (!notes.empty()) sections.push_back({"Left out", left_out, {}, {}});
  for (const ExperimentSection& e : experiments) sections.push_back(section_of(e));
  sections.push_back({"Every run", "", {std::move(every_run)}, {}});
  sections.push_back({"Commands", commands, {}, {}});
  // A run folder may be named index.html: the page then takes another name.
  std::string name = "index.html";
  for (int k = 2; fs::exists(dir / name, error) && !fs::is_regular_file(dir / name, error); ++k) {
    name = "index-" + std::to_string(k) + ".html";
  }
  write_file_atomic(dir / name,
                    html_report("Runs in " + dir.string() + " — physgrad",
                                std::to_string(shown) + " run folders" +
                                    (notes.empty() ? "."
                                                   : "; some of what they hold is left out, "
                                                     "as listed below."),
                                sections));
  return {shown, dir / name};
}

}  // namespace physgrad::experiments
