// What the index of run folders (`physgrad report`) keeps of one folder: a digest of bounded
// size whatever the folder holds — per run label the message metric's median and range over the
// runs that count (failed runs, and for a cost such as iterations runs that did not converge,
// counted apart), the rows of the table of every run, and the compared runs' curves.
#pragma once

#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "physgrad/report/line_plot.hpp"
#include "physgrad/report/significant.hpp"

namespace physgrad::run {

// What a folder's experiment said its message is (summary.json "message"); a folder without one
// is compared over every run by its final test loss, or its final loss when no run has a test
// loss.
struct IndexedMessage {
  std::string figure, sentence;
  std::string metric, metric_text;
  std::vector<std::string> labels;  // the runs compared; empty: every run
  bool compares(const std::string& label) const;
};

// The runs of one compared label: the metric over those that count, how many failed (ended on
// a non-finite value, a failure or divergence) and how many did not reach what a cost metric
// counts (iterations, simulator passes of a direct run that did not converge).
struct ComparedGroup {
  std::string label, rule;
  std::size_t runs = 0, failed = 0, unreached = 0;
  std::size_t unswitched = 0;  // pretrained runs whose rule never took over: Adam's runs
  std::size_t diverging = 0;   // of a cost metric: unconverged runs that ended above their start
  Spread metric, seconds;
  std::string ended;         // the distinct terminations, in the order first seen
  long long switched_at = -1;  // a pretrained run's last Adam iteration, when it switched
  bool ranked() const {
    return failed == 0 && unreached == 0 && unswitched == 0 && diverging == 0 && metric.count > 0;
  }
};

// A row of the table of every run: the runs of one label and setting, medians over them.
struct EveryRunRow {
  std::string label, setting;
  std::size_t runs = 0;
  Spread loss, test_loss, iterations, seconds;
  std::string ended;
};

// How the index draws a folder's compared runs: y against x (columns of metrics.csv).
struct IndexAxes {
  std::string x, x_text, y, y_text;
  bool log_x = false;
};

struct IndexedFolder {
  std::string name;  // as listed: any bytes but '/' and NUL
  std::string experiment;
  // Training runs (by updates and time: a run with epochs, times per part or a test loss), else
  // direct optimization.
  bool learning = false;
  IndexedMessage message;
  std::string command;
  // config.json's "settings" (empty when its text is longer than kIndexMaxSettingsBytes).
  nlohmann::json settings = nlohmann::json::object();
  std::vector<ComparedGroup> compared;  // in the order the labels first appear
  std::vector<EveryRunRow> rows;
  std::string first_setting;  // direct runs: the setting whose curves are drawn ("alpha = 1")
  // Per axes (learning: by updates, then by time; direct: one), a median curve per compared
  // label (at most 300 points, median and band over seeds).
  std::vector<std::pair<IndexAxes, std::vector<Series>>> curves;
  bool has_report = false;
};

// Bounds of what is read and kept of one folder; the index says what it leaves out.
inline constexpr std::size_t kIndexMaxRuns = 10000;    // runs of one summary.json
inline constexpr std::size_t kIndexMaxRows = 100;      // rows of the every-run table
inline constexpr std::size_t kIndexMaxCompared = 64;   // compared labels
inline constexpr std::size_t kIndexMaxCurves = 256;    // (label, seed) curves of one metrics.csv
inline constexpr std::size_t kIndexMaxSettingsBytes = 16384;  // config.json's settings, as text
// Texts kept (in bytes, cut at a character with "…"): names, labels, settings, metric texts; a
// message sentence and a command.
inline constexpr std::size_t kIndexMaxName = 300, kIndexMaxSentence = 2000;

// Reads the run folder at `path` (its summary.json, config.json, and, when `draw` says so for
// the folder read so far, metrics.csv), adding what it cuts short to `notes`. Throws Error naming
// the file (and field) when its summary.json or config.json cannot be shown; a metrics.csv that
// cannot be read leaves out the folder's curves only.
IndexedFolder read_index_folder(const std::filesystem::path& path, std::vector<std::string>& notes,
                                const std::function<bool(const IndexedFolder&)>& draw);

// The steps of read_index_folder (run_index_summary.cpp). A run of a summary.json as the index
// reads it, dropped once the folder is summarized.
struct IndexedRun {
  std::string label, rule;
  nlohmann::json params;
  double loss, test_loss, iterations, seconds, metric;  // NaN when absent
  std::string termination;
  bool learning;
  double initial_loss = NAN;  // the loss at the start (NaN when absent)
};
// The experiment, message and runs (the first kIndexMaxRuns) of a summary.json; Error naming
// the field that is not of its type.
std::vector<IndexedRun> read_index_summary(const nlohmann::json& summary, IndexedFolder& folder,
                                           std::vector<std::string>& notes,
                                           const std::filesystem::path& file);
// The command and settings of a config.json (settings longer than kIndexMaxSettingsBytes noted
// and left out).
void read_index_config(const nlohmann::json& config, IndexedFolder& folder,
                       std::vector<std::string>& notes, const std::filesystem::path& file);
// The rows of the table of every run: per label and setting (the params that vary among the
// label's runs, seeds aside), in the order first seen, at most kIndexMaxRows.
void add_index_rows(IndexedFolder& folder, const std::vector<IndexedRun>& runs,
                    std::vector<std::string>& notes, const std::filesystem::path& file);
// The compared labels: the metric over the runs that count, the failed and unreached apart.
void add_index_compared(IndexedFolder& folder, const std::vector<IndexedRun>& runs,
                        std::vector<std::string>& notes, const std::filesystem::path& file);
// The keys of the runs' params (seed aside) whose values differ among them — with `in_every`
// only keys every run has, else also a key some runs lack — in the order they first appear.
std::vector<std::string> index_varying_keys(const std::vector<const IndexedRun*>& runs,
                                            bool in_every);
// "alpha = 10, problem = fpu": the run's values of `keys`.
std::string index_setting(const IndexedRun& run, const std::vector<std::string>& keys);
// True for a metric that counts the cost of reaching the tolerance (iterations, simulator
// passes): a direct run that did not converge has none.
bool is_cost_metric(const std::string& metric);

// A JSON value as a cell shows it: text as it is, a number as format_number() writes it.
std::string index_text(const nlohmann::json& value);
// `text` cut to at most `bytes` bytes at a character's start, "…" added where it was cut.
std::string index_clipped(std::string text, std::size_t bytes);

}  // namespace physgrad::run
