#include "physgrad/run/life/run_summary.hpp"

#include <cmath>

#include "physgrad/error.hpp"

namespace physgrad::run {

namespace {

using nlohmann::json;

std::string summary_text(const json& object, const char* key, const std::string& where) {
  const json* value = typed_json_field(object, key, where, &json::is_string, "text");
  return value ? value->get<std::string>() : std::string();
}

std::optional<double> summary_number(const json& object, const char* key,
                                      const std::string& where) {
  const json* value = typed_json_field(object, key, where, &json::is_number, "a number");
  return value ? std::optional(value->get<double>()) : std::nullopt;
}

double summary_real(const json& object, const char* key, const std::string& where) {
  return summary_number(object, key, where).value_or(NAN);
}

// A count: a whole number (as written: an integer), or none.
std::optional<long long> summary_count(const json& object, const char* key,
                                       const std::string& where) {
  const json* value = typed_json_field(object, key, where, &json::is_number, "a number");
  if (value == nullptr) return std::nullopt;
  if (value->is_number_integer() && !(value->is_number_unsigned() &&
                                      value->get<std::uint64_t>() > std::uint64_t{1} << 62)) {
    return value->get<long long>();
  }
  const double number = value->get<double>();
  if (number == std::floor(number) && std::abs(number) <= 0x1p62) {
    return static_cast<long long>(number);
  }
  throw Error(where + key + " is " + value->dump() + ", not a whole number");
}

const json& summary_object(const json& object, const char* key, const std::string& where) {
  static const json empty = json::object();
  const json* value = typed_json_field(object, key, where, &json::is_object, "an object");
  return value ? *value : empty;
}

json figures_json(const RunFigures& figures) {
  json document = figures.more.is_object() ? figures.more : json::object();
  document["loss"] = figures.loss;
  if (figures.test_loss) document["test_loss"] = *figures.test_loss;
  return document;
}

RunFigures read_figures(const json& document, const std::string& where) {
  RunFigures figures;
  figures.loss = summary_real(document, "loss", where);
  if (document.contains("test_loss")) {
    figures.test_loss = summary_real(document, "test_loss", where);
  }
  for (const auto& [key, value] : document.items()) {
    if (key != "loss" && key != "test_loss") figures.more[key] = value;
  }
  return figures;
}

// The keys of a run entry read_run_entry() reads into members; any other goes to `more`.
bool is_entry_member(const std::string& key) {
  for (const char* member :
       {"label", "optimizer", "params", "initial", "final", "iterations", "epochs",
        "wall_seconds", "run_seconds", "termination", "message", "step_halvings",
        "seconds_per_part"}) {
    if (key == member) return true;
  }
  return false;
}

RunEntry read_run_entry(const json& run, const std::string& where) {
  if (!run.is_object()) throw Error(where + " is " + json_type_words(run) + ", not an object");
  const std::string in = where + ".";
  RunEntry entry;
  entry.label = summary_text(run, "label", in);
  entry.optimizer = summary_text(run, "optimizer", in);
  entry.params = summary_object(run, "params", in);
  entry.initial = read_figures(summary_object(run, "initial", in), in + "initial.");
  entry.final = read_figures(summary_object(run, "final", in), in + "final.");
  entry.iterations = summary_count(run, "iterations", in).value_or(0);
  entry.epochs = summary_number(run, "epochs", in);
  entry.wall_seconds = summary_real(run, "wall_seconds", in);
  entry.run_seconds = summary_number(run, "run_seconds", in);
  entry.termination = summary_text(run, "termination", in);
  entry.message = summary_text(run, "message", in);
  entry.step_halvings = summary_count(run, "step_halvings", in);
  if (typed_json_field(run, "seconds_per_part", in, &json::is_object, "an object") != nullptr) {
    const json& parts = run.at("seconds_per_part");
    const std::string at = in + "seconds_per_part.";
    entry.seconds_per_part = SecondsPerPart{
        summary_real(parts, "forward", at), summary_real(parts, "derivatives", at),
        summary_real(parts, "inversion", at), summary_real(parts, "update", at)};
  }
  for (const auto& [key, value] : run.items()) {
    if (!is_entry_member(key)) entry.more[key] = value;
  }
  return entry;
}

std::optional<RunMessage> read_run_message(const json& document) {
  const json* given = typed_json_field(document, "message", "", &json::is_object, "an object");
  if (given == nullptr) return std::nullopt;
  RunMessage message{summary_text(*given, "figure", "message."),
                     summary_text(*given, "sentence", "message."),
                     summary_text(*given, "metric", "message."),
                     summary_text(*given, "metric_text", "message."),
                     {}};
  if (const json* labels =
          typed_json_field(*given, "labels", "message.", &json::is_array, "an array")) {
    for (const json& label : *labels) {
      if (!label.is_string()) {
        throw Error("message.labels holds " + json_type_words(label) + ", not text");
      }
      message.labels.push_back(label.get<std::string>());
    }
  }
  return message;
}

}  // namespace

double RunEntry::figure(const std::string& key) const {
  if (key == "loss" && !std::isnan(final.loss)) return final.loss;
  if (key == "test_loss" && final.test_loss && !std::isnan(*final.test_loss)) {
    return *final.test_loss;
  }
  if (final.more.is_object()) {
    const auto value = final.more.find(key);
    if (value != final.more.end() && value->is_number()) return value->get<double>();
  }
  if (key == "iterations") return static_cast<double>(iterations);
  if (key == "epochs" && epochs) return *epochs;
  if (key == "wall_seconds") return wall_seconds;
  if (key == "run_seconds" && run_seconds) return *run_seconds;
  if (key == "step_halvings" && step_halvings) return static_cast<double>(*step_halvings);
  const auto value = more.find(key);
  return value != more.end() && value->is_number() ? value->get<double>() : NAN;
}

json run_entry_json(const RunEntry& entry) {
  json document = entry.more.is_object() ? entry.more : json::object();
  document.update(json{{"label", entry.label},
                       {"optimizer", entry.optimizer},
                       {"params", entry.params},
                       {"initial", figures_json(entry.initial)},
                       {"final", figures_json(entry.final)},
                       {"iterations", entry.iterations},
                       {"epochs", entry.epochs ? json(*entry.epochs) : json(nullptr)},
                       {"wall_seconds", entry.wall_seconds},
                       {"termination", entry.termination},
                       {"message", entry.message}});
  if (entry.run_seconds) document["run_seconds"] = *entry.run_seconds;
  if (entry.step_halvings) document["step_halvings"] = *entry.step_halvings;
  if (const std::optional<SecondsPerPart>& s = entry.seconds_per_part) {
    document["seconds_per_part"] = {{"forward", s->forward},
                                    {"derivatives", s->derivatives},
                                    {"inversion", s->inversion},
                                    {"update", s->update}};
  }
  return document;
}

json run_summary_json(const RunSummary& summary) {
  json runs = json::array();
  for (const RunEntry& entry : summary.runs) runs.push_back(run_entry_json(entry));
  json document = {{"experiment", summary.experiment}, {"runs", std::move(runs)}};
  if (!summary.machine.is_null()) document["machine"] = summary.machine;
  if (const std::optional<RunMessage>& m = summary.message) {
    document["message"] = {{"figure", m->figure},
                           {"sentence", m->sentence},
                           {"metric", m->metric},
                           {"metric_text", m->metric_text},
                           {"labels", m->labels}};
  }
  return document;
}

RunSummary read_run_summary(const json& document, std::size_t max_runs) {
  if (!document.is_object() || !document.contains("runs") || !document.at("runs").is_array()) {
    throw Error("has no list of runs");
  }
  RunSummary summary;
  summary.experiment = summary_text(document, "experiment", "");
  summary.message = read_run_message(document);
  if (const auto machine = document.find("machine"); machine != document.end()) {
    summary.machine = *machine;
  }
  const json& runs = document.at("runs");
  for (std::size_t k = 0; k < std::min(runs.size(), max_runs); ++k) {
    summary.runs.push_back(read_run_entry(runs[k], "runs[" + std::to_string(k) + "]"));
  }
  return summary;
}

std::string json_type_words(const json& value) {
  return (value.is_array() || value.is_object() ? "an " : "a ") + std::string(value.type_name());
}

const json* typed_json_field(const json& object, const char* key, const std::string& where,
                             bool (json::*is_type)() const noexcept, const char* type) {
  const auto it = object.find(key);
  if (it == object.end() || it->is_null()) return nullptr;
  if (!((*it).*is_type)()) {
    throw Error(where + key + " is " + json_type_words(*it) + ", not " + type);
  }
  return &*it;
}

}  // namespace physgrad::run
