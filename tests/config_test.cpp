// Config files and the option table: JSON option values are checked like flags and resolve to
// the same settings, saved settings resolve to themselves, every bad document is one Error with
// an exact message; and a seeded random-input test of the config and option parsers.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <random>
#include <tuple>
#include <typeinfo>

#include "physgrad/run/config_file.hpp"
#include "physgrad/run/registry.hpp"
#include "physgrad/run/experiment.hpp"
#include "physgrad/error.hpp"

namespace physgrad::experiments {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

Settings resolve_json(const std::string& name, const std::string& text,
                      const OptionTexts& flags = {}) {
  const Experiment& experiment = registry().find(name);
  OptionTexts given = config_options(experiment, parse_config_json(text));
  given.insert(given.end(), flags.begin(), flags.end());
  return resolve_settings(experiment, given);
}

// The message of the Error `action` throws; "(no error)" when it returns.
std::string error_of(const std::function<void()>& action) {
  try {
    action();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

std::string config_error(const std::string& name, const std::string& text) {
  return error_of([&] { resolve_json(name, text); });
}

std::string option_names(const std::string& name) {
  std::string names;
  for (const OptionSpec& spec : all_options(registry().find(name))) {
    names += (names.empty() ? "" : ", ") + spec.name;
  }
  return names;
}

TEST(ConfigFile, ResolvesToTheSameSettingsAsTheSameValuesGivenAsFlags) {
  const std::vector<std::tuple<std::string, std::string, OptionTexts>> cases = {
      {"hig-toy",
       R"({"lr": 0.01, "optimizers": ["adam", "hig"], "lambda": [1, 0.01], "seeds": 3,
           "seed": 7})",
       {{"lr", "0.01"}, {"optimizers", "adam,hig"}, {"lambda", "1,0.01"}, {"seeds", "3"},
        {"seed", "7"}}},
      // Command-line text for any kind; a whole number may be written 50.0.
      {"scaled-toy",
       R"({"tol-mode": "absolute", "alpha": "1, 10,100", "start": [0.5, -0.25], "tol": 1e-8,
           "iters": 50.0, "lr": "0.30000000000000004"})",
       {{"tol-mode", "absolute"}, {"alpha", "1,10,100"}, {"start", "0.5,-0.25"}, {"tol", "1e-8"},
        {"iters", "50"}, {"lr", "0.30000000000000004"}}},
      {"comparison", R"({"pg-inverse": ["ig"], "threads": 2, "out": "x", "start": [-3, 1e-3]})",
       {{"pg-inverse", "ig"}, {"threads", "2"}, {"out", "x"}, {"start", "-3,0.001"}}},
  };
  for (const auto& [name, text, flags] : cases) {
    EXPECT_EQ(resolve_json(name, text).json(),
              resolve_settings(registry().find(name), flags).json())
        << name;
  }
}

TEST(ConfigFile, SavedSettingsResolveToThemselvesBareOrAsAWholeConfig) {
  for (const auto& experiment : registry()) {
    const Settings settings =
        resolve_settings(*experiment, {{"iters", "3"}, {"lr", "0.1"}, {"seed", "12"}});
    const json whole = {{"experiment", experiment->name()},
                        {"command", "physgrad run " + experiment->name()},
                        {"settings", settings.json()}};
    for (const json& document : {settings.json(), whole}) {
      EXPECT_EQ(resolve_json(experiment->name(), document.dump(2)).json(), settings.json())
          << experiment->name();
    }
  }
}

TEST(ConfigFile, NullTakesTheDefaultAndFlagsOverrideTheFile) {
  const Settings nulls = resolve_json("comparison", R"({"lr": null, "iters": null})");
  EXPECT_FALSE(nulls.has("lr"));
  EXPECT_EQ(nulls.integer("iters"), 10);
  const Settings overridden =
      resolve_json("comparison", R"({"iters": 3, "lr": 0.5})", {{"iters", "7"}});
  EXPECT_EQ(overridden.integer("iters"), 7);
  EXPECT_EQ(overridden.real("lr"), 0.5);
}

TEST(ConfigFile, EveryBadValueIsOneErrorWithAnExactMessage) {
  const std::string unknown_option = "experiment 'comparison': unknown option '";
  const std::string known_options = "' (known: " + option_names("comparison") + ")";
  const std::string not_a_number = " is not a number (decimal, like 16, -2.5 or 1e-3)";
  const std::string not_whole = " is not a whole number (decimal digits, like 16)";
  // {experiment, document, message}
  const std::vector<std::tuple<std::string, std::string, std::string>> cases = {
      // Unknown keys.
      {"comparison", R"({"learning-rate": 0.1})", unknown_option + "learning-rate" + known_options},
      {"comparison", R"({"": 1})", unknown_option + known_options},
      {"comparison", R"({"LR": 0.1})", unknown_option + "LR" + known_options},
      {"comparison", R"({"tol": 0.1})", unknown_option + "tol" + known_options},
      // Wrong JSON type, per kind.
      {"comparison", R"({"lr": true})", "--lr: expected a number, got true"},
      {"comparison", R"({"lr": [0.1]})", "--lr: expected a number, got [0.1]"},
      {"comparison", R"({"lr": {"value": 1}})", R"(--lr: expected a number, got {"value":1})"},
      {"comparison", R"({"lr": "fast"})", "--lr: 'fast'" + not_a_number},
      {"comparison", R"({"iters": false})", "--iters: expected a whole number, got false"},
      {"comparison", R"({"iters": "ten"})", "--iters: 'ten'" + not_whole},
      {"comparison", R"({"iters": 2.5})", "--iters: '2.5'" + not_whole},
      {"comparison", R"({"iters": 1e300})", "--iters: '1e+300'" + not_whole},
      {"comparison", R"({"threads": 18446744073709551615})",
       "--threads: must be in [1, 256], got '18446744073709551615'"},
      {"scaled-toy", R"({"tol-mode": 1})", "--tol-mode: expected a string, got 1"},
      {"comparison", R"({"out": ["a"]})", R"(--out: expected a string, got ["a"])"},
      {"scaled-toy", R"({"alpha": 10})", "--alpha: expected a list of numbers, got 10"},
      {"scaled-toy", R"({"alpha": [1, "10"]})",
       "--alpha: expected a list of numbers, got item '10'"},
      {"scaled-toy", R"({"alpha": [1, null]})", "--alpha: expected a list of numbers, got item null"},
      {"scaled-toy", R"({"alpha": [[1]]})", "--alpha: expected a list of numbers, got item [1]"},
      {"comparison", R"({"optimizers": ["gd", 1]})",
       "--optimizers: expected a list of strings, got item 1"},
      {"comparison", R"({"optimizers": {"gd": true}})",
       R"(--optimizers: expected a list of strings, got {"gd":true})"},
      {"comparison", R"({"optimizers": ["gd", " "]})",
       R"(--optimizers: empty entry in list ["gd"," "])"},
      {"comparison", R"({"optimizers": "gd,,adam"})", "--optimizers: empty entry in list 'gd,,adam'"},
      {"comparison", R"({"optimizers": ["gd,adam"]})",
       "--optimizers: list entry 'gd,adam' contains a comma"},
      // Out of range, unknown choices, not finite.
      {"comparison", R"({"lr": -0.5})", "--lr: must be > 0, got '-0.5'"},
      {"comparison", R"({"lr": 0})", "--lr: must be > 0, got '0'"},
      {"comparison", R"({"iters": 0})", "--iters: must be in [1, 1000000000], got '0'"},
      {"comparison", R"({"seed": -1})", "--seed: must be in [0, 4294967295], got '-1'"},
      {"comparison", R"({"seed": 4294967296})",
       "--seed: must be in [0, 4294967295], got '4294967296'"},
      {"scaled-toy", R"({"alpha": [1, 0]})", "--alpha: must be > 0, got '0'"},
      {"scaled-toy", R"({"tol-mode": "absolute-ish"})",
       "--tol-mode: unknown value 'absolute-ish' (known: relative, absolute)"},
      {"comparison", R"({"pg-inverse": ["ig", "magic"]})",
       "--pg-inverse: unknown value 'magic' (known: analytic, lbfgs, ig)"},
      {"comparison", R"({"lr": "nan"})", "--lr: 'nan'" + not_a_number},
      {"comparison", R"({"lr": "-inf"})", "--lr: '-inf'" + not_a_number},
      {"scaled-toy", R"({"alpha": "1,NaN"})", "--alpha: 'NaN'" + not_a_number},
      // Numbers are decimal, in a string as on the command line.
      {"scaled-toy", R"({"alpha": "0x10"})", "--alpha: '0x10'" + not_a_number},
      {"comparison", R"({"lr": "0x1p-3"})", "--lr: '0x1p-3'" + not_a_number},
      {"comparison", R"({"lr": "1e"})", "--lr: '1e'" + not_a_number},
      {"comparison", R"({"iters": "0x10"})",
       "--iters: '0x10'" + not_whole},
      {"comparison", R"({"lr": 1e999})",
       "invalid JSON at line 1, column 12: number overflow parsing '1e999'"},
      {"scaled-toy", R"({"alpha": [1, -1e400]})",
       "invalid JSON at line 1, column 20: number overflow parsing '-1e400'"},
      {"comparison", R"({"lr": NaN})",
       "invalid JSON at line 1, column 8: syntax error while parsing value - invalid literal; "
       "last read: '\"lr\": N'"},
      // Empty lists and repeated entries.
      {"scaled-toy", R"({"alpha": []})", "--alpha: needs at least one value"},
      {"comparison", R"({"optimizers": ""})", "--optimizers: needs at least one value"},
      {"comparison", R"({"optimizers": ["gd", "adam", "gd"]})", "--optimizers: 'gd' is listed twice"},
      {"comparison", R"({"pg-inverse": "ig, ig"})", "--pg-inverse: 'ig' is listed twice"},
      // Checks across options.
      {"comparison", R"({"start": [1, 2, 3]})", "--start: needs exactly 2 values, got 3"},
      // Saved run configs.
      {"comparison", R"({"experiment": "scaled-toy", "settings": {}})",
       "saved for experiment 'scaled-toy', not 'comparison'"},
      {"comparison", R"({"experiment": 3, "settings": {}})",
       "saved for experiment 3, not 'comparison'"},
      {"comparison", R"({"experiment": "comparison", "settings": []})",
       "\"settings\" must be an object of option values, got []"},
      {"comparison", R"({"experiment": "comparison", "settings": {}, "notes": ""})",
       "unknown key 'notes' in a saved run config (allowed: experiment, command, settings)"},
      {"comparison", R"({"experiment": "comparison", "settings": {"lr": -1}})",
       "--lr: must be > 0, got '-1'"},
      // Not an object.
      {"comparison", "[]", "expected a JSON object of option values, got []"},
      {"comparison", R"("lr")", "expected a JSON object of option values, got 'lr'"},
      {"comparison", "null", "expected a JSON object of option values, got null"},
      // Malformed JSON, repeated keys, deep nesting.
      {"comparison", R"({"lr": 0.1,})",
       "invalid JSON at line 1, column 12: syntax error while parsing object key - unexpected '}'; "
       "expected string literal"},
      {"comparison", "{\"lr\": 0.1,\n \"iters\" 3}",
       "invalid JSON at line 2, column 10: syntax error while parsing object separator - "
       "unexpected number literal; expected ':'"},
      {"comparison", R"({"lr": 0.1)",
       "invalid JSON at line 1, column 10: syntax error while parsing object - unexpected end of "
       "input; expected '}'"},
      {"comparison", R"({"lr": 0.1} {})",
       "invalid JSON at line 1, column 13: syntax error while parsing value - unexpected '{'; "
       "expected end of input"},
      {"comparison", "",
       "invalid JSON at line 1, column 0: syntax error while parsing value - unexpected end of "
       "input; expected '[', '{', or a literal"},
      {"comparison", R"({"lr": 0.1, "lr": 0.2})", "key 'lr' appears twice"},
      {"comparison", R"({"lr": )" + std::string(17, '[') + std::string(17, ']') + "}",
       "JSON nested deeper than 16 levels"},
  };
  for (const auto& [name, text, message] : cases) {
    EXPECT_EQ(config_error(name, text), message) << text;
  }
}

TEST(ConfigFile, FileErrorsNameThePath) {
  const fs::path dir = fs::temp_directory_path() / ("physgrad_config_" + std::to_string(getpid()));
  fs::create_directories(dir);
  const Experiment& comparison = registry().find("comparison");
  const auto file_error = [&](const fs::path& path) {
    return error_of([&] { read_config_file(comparison, path); });
  };
  const std::string missing = (dir / "missing.json").string();
  EXPECT_EQ(file_error(missing),
            "config file '" + missing + "': cannot open: No such file or directory");
  EXPECT_EQ(file_error(dir), "config file '" + dir.string() + "': is a directory");
  const fs::path bad = dir / "bad.json";
  std::ofstream(bad) << "{\"lr\": -1}\n";
  EXPECT_EQ(file_error(bad), "config file '" + bad.string() + "': --lr: must be > 0, got '-1'");
  const fs::path good = dir / "good.json";
  std::ofstream(good) << "{\"lr\": 0.25, \"iters\": null}\n";
  EXPECT_EQ(read_config_file(comparison, good), (OptionTexts{{"lr", "0.25"}}));
  fs::remove_all(dir);
}

TEST(DescribeExperiment, TableHasEveryOptionWithKindDefaultAndRange) {
  for (const auto& experiment : registry()) {
    const RunContext::Table table = options_table(*experiment);
    EXPECT_EQ(table.title, experiment->name() + " — " + experiment->description());
    const std::vector<OptionSpec> specs = all_options(*experiment);
    ASSERT_EQ(table.rows.size(), specs.size()) << experiment->name();
    for (std::size_t i = 0; i < specs.size(); ++i) {
      ASSERT_EQ(table.rows[i].size(), table.header.size());
      EXPECT_EQ(table.rows[i][0], specs[i].name);
      EXPECT_EQ(table.rows[i][2], specs[i].default_text.empty() ? "unset" : specs[i].default_text);
    }
  }
  const RunContext::Table table = options_table(registry().find("scaled-toy"));
  const auto row = [&](const std::string& name) {
    for (const auto& r : table.rows) {
      if (r[0] == name) return r;
    }
    return std::vector<std::string>{};
  };
  EXPECT_EQ(row("lr"), (std::vector<std::string>{"lr", "real", "unset", "> 0", row("lr")[4]}));
  EXPECT_EQ(row("iters")[1], "integer");
  EXPECT_EQ(row("iters")[3], "in [1, 1000000000]");
  EXPECT_EQ(row("alpha")[1], "real list");
  EXPECT_EQ(row("alpha")[2], "1,10,100,1000");
  EXPECT_EQ(row("tol-mode")[1], "text");
  EXPECT_EQ(row("tol-mode")[3], "one of: relative, absolute");
  EXPECT_EQ(row("optimizers")[1], "text list");
  EXPECT_EQ(row("out")[3], "any");
}

// Random inputs from a seeded generator: plausible and garbage keys and values, truncated and
// mutated documents, random bytes, deep nesting, huge numbers, unicode.
class RandomInput {
 public:
  explicit RandomInput(std::uint64_t seed) : rng_(seed) {}

  std::size_t below(std::size_t n) {
    return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng_);
  }
  bool chance(double p) { return std::bernoulli_distribution(p)(rng_); }
  template <typename T>
  const T& pick(const std::vector<T>& items) { return items[below(items.size())]; }

  std::string bytes(std::size_t max_length) {
    std::string out(below(max_length + 1), '\0');
    for (char& c : out) c = static_cast<char>(below(256));
    return out;
  }

  // Option text: numbers, list forms, special words, unicode and raw bytes, glued together.
  std::string option_text(const OptionSpec& spec) {
    static const std::vector<std::string> pieces = {
        "0", "1", "-1", "2.5", "1e-8", "1e308", "1e999", "-1e999", "1e-400", "nan", "NaN",
        "inf", "-Infinity", "0x1p3", "+7", "-0", "  5  ", "007", "4294967295", "4294967296",
        "9223372036854775807", "9223372036854775808", "18446744073709551616", ".5", "1.",
        "1e", "--1", "", " ", ",", ",,", "1,10,100", "adam,hig", "gd,gd", "relative",
        "λ", "∞", "é", "日本", "😀", "\xff\xfe", "\xc3", "\t", "\n", "a\0b"};
    std::string text;
    const std::size_t parts = 1 + below(3);
    for (std::size_t i = 0; i < parts; ++i) {
      if (i > 0 && chance(0.5)) text += ',';
      if (!spec.choices.empty() && chance(0.4)) {
        text += pick(spec.choices);
      } else if (chance(0.1)) {
        text += bytes(8);
      } else {
        text += pick(pieces);
      }
    }
    return text;
  }

  json scalar() {
    switch (below(9)) {
      case 0: return nullptr;
      case 1: return chance(0.5);
      case 2: return static_cast<long long>(below(21)) - 10;
      case 3: return pick(std::vector<long long>{std::numeric_limits<long long>::min(),
                                                 std::numeric_limits<long long>::max(), 0});
      case 4: return std::numeric_limits<unsigned long long>::max() - below(3);
      case 5: return std::uniform_real_distribution<double>(-5, 5)(rng_);
      case 6: return pick(std::vector<double>{1e308, -1e308, 5e-324, -0.0, 1e-300, 0.1, 1e18});
      case 7: return bytes(6);  // made valid UTF-8 by dump(); raw bytes come in below
      default: return pick(std::vector<std::string>{"λ", "\u00e9", "😀", "", "gd", "adam"});
    }
  }

  json value(std::size_t depth) {
    if (depth > 3 || chance(0.6)) return scalar();
    json container = chance(0.7) ? json::array() : json::object();
    const std::size_t n = below(5);
    for (std::size_t i = 0; i < n; ++i) {
      if (container.is_array()) {
        container.push_back(value(depth + 1));
      } else {
        container[bytes(3)] = value(depth + 1);
      }
    }
    return container;
  }

  // A value of the option's kind, often valid, sometimes its text form.
  json plausible(const OptionSpec& spec) {
    const auto number = [&]() -> json {
      if (spec.kind == OptionSpec::Kind::kInteger || chance(0.3)) {
        return static_cast<long long>(below(50)) - 5;
      }
      return std::exp(std::uniform_real_distribution<double>(-20, 10)(rng_)) *
             (chance(0.9) ? 1 : -1);
    };
    const auto word = [&]() -> json {
      return spec.choices.empty() || chance(0.1) ? json(bytes(4)) : json(pick(spec.choices));
    };
    if (chance(0.2)) return option_text(spec);
    switch (spec.kind) {
      case OptionSpec::Kind::kReal:
      case OptionSpec::Kind::kInteger: return number();
      case OptionSpec::Kind::kText: return word();
      case OptionSpec::Kind::kRealList:
      case OptionSpec::Kind::kTextList: {
        json items = json::array();
        const std::size_t n = below(4);
        for (std::size_t i = 0; i < n; ++i) {
          items.push_back(spec.kind == OptionSpec::Kind::kRealList ? number() : word());
        }
        return items;
      }
    }
    return nullptr;
  }

  json settings(const std::vector<OptionSpec>& specs) {
    json object = json::object();
    const std::size_t n = below(6);
    for (std::size_t i = 0; i < n; ++i) {
      if (chance(0.85)) {
        const OptionSpec& spec = pick(specs);
        object[spec.name] = chance(0.8) ? plausible(spec) : value(0);
      } else {
        object[chance(0.5) ? bytes(6) : pick(std::vector<std::string>{"experiment", "settings",
                                                                      "LR", "λ", ""})] = value(0);
      }
    }
    return object;
  }

  // Returns the document text and the name of the kind of input it is.
  std::pair<std::string, std::string> document(const Experiment& experiment) {
    const auto dump = [](const json& j) {
      return j.dump(-1, ' ', false, json::error_handler_t::replace);
    };
    const json object = settings(all_options(experiment));
    const json saved = {{"experiment", chance(0.8) ? experiment.name() : pick(std::vector<std::string>{"scaled-toy", "comparison", "x"})},
                        {"command", "physgrad"},
                        {"settings", object}};
    const std::string text = dump(chance(0.7) ? object : saved);
    switch (below(8)) {
      case 0:
      case 1: return {text, "settings object"};
      case 2: return {dump(saved), "saved config"};
      case 3: return {text.substr(0, below(text.size() + 1)), "truncated"};
      case 4: {
        std::string mutated = text;
        for (std::size_t i = 1 + below(4); i > 0; --i) {
          const std::size_t at = below(mutated.size() + 1);
          const auto byte = static_cast<char>(below(256));
          if (chance(0.5) && at < mutated.size()) {
            mutated[at] = byte;
          } else {
            mutated.insert(at, 1, byte);
          }
        }
        return {mutated, "mutated bytes"};
      }
      case 5: {
        const std::size_t depth = 1 + below(20000);
        const std::string open = chance(0.5) ? "[" : "{\"lr\":";
        std::string nested = "{\"lr\":";
        for (std::size_t i = 0; i < depth; ++i) nested += open;
        if (chance(0.5)) nested += std::string(depth, open == "[" ? ']' : '}') + "}";
        return {nested, "deep nesting"};
      }
      case 6: {
        static const std::vector<std::string> numbers = {
            "1e999", "-1e999", "1e-999", "123456789012345678901234567890", "-0", "1E+2", "01",
            "1.", ".5", "1e", "--1", "+1", "0.1e1", "9223372036854775808",
            "-9223372036854775809", "18446744073709551616", "4.9e-324", "2.2250738585072014e-308",
            "1" + std::string(400, '0'), "0." + std::string(400, '0') + "1"};
        const OptionSpec spec = pick(all_options(experiment));
        return {"{\"" + spec.name + "\": " + (chance(0.5) ? "[" + pick(numbers) + "]" : pick(numbers)) +
                    "}",
                "huge or odd number"};
      }
      default: {
        static const std::vector<std::string> unicode = {
            "\"\\ud83d\\ude00\"", "\"\\udc00\"", "\"\\ud800x\"", "\"λ\"", "\"\xff\"",
            "\"\xc3\"", "\"\\u0000\"", "\"a\\nb\"", "\"\xEF\xBB\xBF\"", "\"\\u00e9\""};
        const OptionSpec spec = pick(all_options(experiment));
        const std::string key = chance(0.8) ? "\"" + spec.name + "\"" : pick(unicode);
        return {(chance(0.2) ? "\xEF\xBB\xBF" : "") + std::string("{") + key + ": " +
                    pick(unicode) + "}",
                "unicode"};
      }
    }
  }

 private:
  std::mt19937_64 rng_;
};

std::string printable(const std::string& text) {
  return json(text).dump(-1, ' ', true, json::error_handler_t::replace).substr(0, 300);
}

TEST(FuzzConfig, RandomDocumentsResolveOrThrowErrorOnly) {
  RandomInput random(20240917);
  std::map<std::string, std::pair<int, int>> tally;  // kind → (resolved, rejected)
  const auto start = std::chrono::steady_clock::now();
  int documents = 0;
  for (; documents < 2000; ++documents) {
    if (std::chrono::steady_clock::now() - start > std::chrono::seconds(4)) break;
    const Experiment& experiment = *random.pick(registry().experiments());
    const auto [text, kind] = random.document(experiment);
    try {
      const Settings settings = resolve_settings(
          experiment, config_options(experiment, parse_config_json(text)));
      // Resolved settings are a valid config of their own and resolve to themselves.
      EXPECT_EQ(resolve_settings(experiment, config_options(experiment, settings.json())).json(),
                settings.json())
          << printable(text);
      ++tally[kind].first;
    } catch (const Error&) {
      ++tally[kind].second;
    } catch (const std::exception& e) {
      ADD_FAILURE() << typeid(e).name() << ": " << e.what() << " for " << printable(text);
    }
  }
  EXPECT_GE(documents, 500) << "too slow";
  int resolved = 0;
  for (const auto& [kind, counts] : tally) {
    std::cout << kind << ": " << counts.first << " resolved, " << counts.second << " rejected\n";
    resolved += counts.first;
  }
  EXPECT_GT(resolved, 50);  // the generator reaches valid settings, not only errors
}

TEST(FuzzOptions, RandomTextsParseToValidValuesOrThrowErrorOnly) {
  RandomInput random(77);
  int accepted = 0, rejected = 0;
  for (int i = 0; i < 5000; ++i) {
    const Experiment& experiment = *random.pick(registry().experiments());
    const OptionSpec spec = random.pick(all_options(experiment));
    const std::string text = random.option_text(spec);
    try {
      const json value = parse_option(spec, text);
      const std::vector<json> items = value.is_array() ? value.get<std::vector<json>>()
                                                       : std::vector<json>{value};
      EXPECT_FALSE(items.empty()) << printable(text);
      for (const json& item : items) {
        if (item.is_number()) {
          const double x = item.get<double>();
          EXPECT_TRUE(std::isfinite(x) && x >= spec.min && x <= spec.max) << printable(text);
        } else if (!spec.choices.empty()) {
          EXPECT_NE(std::find(spec.choices.begin(), spec.choices.end(), item), spec.choices.end())
              << printable(text);
        }
      }
      ++accepted;
    } catch (const Error&) {
      ++rejected;
    } catch (const std::exception& e) {
      ADD_FAILURE() << typeid(e).name() << ": " << e.what() << " for " << printable(text);
    }
  }
  std::cout << "option texts: " << accepted << " accepted, " << rejected << " rejected\n";
  EXPECT_GT(accepted, 100);
}

}  // namespace
}  // namespace physgrad::experiments
