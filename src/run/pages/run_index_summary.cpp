// Reading a run folder's summary.json and config.json for the index (run_index_folder.hpp): the
// runs, then at once the rows of the table of every run and the compared labels.
#include "physgrad/run/pages/run_index_folder.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include "physgrad/error.hpp"
#include "physgrad/run/life/experiment.hpp"
#include "physgrad/run/life/run_summary.hpp"
#include "physgrad/run/pages/report_page.hpp"
#include "physgrad/text.hpp"

namespace physgrad::run {

namespace fs = std::filesystem;
using nlohmann::json;

using RunRecord = IndexedRun;

bool IndexedMessage::compares(const std::string& label) const {
  return labels.empty() || std::find(labels.begin(), labels.end(), label) != labels.end();
}

std::string index_text(const json& value) {
  return value.is_string() ? value.get<std::string>() : format_number(value);
}

std::string index_clipped(std::string text, std::size_t bytes) {
  if (text.size() <= bytes) return text;
  std::size_t end = 0;
  while (end < text.size()) {
    const std::size_t next = end + utf8_char_at(text, end).length;
    if (next > bytes) break;
    end = next;
  }
  text.resize(end);
  return text + "…";
}

namespace {

std::string index_text_field(const json& object, const char* key, const std::string& where,
                       const std::string& absent) {
  const json* value = typed_json_field(object, key, where, &json::is_string, "text");
  return value ? value->get<std::string>() : absent;
}

const json& index_object_field(const json& object, const char* key, const std::string& where) {
  static const json empty = json::object();
  const json* value = typed_json_field(object, key, where, &json::is_object, "an object");
  return value ? *value : empty;
}

bool index_failed_end(const std::string& t) {
  return t == "numerical_failure" || t == "failed" || t == "diverged";
}
bool index_converged_end(const std::string& t) {
  return t == "converged" || t == "relative_loss" || t == "gradient_tolerance" ||
         t == "function_tolerance" || t == "parameter_tolerance";
}

}  // namespace

namespace {

// The message of a summary as the index keeps it: texts clipped; without one, every run is
// compared by its final test loss, or by its final loss when no run has one.
IndexedMessage read_index_message(const RunSummary& summary) {
  IndexedMessage message;
  if (summary.message) {
    const RunMessage& given = *summary.message;
    message.figure = index_clipped(given.figure, kIndexMaxName);
    message.sentence = index_clipped(given.sentence, kIndexMaxSentence);
    if (!given.metric.empty()) {
      message.metric = index_clipped(given.metric, kIndexMaxName);
      message.metric_text = index_clipped(
          given.metric_text.empty() ? given.metric : given.metric_text, kIndexMaxName);
    }
    for (const std::string& label : given.labels) {
      message.labels.push_back(index_clipped(label, kIndexMaxName));
    }
  }
  if (message.metric.empty()) {
    const bool tested = std::any_of(summary.runs.begin(), summary.runs.end(),
                                    [](const RunEntry& run) {
                                      return !std::isnan(run.figure("test_loss"));
                                    });
    message.metric = tested ? "test_loss" : "loss";
    message.metric_text = tested ? "final test loss" : "final loss";
  }
  return message;
}

}  // namespace

std::vector<RunRecord> read_index_summary(const json& document, IndexedFolder& folder,
                                          std::vector<std::string>& notes, const fs::path& file) {
  const RunSummary summary = read_run_summary(document, kIndexMaxRuns);
  folder.experiment =
      index_clipped(summary.experiment.empty() ? "?" : summary.experiment, kIndexMaxName);
  folder.message = read_index_message(summary);
  if (const std::size_t runs = document.at("runs").size(); runs > kIndexMaxRuns) {
    notes.push_back(in_quotes(file.string()) + ": " + std::to_string(runs) +
                    " runs, only the first " + std::to_string(kIndexMaxRuns) + " are listed");
  }
  std::vector<RunRecord> records;
  for (const RunEntry& run : summary.runs) {
    // Only training evaluates on a test set; direct optimization writes "epochs": null.
    const bool learning = run.seconds_per_part.has_value() || run.epochs.has_value() ||
                          !std::isnan(run.figure("test_loss"));
    records.push_back({index_clipped(run.label.empty() ? "?" : run.label, kIndexMaxName),
                       run.optimizer, run.params, run.final.loss,
                       run.final.test_loss.value_or(NAN), static_cast<double>(run.iterations),
                       run.wall_seconds, run.figure(folder.message.metric),
                       run.termination.empty() ? "–" : run.termination, learning});
    records.back().initial_loss = run.initial.loss;
  }
  folder.learning = std::any_of(records.begin(), records.end(),
                                [](const RunRecord& r) { return r.learning; });
  return records;
}

// The keys of the runs' params (seed aside) whose values are not the same in every run — with
// `in_every`, only keys every run has; else a key some runs lack counts — in the order they
// first appear.
std::vector<std::string> index_varying_keys(const std::vector<const RunRecord*>& runs,
                                            bool in_every) {
  struct Seen {
    const json* first;
    std::size_t count;
    bool differs;
  };
  std::map<std::string, Seen> seen;
  std::vector<std::string> keys;
  for (const RunRecord* run : runs) {
    for (auto it = run->params.begin(); it != run->params.end(); ++it) {
      if (it.key() == "seed") continue;
      const auto [at, added] = seen.try_emplace(it.key(), Seen{&it.value(), 0, false});
      if (added) keys.push_back(it.key());
      ++at->second.count;
      at->second.differs = at->second.differs || *at->second.first != it.value();
    }
  }
  std::erase_if(keys, [&](const std::string& key) {
    const Seen& s = seen.at(key);
    return in_every ? (!s.differs || s.count != runs.size()) : (!s.differs && s.count == runs.size());
  });
  return keys;
}

std::string index_setting(const RunRecord& run, const std::vector<std::string>& keys) {
  std::string setting;
  for (const std::string& key : keys) {
    const json value = run.params.value(key, json());
    setting += (setting.empty() ? "" : ", ") + key + " = " +
               (value.is_null() ? std::string("–") : index_text(value));
  }
  return setting;
}

namespace {

std::string index_joined_ends(const std::vector<const RunRecord*>& runs) {
  std::vector<std::string> ends;
  for (const RunRecord* run : runs) {
    if (std::find(ends.begin(), ends.end(), run->termination) == ends.end()) {
      ends.push_back(run->termination);
    }
  }
  std::string out;
  for (const std::string& e : ends) out += (out.empty() ? "" : ", ") + e;
  return out;
}

}  // namespace

void add_index_rows(IndexedFolder& folder, const std::vector<RunRecord>& runs,
              std::vector<std::string>& notes, const fs::path& file) {
  std::map<std::string, std::vector<const RunRecord*>> by_label;
  for (const RunRecord& run : runs) by_label[run.label].push_back(&run);
  std::map<std::string, std::vector<std::string>> keys;
  for (const auto& [label, members] : by_label) keys[label] = index_varying_keys(members, false);
  std::vector<std::pair<std::string, std::string>> order;
  std::map<std::pair<std::string, std::string>, std::vector<const RunRecord*>> groups;
  for (const RunRecord& run : runs) {
    auto key = std::make_pair(run.label,
                              index_clipped(index_setting(run, keys[run.label]), kIndexMaxName));
    std::vector<const RunRecord*>& group = groups[key];
    if (group.empty()) order.push_back(std::move(key));
    group.push_back(&run);
  }
  if (order.size() > kIndexMaxRows) {
    notes.push_back(in_quotes(file.string()) + ": " + std::to_string(order.size()) +
                    " runs of different label or setting, only the first " +
                    std::to_string(kIndexMaxRows) + " are listed in the table of every run");
    order.resize(kIndexMaxRows);
  }
  for (const auto& key : order) {
    const std::vector<const RunRecord*>& members = groups[key];
    const auto medians = [&](double RunRecord::*value) {
      std::vector<double> values;
      for (const RunRecord* run : members) values.push_back(run->*value);
      return spread_of(values);
    };
    folder.rows.push_back({key.first, key.second, members.size(), medians(&RunRecord::loss),
                           medians(&RunRecord::test_loss), medians(&RunRecord::iterations),
                           medians(&RunRecord::seconds), index_joined_ends(members)});
  }
}

void add_index_compared(IndexedFolder& folder, const std::vector<RunRecord>& runs,
                  std::vector<std::string>& notes, const fs::path& file) {
  std::vector<std::string> labels;
  std::map<std::string, std::vector<const RunRecord*>> by_label;
  for (const RunRecord& run : runs) {
    if (!folder.message.compares(run.label)) continue;
    std::vector<const RunRecord*>& members = by_label[run.label];
    if (members.empty()) labels.push_back(run.label);
    members.push_back(&run);
  }
  if (labels.size() > kIndexMaxCompared) {
    notes.push_back(in_quotes(file.string()) + ": " + std::to_string(labels.size()) +
                    " compared labels, only the first " + std::to_string(kIndexMaxCompared) +
                    " are compared");
    labels.resize(kIndexMaxCompared);
  }
  const bool cost = !folder.learning && is_cost_metric(folder.message.metric);
  for (const std::string& label : labels) {
    const std::vector<const RunRecord*>& members = by_label[label];
    ComparedGroup group;
    group.label = label;
    group.rule = members.front()->rule;
    group.runs = members.size();
    std::vector<double> values, seconds;
    for (const RunRecord* run : members) {
      seconds.push_back(run->seconds);
      if (index_failed_end(run->termination)) {
        ++group.failed;
      } else if (run->params.is_object() && run->params.value("switched", true) == false) {
        ++group.unswitched;
      } else if (cost && !index_converged_end(run->termination)) {
        ++(run->loss > run->initial_loss ? group.diverging : group.unreached);
      } else {
        values.push_back(run->metric);
      }
    }
    group.metric = spread_of(values);
    group.seconds = spread_of(seconds);
    group.ended = index_joined_ends(members);
    const json& params = members.front()->params;
    const json switch_at = params.value("pretrain_iterations", json());
    if (switch_at.is_number() && members.front()->iterations > switch_at.get<double>()) {
      group.switched_at = switch_at.get<long long>();
    }
    folder.compared.push_back(std::move(group));
  }
}

void read_index_config(const json& config, IndexedFolder& folder, std::vector<std::string>& notes,
                       const fs::path& file) {
  if (!config.is_object()) throw Error("holds " + json_type_words(config) + ", not an object");
  folder.command = index_clipped(index_text_field(config, "command", "", ""), kIndexMaxSentence);
  const json& settings = index_object_field(config, "settings", "");
  const std::size_t bytes = settings.dump().size();
  if (bytes > kIndexMaxSettingsBytes) {
    notes.push_back(in_quotes(file.string()) + ": settings of " + std::to_string(bytes) +
                    " bytes, more than the " + std::to_string(kIndexMaxSettingsBytes) +
                    " shown; its options are not listed");
  } else {
    folder.settings = settings;
  }
}

bool is_cost_metric(const std::string& metric) {
  return metric == "iterations" || metric == "simulator_passes";
}

}  // namespace physgrad::run
