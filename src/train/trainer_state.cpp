// TrainerState ↔ JSON for checkpoints.
#include <cmath>
#include <utility>

#include "physgrad/error.hpp"
#include "physgrad/io/serialize.hpp"
#include "physgrad/train/trainer.hpp"

namespace physgrad {

namespace {

// NaN (a test loss without a test set) is written as null.
nlohmann::json finite_or_null(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nullptr;
}

nlohmann::json record_to_json(const TrainingRecord& r) {
  return {{"iteration", r.iteration},         {"epoch", r.epoch},
          {"train_seconds", r.train_seconds}, {"train_loss", finite_or_null(r.train_loss)},
          {"test_loss", finite_or_null(r.test_loss)}, {"extras", r.extras},
          {"step", r.step}};
}

TrainingRecord record_from_json(const nlohmann::json& document) {
  TrainingRecord r;
  r.iteration = integer_from_json(document, "iteration");
  r.epoch = real_from_json(document, "epoch");
  r.train_seconds = real_from_json(document, "train_seconds");
  r.train_loss = real_from_json(document, "train_loss");
  r.test_loss = real_from_json(document, "test_loss", true);
  r.extras = object_from_json(document, "extras");
  if (document.contains("step")) r.step = object_from_json(document, "step");
  return r;
}

nlohmann::json counts_to_json(const SimulatorCounts& counts) {
  nlohmann::json out = nlohmann::json::object();
  for (const auto& [name, field] : SimulatorCounts::fields()) out[name] = counts.*field;
  return out;
}

SimulatorCounts counts_from_json(const nlohmann::json& document) {
  if (!document.is_object()) throw Error("checkpoint field 'counts': expected an object");
  SimulatorCounts counts;
  for (const auto& [name, field] : SimulatorCounts::fields()) {
    counts.*field = integer_from_json(document, name);  // ≥ 0
  }
  return counts;
}

nlohmann::json phases_to_json(const std::vector<TrainingSummary::Phase>& phases) {
  nlohmann::json out = nlohmann::json::array();
  for (const TrainingSummary::Phase& phase : phases) {
    out.push_back({{"first_iteration", phase.first_iteration},
                   {"batch_size", phase.batch_size},
                   {"probes", phase.probes},
                   {"reference_cpu_seconds", phase.reference_cpu_seconds},
                   {"timed_steps", phase.timed_steps},
                   {"step_cpu_seconds", phase.step_cpu_seconds}});
  }
  return out;
}

// Each part's first iteration and batch size (checked against the run by train() on resuming).
std::vector<TrainingSummary::Phase> phases_from_json(const nlohmann::json& document) {
  if (!document.is_array()) throw Error("checkpoint field 'phases': expected an array");
  std::vector<TrainingSummary::Phase> phases;
  for (const nlohmann::json& entry : document) {
    TrainingSummary::Phase phase{integer_from_json(entry, "first_iteration"),
                                 static_cast<Index>(integer_from_json(entry, "batch_size", 1))};
    // Absent from files of earlier versions, which made no cost probes; those that did timed
    // the rule's steps at the probes alone ("probed_step_cpu_seconds").
    if (entry.contains("probes")) {
      phase.probes = integer_from_json(entry, "probes");
      phase.reference_cpu_seconds = real_from_json(entry, "reference_cpu_seconds");
      const bool every_step = entry.contains("timed_steps");
      phase.timed_steps = every_step ? integer_from_json(entry, "timed_steps") : phase.probes;
      phase.step_cpu_seconds =
          real_from_json(entry, every_step ? "step_cpu_seconds" : "probed_step_cpu_seconds");
    }
    phases.push_back(phase);
  }
  return phases;
}

}  // namespace

nlohmann::json training_summary_to_json(const TrainingSummary& s) {
  nlohmann::json history = nlohmann::json::array();
  for (const TrainingRecord& r : s.history) history.push_back(record_to_json(r));
  return {{"history", history},
          {"termination", s.termination ? nlohmann::json(to_string(*s.termination))
                                        : nlohmann::json(nullptr)},
          {"message", s.message},
          {"iterations", s.iterations},
          {"train_seconds", s.train_seconds},
          {"wall_seconds", s.wall_seconds},
          {"forward_seconds", s.forward_seconds},
          {"derivative_seconds", s.derivative_seconds},
          {"inversion_seconds", s.inversion_seconds},
          {"update_seconds", s.update_seconds},
          {"step_halvings", s.step_halvings},
          {"counts", counts_to_json(s.counts)},
          {"phases", phases_to_json(s.phases)}};
}

TrainingSummary training_summary_from_json(const nlohmann::json& document) {
  TrainingSummary summary;
  // null (or "", as files of earlier versions have it) while the run is in progress.
  if (!document.contains("termination") ||
      !(document.at("termination").is_null() || document.at("termination").is_string())) {
    throw Error("checkpoint field 'termination': expected a text or null");
  }
  const nlohmann::json& termination = document.at("termination");
  if (termination.is_string() && !termination.get<std::string>().empty()) {
    try {
      summary.termination = parse_training_termination(termination.get<std::string>());
    } catch (const Error& e) {
      throw Error(std::string("checkpoint field 'termination': ") + e.what());
    }
  }
  summary.message = string_from_json(document, "message");
  summary.iterations = integer_from_json(document, "iterations");
  const std::pair<const char*, double*> times[] = {
      {"train_seconds", &summary.train_seconds},
      {"forward_seconds", &summary.forward_seconds},
      {"derivative_seconds", &summary.derivative_seconds},
      {"inversion_seconds", &summary.inversion_seconds},
      {"update_seconds", &summary.update_seconds}};
  for (const auto& [key, time] : times) {
    *time = real_from_json(document, key);
    if (!(*time >= 0) || !std::isfinite(*time)) {
      throw Error(std::string("checkpoint field '") + key + "': must be a finite time ≥ 0");
    }
  }
  // Absent from files of earlier versions: their runs counted training time alone.
  summary.wall_seconds = summary.train_seconds;
  if (document.contains("wall_seconds")) {
    summary.wall_seconds = real_from_json(document, "wall_seconds");
    if (!(summary.wall_seconds >= 0) || !std::isfinite(summary.wall_seconds)) {
      throw Error("checkpoint field 'wall_seconds': must be a finite time ≥ 0");
    }
  }
  summary.step_halvings = integer_from_json(document, "step_halvings");
  // Absent from files of earlier versions: the work of the steps before is then not known.
  if (document.contains("counts")) summary.counts = counts_from_json(document.at("counts"));
  // Absent from files of earlier versions, whose runs had one part.
  if (document.contains("phases")) summary.phases = phases_from_json(document.at("phases"));
  if (!document.contains("history") || !document.at("history").is_array() ||
      document.at("history").empty()) {
    throw Error("checkpoint field 'history': expected a non-empty array of records");
  }
  long long previous = -1;
  for (const nlohmann::json& entry : document.at("history")) {
    TrainingRecord record = record_from_json(entry);
    if (record.iteration < previous || record.iteration > summary.iterations ||
        !std::isfinite(record.train_loss)) {
      throw Error("checkpoint field 'history': record at iteration " +
                  std::to_string(record.iteration) + " is out of order or not finite");
    }
    previous = record.iteration;
    summary.history.push_back(std::move(record));
  }
  return summary;
}

nlohmann::json trainer_state_to_json(const TrainerState& state) {
  return {{"epoch", state.epoch},
          {"batch_start", state.batch_start},
          {"parameters", vector_to_json(state.parameters)},
          {"last_step", vector_to_json(state.last_step)},
          {"before_last_step", vector_to_json(state.before_last_step)},
          {"last_evaluated", vector_to_json(state.last_evaluated)},
          {"update_state", state.update_state},
          {"summary", training_summary_to_json(state.summary)}};
}

TrainerState trainer_state_from_json(const nlohmann::json& document, Index parameter_count) {
  TrainerState state;
  state.epoch = integer_from_json(document, "epoch");
  state.batch_start = integer_from_json(document, "batch_start");
  state.parameters = vector_from_json(document, "parameters", parameter_count);
  const Index steps = vector_from_json(document, "last_step").size() == 0 ? 0 : parameter_count;
  state.last_step = vector_from_json(document, "last_step", steps);
  state.before_last_step = vector_from_json(document, "before_last_step", steps);
  state.last_evaluated = vector_from_json(document, "last_evaluated", parameter_count);
  if (!document.is_object() || !document.contains("update_state")) {
    throw Error("checkpoint field 'update_state': missing");
  }
  state.update_state = document.at("update_state");
  state.summary = training_summary_from_json(object_from_json(document, "summary"));
  if (state.summary.termination) {
    throw Error("checkpoint field 'termination': a state to resume belongs to a run in progress");
  }
  return state;
}

}  // namespace physgrad
