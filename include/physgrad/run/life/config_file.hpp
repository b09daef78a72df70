// Config files — an experiment's option values read from a JSON object keyed by option name
// (`physgrad run NAME --config FILE.json`), and the option table of `physgrad describe NAME`.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "physgrad/run/life/experiment.hpp"
#include "physgrad/io/folder_handle.hpp"

namespace physgrad::run {

// Option name → text, the form resolve_settings() takes from the command line.
using OptionTexts = std::vector<std::pair<std::string, std::string>>;

// Parses JSON text. Throws Error "invalid JSON at line L, column C: …" on a syntax error or a
// number too large for a double, and Error on a repeated key or nesting deeper than 16 levels.
nlohmann::json parse_config_json(const std::string& text);

// The option values in `document`: a settings object {"lr": 0.01, "optimizers": ["adam"], ...}
// or a whole saved config.json {"experiment": NAME, "command": ..., "settings": {...}}. A value
// is JSON of the option's kind or its command-line text ("1,10,100"); null leaves the option at
// its default. Every value is checked by parse_option(). Throws Error naming the bad key or value.
OptionTexts config_options(const Experiment& experiment, const nlohmann::json& document);

// Reads and parses a config file (without checking its values); errors start with
// "config file 'PATH': ".
nlohmann::json read_config_document(const std::filesystem::path& path);
// The same for the file `name` in `folder`, opened through the folder's handle.
nlohmann::json read_config_document(const FolderHandle& folder, const std::string& name);
// Reads, parses and checks a config file; errors start with "config file 'PATH': ".
OptionTexts read_config_file(const Experiment& experiment, const std::filesystem::path& path);

// Titled "NAME — description"; one row per option: name, kind, default (or "unset"), range or
// choices (or "any"), help.
RunContext::Table options_table(const Experiment& experiment);

}  // namespace physgrad::run
