// Config files — JSON documents of option values, checked by the same parse_option() as the
// command line; and the option table printed by `physgrad describe`.
#include "config_file.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>
#include <string_view>

#include "physgrad/error.hpp"

namespace physgrad::experiments {

namespace {

using json = nlohmann::json;
using Kind = OptionSpec::Kind;

constexpr std::size_t kMaxDepth = 16;
constexpr std::size_t kPreviewBytes = 60;

std::string flag(const OptionSpec& spec) { return "--" + spec.name; }

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

// "line L, column C" of the byte after the first `position` bytes, counted as nlohmann::json does.
std::string text_position(const std::string& text, std::size_t position) {
  const std::string_view read(text.data(), std::min(position, text.size()));
  const auto lines = std::count(read.begin(), read.end(), '\n');
  const std::size_t last_newline = read.rfind('\n');
  const std::size_t column =
      last_newline == std::string_view::npos ? read.size() : read.size() - last_newline - 1;
  return "line " + std::to_string(lines + 1) + ", column " + std::to_string(column);
}

// nlohmann::json SAX handler building the document iteratively, so that repeated keys and deep
// nesting are caught while parsing and every parse error gets its line and column.
class DocumentBuilder {
 public:
  explicit DocumentBuilder(const std::string& text) : text_(text) {}
  json take() { return std::move(root_); }

  bool null() { return add(nullptr); }
  bool boolean(bool value) { return add(value); }
  bool number_integer(json::number_integer_t value) { return add(value); }
  bool number_unsigned(json::number_unsigned_t value) { return add(value); }
  bool number_float(json::number_float_t value, const json::string_t& /*text*/) {
    return add(value);
  }
  bool string(json::string_t& value) { return add(std::move(value)); }
  bool binary(json::binary_t& /*value*/) { return false; }  // JSON text has no binary values
  bool start_object(std::size_t /*size*/) {
    keys_.emplace_back();
    return open(json::object());
  }
  bool key(json::string_t& name) {
    if (!keys_.back().insert(name).second) throw Error("key '" + name + "' appears twice");
    key_ = std::move(name);
    return true;
  }
  bool end_object() {
    keys_.pop_back();
    open_.pop_back();
    return true;
  }
  bool start_array(std::size_t /*size*/) { return open(json::array()); }
  bool end_array() {
    open_.pop_back();
    return true;
  }
  bool parse_error(std::size_t position, const std::string& /*last_token*/,
                   const json::exception& error) {
    // what() is "[json.exception.KIND.ID] parse error at line L, column C: DETAIL" or
    // "[json.exception.KIND.ID] DETAIL"; keep DETAIL.
    std::string detail = error.what();
    detail.erase(0, detail.find("] ") + 2);
    if (detail.starts_with("parse error")) detail.erase(0, detail.find(": ") + 2);
    throw Error("invalid JSON at " + text_position(text_, position) + ": " + detail);
  }

 private:
  bool add(json value) {
    place(std::move(value));
    return true;
  }
  json* place(json value) {
    if (open_.empty()) {
      root_ = std::move(value);
      return &root_;
    }
    json& parent = *open_.back();
    if (parent.is_array()) {
      parent.push_back(std::move(value));
      return &parent.back();
    }
    return &(parent[key_] = std::move(value));
  }
  bool open(json container) {
    if (open_.size() == kMaxDepth) {
      throw Error("JSON nested deeper than " + std::to_string(kMaxDepth) + " levels");
    }
    open_.push_back(place(std::move(container)));
    return true;
  }

  const std::string& text_;
  json root_;
  std::vector<json*> open_;  // the open arrays and objects, innermost last
  std::vector<std::set<std::string>> keys_;  // keys seen in each open object
  std::string key_;
};

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
      throw Error(flag(spec) + ": expected " + kind_description(spec.kind) + ", got item " +
                  preview(item));
    }
    const std::string item_text = numbers ? number_text(item, false) : item.get<std::string>();
    if (item_text.find_first_not_of(" \t") == std::string::npos) {
      throw Error(flag(spec) + ": empty entry in list " + preview(items));
    }
    if (item_text.find(',') != std::string::npos) {
      throw Error(flag(spec) + ": list entry '" + item_text + "' contains a comma");
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
  throw Error(flag(spec) + ": expected " + kind_description(spec.kind) + ", got " +
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

json parse_config_json(const std::string& text) {
  DocumentBuilder builder(text);
  json::sax_parse(text, &builder);
  return builder.take();
}

OptionTexts config_options(const Experiment& experiment, const json& document) {
  if (!document.is_object()) {
    throw Error("expected a JSON object of option values, got " + preview(document));
  }
  const bool saved = document.contains("experiment") && document.contains("settings");
  const json& settings = saved ? saved_settings(experiment, document) : document;
  const std::vector<OptionSpec> specs = all_options(experiment);
  OptionTexts texts;
  for (const auto& [key, value] : settings.items()) {
    const auto spec = std::find_if(specs.begin(), specs.end(),
                                   [&](const OptionSpec& s) { return s.name == key; });
    if (spec == specs.end()) {
      std::string allowed;
      for (const OptionSpec& s : specs) allowed += (allowed.empty() ? "" : ", ") + s.name;
      throw Error("experiment '" + experiment.name() + "' has no option '" + key +
                  "' (allowed: " + allowed + ")");
    }
    if (value.is_null()) continue;
    std::string text = option_text(*spec, value);
    parse_option(*spec, text);
    texts.emplace_back(key, std::move(text));
  }
  return texts;
}

nlohmann::json read_config_document(const std::filesystem::path& path) {
  const std::string where = std::string("config file '") + path.string() + "': ";
  std::error_code error;
  if (std::filesystem::is_directory(path, error)) throw Error(where + "is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(where + "cannot open: " + std::strerror(errno));
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw Error(where + "cannot read: " + std::strerror(errno));
  try {
    return parse_config_json(text.str());
  } catch (const Error& e) {
    throw Error(where + e.what());
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

}  // namespace physgrad::experiments
