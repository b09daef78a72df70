// Config files — JSON documents of option values, checked by the same parse_option() as the
// command line; and the option table printed by `physgrad describe`.
#include "physgrad/run/life/config_file.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>

#include "physgrad/error.hpp"
#include "physgrad/io/json_file.hpp"

namespace physgrad::run {

namespace {

using json = nlohmann::json;
using Kind = OptionSpec::Kind;

constexpr std::size_t kMaxDepth = 16;
constexpr std::size_t kMaxBytes = 1 << 20;
constexpr std::size_t kPreviewBytes = 60;

// A JSON value as named in a message: 'text' for strings, JSON otherwise; cut to a short prefix.
std::string preview(const json& value) {
  std::string text = value.is_string()
                         ? "'" + value.get<std::string>() + "'"
                         : value.dump(-1, ' ', false, json::error_handler_t::replace);
  if (text.size() <= kPreviewBytes) return text;
  std::size_t cut = kPreviewBytes - 3;
  while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80) --cut;
  return text.substr(0, cut) + "…";
}

std::string kind_description(Kind kind) {
  switch (kind) {
    case Kind::kReal: return "a number";
    case Kind::kInteger: return "a whole number";
    case Kind::kText: return "a string";
    case Kind::kRealList: return "a list of numbers";
    case Kind::kTextList: return "a list of strings";
  }
  return "a value";
}

std::string kind_name(Kind kind) {
  switch (kind) {
    case Kind::kReal: return "real";
    case Kind::kInteger: return "integer";
    case Kind::kText: return "text";
    case Kind::kRealList: return "real list";
    case Kind::kTextList: return "text list";
  }
  return "text";
}

// The command-line text of a JSON number: exact for integers, shortest round-trip form for
// reals; an integral real given for a whole number is written as one (5.0 → "5").
std::string number_text(const json& value, bool whole) {
  if (value.is_number_integer()) return value.dump();
  const double number = value.get<double>();
  if (whole && std::trunc(number) == number && std::abs(number) < 9.2e18) {
    return std::to_string(static_cast<long long>(number));
  }
  char buffer[32];
  return std::string(buffer, std::to_chars(buffer, buffer + sizeof buffer, number).ptr);
}

std::string list_text(const OptionSpec& spec, const json& items) {
  const bool numbers = spec.kind == Kind::kRealList;
  std::string text;
  for (std::size_t i = 0; i < items.size(); ++i) {
    const json& item = items[i];
    if (numbers ? !item.is_number() : !item.is_string()) {
      throw Error(spec.flag() + ": expected " + kind_description(spec.kind) + ", got item " +
                  preview(item));
    }
    const std::string item_text = numbers ? number_text(item, false) : item.get<std::string>();
    if (item_text.find_first_not_of(" \t") == std::string::npos) {
      throw Error(spec.flag() + ": empty entry in list " + preview(items));
    }
    if (item_text.find(',') != std::string::npos) {
      throw Error(spec.flag() + ": list entry '" + item_text + "' contains a comma");
    }
    if (i > 0) text += ',';
    text += item_text;
  }
  return text;
}

// The command-line text of `value` for `spec`; strings are taken as command-line text.
std::string option_text(const OptionSpec& spec, const json& value) {
  if (value.is_string()) return value.get<std::string>();
  switch (spec.kind) {
    case Kind::kReal:
    case Kind::kInteger:
      if (value.is_number()) return number_text(value, spec.kind == Kind::kInteger);
      break;
    case Kind::kText: break;
    case Kind::kRealList:
    case Kind::kTextList:
      if (value.is_array()) return list_text(spec, value);
      break;
  }
  throw Error(spec.flag() + ": expected " + kind_description(spec.kind) + ", got " +
              preview(value));
}

// The "settings" object of a whole saved config.json, after checking it belongs to `experiment`.
const json& saved_settings(const Experiment& experiment, const json& document) {
  for (const auto& [key, value] : document.items()) {
    if (key != "experiment" && key != "command" && key != "settings") {
      throw Error("unknown key '" + key +
                  "' in a saved run config (allowed: experiment, command, settings)");
    }
  }
  const json& name = document.at("experiment");
  if (name != experiment.name()) {
    throw Error("saved for experiment " + preview(name) + ", not '" + experiment.name() + "'");
  }
  const json& settings = document.at("settings");
  if (!settings.is_object()) {
    throw Error("\"settings\" must be an object of option values, got " + preview(settings));
  }
  return settings;
}

}  // namespace

json parse_config_json(const std::string& text) { return parse_json_text(text, kMaxDepth); }

OptionTexts config_options(const Experiment& experiment, const json& document) {
  if (!document.is_object()) {
    throw Error("expected a JSON object of option values, got " + preview(document));
  }
  const bool saved = document.contains("experiment") && document.contains("settings");
  const json& settings = saved ? saved_settings(experiment, document) : document;
  const std::vector<OptionSpec> specs = all_options(experiment);
  OptionTexts texts;
  for (const auto& [key, value] : settings.items()) {
    const OptionSpec& spec = find_option(experiment, specs, key);
    if (value.is_null()) continue;
    std::string text = option_text(spec, value);
    parse_option(spec, text);
    texts.emplace_back(key, std::move(text));
  }
  return texts;
}

nlohmann::json read_config_document(const std::filesystem::path& path) {
  try {
    return parse_config_json(read_regular_file(path, kMaxBytes));
  } catch (const Error& e) {
    throw Error(std::string("config file '") + path.string() + "': " + e.what());
  }
}

nlohmann::json read_config_document(const FolderHandle& folder, const std::string& name) {
  try {
    return parse_config_json(read_regular_file(folder, name, kMaxBytes));
  } catch (const Error& e) {
    throw Error("config file '" + folder.shown(name) + "': " + e.what());
  }
}

OptionTexts read_config_file(const Experiment& experiment, const std::filesystem::path& path) {
  const nlohmann::json document = read_config_document(path);
  try {
    return config_options(experiment, document);
  } catch (const Error& e) {
    throw Error(std::string("config file '") + path.string() + "': " + e.what());
  }
}

RunContext::Table options_table(const Experiment& experiment) {
  RunContext::Table table{experiment.name() + " — " + experiment.description(),
                          {"option", "kind", "default", "range", "help"},
                          {}};
  for (const OptionSpec& spec : all_options(experiment)) {
    const std::string range = describe_range(spec);
    table.rows.push_back({spec.name, kind_name(spec.kind),
                          spec.default_text.empty() ? "unset" : spec.default_text,
                          range.empty() ? "any" : range, spec.help});
  }
  return table;
}

}  // namespace physgrad::run
