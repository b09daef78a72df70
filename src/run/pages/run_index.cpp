// The index page of a folder of run folders: the folders are read one at a time
// (run_index_folder.hpp) into bounded digests; what the page shows of each — its sentence, its
// rows in the tables, its command — goes to a spool file at once, and only the overlays' curves
// stay in memory, for a bounded number of folders, so that memory does not grow with the number
// of folders. The page is written at the end, part by part, from the spool.
#include "physgrad/run/pages/run_index.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "physgrad/error.hpp"
#include "physgrad/io/atomic_file.hpp"
#include "physgrad/io/json_file.hpp"
#include "physgrad/report/compare_view.hpp"
#include "physgrad/report/html_report.hpp"
#include "physgrad/report/page_spool.hpp"
#include "physgrad/run/life/checkpoint.hpp"
#include "physgrad/run/cases/registry.hpp"
#include "physgrad/run/pages/run_compare_data.hpp"
#include "physgrad/run/life/run_folder.hpp"
#include "physgrad/run/pages/run_index_compare.hpp"
#include "physgrad/run/pages/run_index_folder.hpp"
#include "physgrad/text.hpp"

namespace physgrad::run {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// The settings of experiment `name` when no option is given, or null for a name `experiments`
// does not hold.
json default_settings(const Registry& experiments, const std::string& name) {
  for (const auto& experiment : experiments) {
    if (experiment->name() == name) return resolve_settings(*experiment, {}).json();
  }
  return nullptr;
}

struct ExperimentSection {
  std::string name;
  json defaults;                // null: an experiment the registry does not hold
  PageSpool::Part sentences;    // each folder's message sentence, as paragraphs
  std::vector<IndexComparison> comparisons;
};

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

// The folders directly in `dir` that a run started and did not finish (config.json without
// summary.json: killed, or running), and how many of them hold a checkpoint to resume from.
std::pair<std::size_t, std::size_t> unfinished_run_folders(const fs::path& dir) {
  std::size_t unfinished = 0, resumable = 0;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir)) {
    std::error_code error;
    if (!entry.is_directory(error) || fs::exists(entry.path() / kSummaryFile, error)) continue;
    if (!fs::exists(entry.path() / kConfigFile, error)) continue;
    ++unfinished;
    resumable += fs::exists(entry.path() / kCheckpointFile, error) ? 1 : 0;
  }
  return {unfinished, resumable};
}

// "15 run folders" and, when there are any, the unfinished ones that are not shown.
std::string run_folders_text(std::size_t shown, std::pair<std::size_t, std::size_t> unfinished) {
  std::string out = std::to_string(shown) + " run folders";
  if (unfinished.first == 0) return out;
  return out + " (and " + std::to_string(unfinished.first) +
         " unfinished, not shown: config.json without summary.json, killed or still running; " +
         std::to_string(unfinished.second) + " of them with a checkpoint, resumable with "
         "`physgrad resume FOLDER`)";
}

constexpr const char* kCompareText =
    "Every run of every folder (each label and seed, and each setting of a label), from its "
    "metrics.csv: pick the runs and the metric to overlay, click a legend entry to hide a run, "
    "drag a box or turn the wheel to zoom (double-click resets), read every shown run's value "
    "at the pointer, switch the y axis to log and the x axis to seconds, smooth (EMA, as "
    "TensorBoard), and download the shown curves as CSV. Each run is thinned to at most 2000 "
    "points (every k-th row, the first and last kept).";

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

// The folder's rows of the table of every run.
HtmlTable every_run_rows(const HtmlTable& header, const IndexedFolder& folder) {
  HtmlTable table{header.header, {}, "", {}};
  const auto cell = [](const Spread& s) { return with_digits(s.median, digits_for(s)); };
  for (const EveryRunRow& row : folder.rows) {
    table.rows.push_back({folder.name, folder.experiment, row.label, row.setting,
                          std::to_string(row.runs), cell(row.loss), cell(row.test_loss),
                          cell(row.iterations), row.ended, cell(row.seconds)});
    table.links.push_back(std::vector<std::string>(table.header.size()));
    if (folder.has_report) table.links.back()[0] = folder.name + "/report.html";
  }
  return table;
}

// The index's name in `dir`: index.html, or index-2.html, … when a run folder (or anything but
// a regular file) has that name.
std::string index_page_name(const fs::path& dir) {
  std::error_code error;
  std::string name = "index.html";
  for (int k = 2; fs::exists(dir / name, error) && !fs::is_regular_file(dir / name, error); ++k) {
    name = "index-" + std::to_string(k) + ".html";
  }
  return name;
}

// Everything the page holds while the folders are read.
struct IndexPage {
  IndexPage(const Registry& known, const fs::path& dir) : registry(known), spool(dir) {}

  const Registry& registry;  // whose experiments' defaults the tables compare with
  PageSpool spool;
  PageSpool::Part notes, warnings, every_run, commands, compare_data;
  std::string first_note;  // named in the error when no folder can be shown
  std::size_t shown = 0, overlaid = 0;  // folders shown; comparisons with overlays
  std::pair<std::size_t, std::size_t> unfinished{};  // folders unfinished; of them, resumable
  std::vector<ExperimentSection> experiments;
  HtmlTable every_run_header = every_run_table();

  void note(const std::string& text) {
    if (first_note.empty()) first_note = text;
    spool.append(notes, html_paragraphs(text));
    spool.append(warnings, "physgrad: warning: report: " + one_line(text) + "\n");
  }

  ExperimentSection& section_of(const std::string& experiment) {
    auto e = std::find_if(experiments.begin(), experiments.end(),
                          [&](const ExperimentSection& s) { return s.name == experiment; });
    if (e == experiments.end()) {
      e = experiments.insert(experiments.end(),
                             {experiment, default_settings(registry, experiment), {}, {}});
    }
    return *e;
  }

  // The comparison of the folder's experiment by its message metric (made when new); null when
  // `make` is false and there is none yet.
  IndexComparison* comparison_of(const IndexedFolder& folder, bool make) {
    ExperimentSection& e = section_of(folder.experiment);
    auto c = std::find_if(e.comparisons.begin(), e.comparisons.end(),
                          [&](const IndexComparison& x) { return x.compares(folder); });
    if (c != e.comparisons.end()) return &*c;
    if (!make) return nullptr;
    e.comparisons.push_back(new_index_comparison(folder, overlaid < kIndexOverlaidComparisons));
    if (e.comparisons.back().overlays) ++overlaid;
    return &e.comparisons.back();
  }

  // Whether the folder's curves are still wanted: its comparison overlays fewer folders than it
  // may (or is new and may overlay).
  bool draws(const IndexedFolder& folder) {
    const IndexComparison* c = comparison_of(folder, false);
    return c ? c->wants_curves() : overlaid < kIndexOverlaidComparisons;
  }

  void add(const IndexedFolder& folder) {
    ++shown;
    ExperimentSection& e = section_of(folder.experiment);
    if (!folder.message.sentence.empty()) {
      spool.append(e.sentences, html_paragraphs(folder.name + ": " + folder.message.sentence));
    }
    IndexComparison& c = *comparison_of(folder, true);
    spool.append(c.rows, html_table_rows(index_comparison_rows(c, folder, e.defaults),
                                         "section '" + folder.experiment + "'"));
    overlay_index_curves(c, folder);
    spool.append(every_run, html_table_rows(every_run_rows(every_run_header, folder),
                                            "section 'Every run'"));
    if (!folder.command.empty()) {
      spool.append(commands, html_paragraphs(folder.name + ": " + folder.command));
    }
  }

  // The folder's runs in the interactive comparison (metrics.csv, at most 32 MiB).
  void add_compare_data(const IndexedFolder& folder, const fs::path& path) {
    std::vector<std::string> left_out;
    std::string runs;
    const fs::path file = path / "metrics.csv";
    std::error_code error;
    try {
      if (fs::exists(fs::symlink_status(file, error))) {
        runs = compare_runs_json(folder.name + " (" + folder.experiment + ")",
                                 read_regular_file(file, std::size_t{32} << 20), left_out);
      }
    } catch (const Error& e) {
      left_out.push_back(in_quotes(file.string()) + ": " + e.what() +
                         "; not in the interactive comparison");
    }
    if (!runs.empty()) spool.append(compare_data, (compare_data.empty() ? "" : ",") + runs);
    for (const std::string& text : left_out) {
      note(text.rfind(in_quotes(file.string()), 0) == 0 ? text
                                                        : in_quotes(file.string()) + ": " + text);
    }
  }

  // The page, part by part: the notes, per experiment its sentences and per metric its table
  // and overlays, the table of every run and the commands.
  void write(const ContentSink& sink, const fs::path& dir) {
    const auto copy = [&](const PageSpool::Part& part) { spool.copy(part, sink); };
    sink(html_page_open("Runs in " + dir.string() + " — physgrad",
                        run_folders_text(shown, unfinished) +
                            (notes.empty() ? "."
                                           : "; some of what they hold is left out, as listed "
                                             "below."),
                        compare_csp()));
    std::vector<std::pair<std::string, std::string>> contents;
    if (!notes.empty()) contents.emplace_back("Left out", "Left out");
    for (const ExperimentSection& e : experiments) contents.emplace_back(e.name, e.name);
    if (!compare_data.empty()) {
      contents.emplace_back("Interactive comparison", "Interactive comparison");
    }
    contents.emplace_back("Every run", "Every run");
    contents.emplace_back("Commands", "Commands");
    sink(html_contents(contents));
    if (!notes.empty()) {
      sink(html_section_open({"Left out", "", {}, {}, {}, "Left out"}));
      copy(notes);
      sink(kHtmlSectionClose);
    }
    for (const ExperimentSection& e : experiments) {
      sink(html_section_open({e.name, "", {}, {}, {}, e.name}));
      copy(e.sentences);
      for (const IndexComparison& c : e.comparisons) {
        sink(html_table_open(c.table));
        copy(c.rows);
        sink(kHtmlTableClose);
        sink(html_figures(index_overlays(c, e.name)));
      }
      sink(kHtmlSectionClose);
    }
    if (!compare_data.empty()) {  // folders without metrics.csv have no curves to compare
      sink(compare_section_open("Interactive comparison", kCompareText));
      sink("{\"runs\":[");
      copy(compare_data);
      sink("]}");
      sink(compare_section_close());
    }
    sink(html_section_open({"Every run", "", {}, {}, {}, "Every run"}));
    sink(html_table_open(every_run_header));
    copy(every_run);
    sink(kHtmlTableClose);
    sink(kHtmlSectionClose);
    sink(html_section_open({"Commands", "", {}, {}, {}, "Commands"}));
    copy(commands);
    sink(kHtmlSectionClose);
    sink(kHtmlPageClose);
  }
};

}  // namespace

RunIndex write_run_index(const Registry& experiments, const fs::path& dir,
                         std::ostream& warnings) {
  std::error_code error;
  if (!fs::is_directory(dir, error)) {
    throw Error("report: '" + dir.string() + "' is not a directory");
  }
  IndexPage page(experiments, dir);
  page.unfinished = unfinished_run_folders(dir);
  for (const fs::path& path : run_folder_paths(dir)) {
    std::vector<std::string> notes;
    std::optional<IndexedFolder> folder;
    try {
      folder = read_index_folder(path, notes,
                                 [&](const IndexedFolder& read) { return page.draws(read); });
    } catch (const Error& e) {
      notes.push_back(std::string(e.what()) + "; the folder is left out");
    }
    if (folder) {
      page.add(*folder);
      page.add_compare_data(*folder, path);
    }
    for (const std::string& note : notes) page.note(note);
  }
  if (page.shown == 0) {
    throw Error("report: '" + dir.string() + "' holds no run folder (a folder with summary.json)" +
                (page.first_note.empty() ? "" : " that can be read: " + page.first_note));
  }
  page.spool.copy(page.warnings, [&](std::string_view text) { warnings << text; });
  const std::string name = index_page_name(dir);
  write_file_atomic(dir / name, [&](const ContentSink& sink) { page.write(sink, dir); });
  return {page.shown, dir / name};
}

}  // namespace physgrad::run
