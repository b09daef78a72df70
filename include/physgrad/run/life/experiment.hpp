// Experiment framework — a reference experiment declares its options and runs into a
// RunContext, which collects metrics, per-run summaries, figures and tables for the run folder.
#pragma once

#include <atomic>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "physgrad/catalogue.hpp"
#include "physgrad/parallel/communicator.hpp"
#include "physgrad/types.hpp"
#include "physgrad/run/life/run_summary.hpp"

namespace physgrad::run {

class ExperimentCheckpoint;
class Settings;

// One command-line option of an experiment. Values are parsed and validated by parse_option(),
// so every bad value gets the same kind of one-line error naming the option and the value.
struct OptionSpec {
  enum class Kind { kReal, kInteger, kText, kRealList, kTextList };
  std::string name;          // "lr" is given as --lr
  Kind kind = Kind::kReal;
  std::string default_text;  // as typed on the command line; empty = unset (optional)
  std::string help;
  double min = -std::numeric_limits<double>::infinity();  // numeric bounds, inclusive unless
  double max = std::numeric_limits<double>::infinity();   // min_exclusive / max_exclusive
  bool min_exclusive = false;
  bool max_exclusive = false;
  bool nonzero = false;              // numeric: 0 is not allowed
  std::vector<std::string> choices;  // allowed texts (text kinds); empty = any
  // Lists: each entry is a setting of its own, named in labels, tables and file names, so no two
  // may be equal or read the same there (format_value). Off for the coordinates of one point.
  bool distinct = true;
  // Integers that count items (samples): the bytes each needs at least, for the settings given.
  // A value whose items do not fit in the memory this process may use is refused before
  // anything is allocated.
  std::function<double(const Settings&)> bytes_each;
  // The value a quick check of the whole experiment uses (tests): its sizes and limits made
  // tiny. Empty: the default.
  std::string quick_text;

  // Chainable constraints: real_option("lr", "0.1", "step size").above(0).
  OptionSpec& above(double bound) { min = bound; min_exclusive = true; return *this; }
  OptionSpec& at_least(double bound) { min = bound; min_exclusive = false; return *this; }
  OptionSpec& at_most(double bound) { max = bound; max_exclusive = false; return *this; }
  OptionSpec& below(double bound) { max = bound; max_exclusive = true; return *this; }
  OptionSpec& not_zero() { nonzero = true; return *this; }
  OptionSpec& one_of(std::vector<std::string> allowed) { choices = std::move(allowed); return *this; }
  OptionSpec& coordinates() { distinct = false; return *this; }
  OptionSpec& needs_bytes_each(std::function<double(const Settings&)> bytes) {
    bytes_each = std::move(bytes);
    return *this;
  }
  OptionSpec& quick(std::string text) { quick_text = std::move(text); return *this; }

  std::string flag() const { return "--" + name; }  // as messages name the option
};

OptionSpec real_option(std::string name, std::string default_text, std::string help);
OptionSpec integer_option(std::string name, std::string default_text, std::string help);
OptionSpec text_option(std::string name, std::string default_text, std::string help);
OptionSpec real_list_option(std::string name, std::string default_text, std::string help);
OptionSpec text_list_option(std::string name, std::string default_text, std::string help);

// Parses `text` for `spec` into JSON (number, integer, string or array): the one parser of the
// command line and of config files. Numbers are decimal: an optional sign (+ or −), digits, and
// for reals a point and an exponent (16, -2.5, +1e-3, .5); hexadecimal, inf and nan are not
// numbers. Throws Error such as "--lr: 'abc' is not a number (…)" or "--iters: must be ≥ 1,
// got 0".
nlohmann::json parse_option(const OptionSpec& spec, const std::string& text);
// "a range like ≥ 1" for help texts; empty when unbounded.
std::string describe_range(const OptionSpec& spec);

// The command line's option for every rule that has rule option `name` (--lr, --rcond,
// --decay-every for decay_every): unset by default,
// so each rule keeps its own; its range (the one all those rules take) and its help come from
// the rules' option descriptions (shared_rule_option in catalogue.hpp). `offered`: the rule ids
// the experiment runs, named in the help; `kind`: which rules' range counts (none: every rule).
OptionSpec rule_option_spec(const std::string& name, std::optional<RuleKind> kind,
                            const std::vector<std::string>& offered);

// An option `name` taking the values of `range` (a real, an integer or one of its names), unset by
// default.
OptionSpec option_in_range(std::string name, const OptionRange& range, std::string help);

// The command line's name of rule option `rule_option`: "decay_every" is --decay-every.
std::string flag_name(std::string rule_option);

// The settings of a run that name a rule option (those rule_option_spec declared), as the
// rules take them; each rule ignores those it has not.
RuleSettings rule_settings(const Settings& settings, RuleKind kind);

// The resolved settings of a run: option name → parsed value (null when unset).
class Settings {
 public:
  explicit Settings(nlohmann::json values) : values_(std::move(values)) {}
  const nlohmann::json& json() const { return values_; }
  bool has(const std::string& name) const;
  double real(const std::string& name) const;
  long long integer(const std::string& name) const;
  std::string text(const std::string& name) const;
  std::vector<double> reals(const std::string& name) const;
  std::vector<std::string> texts(const std::string& name) const;

 private:
  const nlohmann::json& at(const std::string& name) const;
  nlohmann::json values_;
};

// The quantity a message compares, lower being better: `key` names a number of each run's
// summary entry ("final"'s keys first, then the entry's own, e.g. "iterations") and, where
// it is one, a column of metrics.csv; `text` says what it is ("final test loss"); `labels`
// are the runs compared (empty: every run). The index of run folders compares folders by it.
struct MessageMetric {
  std::string key;
  std::string text;
  std::vector<std::string> labels{};
};

// Collects what a run produces; Run (run.hpp) turns it into the run folder.
class RunContext {
 public:
  struct Figure {
    std::string file;  // e.g. "loss.svg"
    std::string caption;
    std::string svg;
    // Consecutive figures of one row (e.g. one setting's) share a row of the report.
    std::string row{};
  };
  struct Table {
    std::string title;
    std::vector<std::string> header;
    std::vector<std::vector<std::string>> rows;
  };

  // Metrics: one row per run × evaluation; columns are the union of all keys in first-seen
  // order (label, optimizer and iteration first).
  void add_metrics_row(nlohmann::json row);
  // A run's entry of summary.json (run_summary.hpp).
  void add_run(RunEntry run) { runs_.push_back(std::move(run)); }
  void add_figure(Figure figure) { figures_.push_back(std::move(figure)); }
  void add_table(Table table) { tables_.push_back(std::move(table)); }
  void add_note(std::string text) { notes_.push_back(std::move(text)); }
  // The experiment's point: the figure that shows it (a file of add_figure) and one sentence
  // with the ratio it measures, and the metric the sentence compares (none: an empty key).
  // report.html shows this figure first, the sentence under it; summary.json keeps all three.
  void set_message(std::string figure_file, std::string sentence, MessageMetric metric = {}) {
    message_figure_ = std::move(figure_file);
    message_ = std::move(sentence);
    message_metric_ = std::move(metric);
  }
  const std::string& message_figure() const { return message_figure_; }
  const std::string& message() const { return message_; }
  const MessageMetric& message_metric() const { return message_metric_; }
  // A trained network {"label", "seed", "network" (its describe()), "parameters"} for
  // networks.json.
  void add_network(nlohmann::json network) { networks_.push_back(std::move(network)); }
  // A progress line, handed to the function set_progress() gave (none: the run is silent).
  void progress(const std::string& line);
  // The progress lines of one sweep have ended.
  void finish_progress();
  // A line that stays (a run started or finished), handed to set_progress()'s `event`.
  void progress_event(const std::string& line);
  // The learning runs of the whole experiment, however many sweeps make them: how many are
  // planned (0: not known yet), how many finished, and when the first started (steady-clock
  // seconds; negative before).
  struct RunPlan {
    long long runs = 0, finished = 0;
    double started = -1;
    std::string announcement;  // the start line, printed when the first run starts training
  };
  RunPlan& run_plan() { return run_plan_; }

  const std::vector<nlohmann::json>& metrics() const { return metrics_; }
  const std::vector<RunEntry>& runs() const { return runs_; }
  const std::vector<Figure>& figures() const { return figures_; }
  const std::vector<Table>& tables() const { return tables_; }
  const std::vector<std::string>& notes() const { return notes_; }
  const std::vector<nlohmann::json>& networks() const { return networks_; }
  // Where progress lines go: `show` gets each line, `end` is told when a sweep's lines end,
  // `event` gets the lines that stay (none of them: the run is silent).
  void set_progress(std::function<void(const std::string&)> show, std::function<void()> end,
                    std::function<void(const std::string&)> event) {
    show_progress_ = std::move(show);
    end_progress_ = std::move(end);
    show_event_ = std::move(event);
  }
  void set_experiment_name(std::string name) { experiment_name_ = std::move(name); }
  const std::string& experiment_name() const { return experiment_name_; }
  // The ranks that train together (data-parallel learning); none: this process alone.
  void set_communicator(std::shared_ptr<Communicator> communicator) {
    communicator_ = std::move(communicator);
  }
  const std::shared_ptr<Communicator>& communicator() const { return communicator_; }

  // Set by Run (run.hpp): the flag a stop request sets, and where learning runs keep their
  // checkpoint. Both may stay null (no interruption, no checkpoint).
  void set_stop_flag(const std::atomic<bool>* stop) { stop_ = stop; }
  const std::atomic<bool>* stop_flag() const { return stop_; }
  // Throws Interrupted once a stop was requested.
  void check_interrupt() const;
  void set_checkpoint(ExperimentCheckpoint* checkpoint) { checkpoint_ = checkpoint; }
  ExperimentCheckpoint* checkpoint() const { return checkpoint_; }
  // The position of the next learning run in the whole experiment (0, 1, 2, … in the order the
  // runs start, however many sweeps make them): what identifies a run in the checkpoint.
  long long next_learning_run() { return learning_runs_++; }

 private:
  std::vector<nlohmann::json> metrics_;
  std::vector<RunEntry> runs_;
  std::vector<Figure> figures_;
  std::vector<Table> tables_;
  std::vector<std::string> notes_;
  std::string message_figure_, message_;
  MessageMetric message_metric_;
  std::vector<nlohmann::json> networks_;
  std::string experiment_name_;
  const std::atomic<bool>* stop_ = nullptr;
  ExperimentCheckpoint* checkpoint_ = nullptr;
  long long learning_runs_ = 0;
  std::shared_ptr<Communicator> communicator_;
  std::function<void(const std::string&)> show_progress_;
  std::function<void()> end_progress_;
  std::function<void(const std::string&)> show_event_;
  RunPlan run_plan_;
};

class Experiment {
 public:
  virtual ~Experiment() = default;
  virtual std::string name() const = 0;
  virtual std::string description() const = 0;
  // The experiment's own options, after the common ones (optimizers, iters, lr, seed, out).
  virtual std::vector<OptionSpec> options() const = 0;
  // Ids accepted by --optimizers, and the default selection.
  virtual std::vector<std::string> optimizer_choices() const = 0;
  virtual std::vector<std::string> default_optimizers() const = 0;
  // The default of --iters; 0 leaves it unset (for experiments limited by epochs or time).
  virtual long long default_iterations() const = 0;
  // Checks between options that one option alone cannot express; throws Error. Runs before
  // anything is written.
  virtual void validate(const Settings& /*settings*/) const {}
  virtual void run(const Settings& settings, RunContext& context) const = 0;
};

// The options every experiment has, with this experiment's choices and defaults.
std::vector<OptionSpec> common_options(const Experiment& experiment);
// common_options() followed by experiment.options().
std::vector<OptionSpec> all_options(const Experiment& experiment);
// The option `name` of `specs` (all_options(experiment)); throws Error "experiment 'E': unknown
// option 'NAME' (known: …)".
const OptionSpec& find_option(const Experiment& experiment, const std::vector<OptionSpec>& specs,
                              const std::string& name);
// Parses option name → text (missing names take their defaults). Throws Error on bad values
// and on names the experiment does not have.
Settings resolve_settings(const Experiment& experiment,
                          const std::vector<std::pair<std::string, std::string>>& given);

// Compact number formatting for tables and labels: 4 significant digits.
std::string format_value(double value);
// The median of the values that are not NaN (the mean of the middle two for an even count);
// NaN when there are none.
double median(std::vector<double> values);

}  // namespace physgrad::run
