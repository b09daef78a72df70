// A seeded random-input test of the config and option parsers: random documents (plausible and
// garbage keys and values, truncated and mutated, random bytes, deep nesting, huge numbers,
// unicode) resolve to settings that resolve to themselves, or throw Error, nothing else.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <limits>
#include <map>
#include <random>
#include <typeinfo>

#include "physgrad/run/life/config_file.hpp"
#include "registry.hpp"
#include "physgrad/run/life/experiment.hpp"
#include "physgrad/error.hpp"

namespace physgrad::run {
namespace {

using json = nlohmann::json;

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
    const Experiment& experiment = *random.pick(experiments::builtin_registry().experiments());
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
    const Experiment& experiment = *random.pick(experiments::builtin_registry().experiments());
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
}  // namespace physgrad::run
