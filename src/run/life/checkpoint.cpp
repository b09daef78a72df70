#include "physgrad/run/life/checkpoint.hpp"

#include "physgrad/error.hpp"
#include "physgrad/io/serialize.hpp"
#include "physgrad/io/checkpoint_file.hpp"
#include "physgrad/run/life/run_folder.hpp"
#include "fault_point.hpp"

namespace physgrad::run {

nlohmann::json RunKey::json() const {
  return {{"index", index}, {"optimizer", optimizer}, {"tag", tag}, {"seed", seed}};
}

std::string RunKey::describe() const {
  return "run " + std::to_string(index) + " (" + optimizer + ", " + tag + ", seed " +
         std::to_string(seed) + ")";
}

namespace {

RunKey key_from_json(const nlohmann::json& document) {
  const nlohmann::json& key = object_from_json(document, "key");
  return {integer_from_json(key, "index"), string_from_json(key, "optimizer"),
          string_from_json(key, "tag"), integer_from_json(key, "seed")};
}

// True when `entry` is the saved run at key.index; Error when that run is another one.
bool is_run(const nlohmann::json& entry, const RunKey& key) {
  const RunKey saved = key_from_json(entry);
  if (saved.index != key.index) return false;
  if (saved.json() != key.json()) {
    throw Error("the checkpoint does not match this experiment: it has " + saved.describe() +
                " where the experiment runs " + key.describe());
  }
  return true;
}

}  // namespace

ExperimentCheckpoint::ExperimentCheckpoint(const FolderHandle* folder, nlohmann::json config,
                                           nlohmann::json resumed)
    : folder_(folder), config_(std::move(config)) {
  if (resumed.is_null()) return;
  const std::string experiment = string_from_json(resumed, "experiment");
  if (experiment != config_.at("experiment").get<std::string>()) {
    throw Error("the checkpoint belongs to experiment '" + experiment + "', config.json to '" +
                config_.at("experiment").get<std::string>() +
                "': config.json was changed after the run started; put back the checkpoint's "
                "experiment");
  }
  const nlohmann::json& settings = object_from_json(resumed, "settings");
  for (const auto& [name, value] : config_.at("settings").items()) {
    if (name != "out" && settings.value(name, nlohmann::json()) != value) {
      throw Error("config.json and the checkpoint disagree on --" + name + " (" + value.dump() +
                  " vs " + settings.value(name, nlohmann::json()).dump() +
                  "): config.json was changed after the run started; put back the checkpoint's "
                  "value");
    }
  }
  if (!resumed.contains("finished") || !resumed.at("finished").is_array()) {
    throw Error("checkpoint field 'finished': expected an array of runs");
  }
  finished_ = resumed.at("finished");
  for (std::size_t i = 0; i < finished_.size(); ++i) {
    if (key_from_json(finished_[i]).index != static_cast<long long>(i)) {
      throw Error("checkpoint field 'finished': run " + std::to_string(i) + " is out of order");
    }
  }
  resumed_current_ = resumed.value("current", nlohmann::json());
  resumed_environment_ = resumed.value("environment", nlohmann::json::object());
  written_ = true;  // the resumed checkpoint file exists
}

std::optional<FinishedRun> ExperimentCheckpoint::finished(const RunKey& key,
                                                          Index parameter_count) const {
  // finished_[i] is run i (checked when the checkpoint was read).
  if (key.index < 0 || key.index >= static_cast<long long>(finished_.size())) return std::nullopt;
  const nlohmann::json& entry = finished_[static_cast<std::size_t>(key.index)];
  if (!is_run(entry, key)) return std::nullopt;
  FinishedRun run{training_summary_from_json(object_from_json(entry, "summary")),
                  vector_from_json(entry, "parameters", parameter_count)};
  if (!run.summary.termination ||
      *run.summary.termination == TrainingTermination::kInterrupted) {
    throw Error("checkpoint: " + key.describe() + " is listed as finished but has termination '" +
                (run.summary.termination ? to_string(*run.summary.termination) : "") + "'");
  }
  return run;
}

std::optional<TrainerState> ExperimentCheckpoint::in_progress(const RunKey& key,
                                                              Index parameter_count) const {
  if (resumed_current_.is_null() || !is_run(resumed_current_, key)) return std::nullopt;
  return trainer_state_from_json(object_from_json(resumed_current_, "state"), parameter_count);
}

std::string ExperimentCheckpoint::set_environment(nlohmann::json environment) {
  environment_ = std::move(environment);
  std::string differences;
  if (!resumed_environment_.is_object()) return differences;
  for (const auto& [key, value] : environment_.items()) {
    const auto saved = resumed_environment_.find(key);
    if (saved == resumed_environment_.end() || *saved == value) continue;
    differences += (differences.empty() ? "" : ", ") + key + " " + saved->dump() + " (now " +
                   value.dump() + ")";
  }
  return differences;
}

void ExperimentCheckpoint::record_finished(const RunKey& key, const TrainingSummary& summary,
                                           const Vector& theta) {
  finished_.push_back({{"key", key.json()},
                       {"summary", training_summary_to_json(summary)},
                       {"parameters", vector_to_json(theta)}});
  write(nullptr);
}

void ExperimentCheckpoint::save_progress(const RunKey& key, const TrainerState& state) {
  write({{"key", key.json()}, {"state", trainer_state_to_json(state)}});
}

void ExperimentCheckpoint::write(const nlohmann::json& current) {
  if (folder_ == nullptr) return;
  write_checkpoint_file(*folder_, kCheckpointFile,
                        {{"experiment", config_.at("experiment")},
                         {"settings", config_.at("settings")},
                         {"environment", environment_},
                         {"finished", finished_},
                         {"current", current}});
  written_ = true;
  fault_point("checkpoint");
}

}  // namespace physgrad::run
