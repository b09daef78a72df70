// Config files and the option table: JSON option values are checked like flags and resolve to
// the same settings, saved settings resolve to themselves, every bad document is one Error with
// an exact message. (The seeded random-input test of these parsers: config_fuzz_test.cpp.)
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <tuple>

#include "physgrad/run/life/config_file.hpp"
#include "registry.hpp"
#include "physgrad/run/life/experiment.hpp"
#include "physgrad/error.hpp"

namespace physgrad::run {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

Settings resolve_json(const std::string& name, const std::string& text,
                      const OptionTexts& flags = {}) {
  const Experiment& experiment = experiments::builtin_registry().find(name);
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
  for (const OptionSpec& spec : all_options(experiments::builtin_registry().find(name))) {
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
              resolve_settings(experiments::builtin_registry().find(name), flags).json())
        << name;
  }
}

TEST(ConfigFile, SavedSettingsResolveToThemselvesBareOrAsAWholeConfig) {
  for (const auto& experiment : experiments::builtin_registry()) {
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
  const Experiment& comparison = experiments::builtin_registry().find("comparison");
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
  for (const auto& experiment : experiments::builtin_registry()) {
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
  const RunContext::Table table = options_table(experiments::builtin_registry().find("scaled-toy"));
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

}  // namespace
}  // namespace physgrad::run
