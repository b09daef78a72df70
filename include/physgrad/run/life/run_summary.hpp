// Run summary — summary.json, how each run of an experiment ended, as one typed RunSummary with
// one writer (run_summary_json) and one reader (read_run_summary): document = write(read(document)).
#pragma once

#include <cstddef>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace physgrad::run {

inline constexpr const char* kSummaryFile = "summary.json";

// A run's figures at its start ("initial") or end ("final"): the loss, a learning run's test loss
// (NaN: not evaluated, written null) and the experiment's further figures by name (a learning
// run's extras; a direct run's iterate "x" and its simulator counts).
struct RunFigures {
  double loss = std::numeric_limits<double>::quiet_NaN();
  std::optional<double> test_loss;
  nlohmann::json more = nlohmann::json::object();
};

// A learning run's training seconds by part of the step.
struct SecondsPerPart {
  double forward = 0, derivatives = 0, inversion = 0, update = 0;
};

// One run of summary.json's "runs": the rule and its settings, how it started and ended. The
// optional members are a learning run's; a direct run writes "epochs": null.
struct RunEntry {
  std::string label;
  std::string optimizer;  // the rule's id
  nlohmann::json params = nlohmann::json::object();
  RunFigures initial, final;
  long long iterations = 0;
  std::optional<double> epochs;       // epochs made (fractional)
  double wall_seconds = 0;            // a learning run's training seconds, evaluations excluded
  std::optional<double> run_seconds;  // evaluations and checkpoints included
  std::string termination;            // Termination or TrainingTermination as text
  std::string message;
  std::optional<long long> step_halvings;
  std::optional<SecondsPerPart> seconds_per_part;
  // Keys of a newer writer, kept as read; and a learning twin's "phases" (its training seconds
  // per part, written by the learning runs: [{"rule", "updates", "train_seconds",
  // "seconds_per_update"}, …]).
  nlohmann::json more = nlohmann::json::object();

  // The number `key` names: final's figure of that name, else the run's own ("iterations",
  // "wall_seconds", …); NaN when neither is a number.
  double figure(const std::string& key) const;
};

// The experiment's message (RunContext::set_message): the figure that shows it, its sentence,
// the metric it compares (a key of RunEntry::figure), what that is, the runs compared.
struct RunMessage {
  std::string figure, sentence, metric, metric_text;
  std::vector<std::string> labels;
};

struct RunSummary {
  std::string experiment;
  std::vector<RunEntry> runs;
  std::optional<RunMessage> message;
  nlohmann::json machine;  // run_machine()'s document; null when the file has none
};

// The field `key` of a JSON object when it has type `is_type` (nullptr when absent or null); an
// Error "WHEREKEY is a number, not text" (`type` the expected type's words) when it has another.
// The one typed read of the run folder's JSON files (summary.json here, config.json by the index).
const nlohmann::json* typed_json_field(const nlohmann::json& object, const char* key,
                                       const std::string& where,
                                       bool (nlohmann::json::*is_type)() const noexcept,
                                       const char* type);
// "a number", "an array", … of a JSON value, for such messages.
std::string json_type_words(const nlohmann::json& value);

// The summary.json document {"experiment", "runs": [...], "machine", "message"}.
nlohmann::json run_summary_json(const RunSummary& summary);
nlohmann::json run_entry_json(const RunEntry& entry);

// Reads a summary.json document, at most `max_runs` of its runs. Files of every version read:
// an absent or null field takes its default (empty text, NaN, none). Throws Error naming the
// field that has another type ("runs[2].final.loss is a string, not a number"), or "has no list
// of runs".
RunSummary read_run_summary(const nlohmann::json& document,
                            std::size_t max_runs = std::numeric_limits<std::size_t>::max());

}  // namespace physgrad::run
