// Rule options — the one description of each option of an update rule: its name, the member of the
// rule's options struct it is, the values it takes and its help.
// params(), setting options by name, the rules' validation and the option help of the command
// line, Python and the docs tables are all read from it.
#pragma once

#include <functional>
#include <initializer_list>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "physgrad/error.hpp"
#include "physgrad/text.hpp"

namespace physgrad {

// The values an option takes: a finite real or an integer within min…max (each end included
// unless open), or one name of a list.
struct OptionRange {
  enum class Type { kReal, kInteger, kChoice };
  Type type = Type::kReal;
  double min = -std::numeric_limits<double>::infinity();
  bool min_open = false;
  double max = std::numeric_limits<double>::infinity();
  bool max_open = false;
  std::vector<std::string> choices;  // kChoice: the names

  // Whether `value` is one of the values: a finite number within the bounds (an integral one for
  // kInteger), or one of the names.
  bool contains(const nlohmann::json& value) const;
  // "> 0", "in [0, 1)", "an integer in [1, 2147483647]", "one of: auto, svd", "finite" — after "must be".
  std::string text() const;
  // The values both ranges take (a shared option of several rules); Error when they are of
  // different types or have no value in common.
  OptionRange common(const OptionRange& other) const;
};

// The ranges the rules use.
OptionRange positive();          // (0, ∞)
OptionRange non_negative();      // [0, ∞)
OptionRange fraction();          // [0, 1): relative cutoffs and tolerances
OptionRange open_fraction();     // (0, 1)
OptionRange integer_at_least(int min);  // [min, 2³¹ − 1]: what the option's int holds
OptionRange any_finite();

// Which options a front end offers once for every rule of a kind that has them (the learning
// command line's flags; docs/cli.md), and where: kNone, only per rule (Python keywords,
// settings); kInversion, how a rule cuts and solves its inverse (rcond, precision, damping, …);
// kSchedule, the step-size schedule.
enum class OptionGroup { kNone, kInversion, kSchedule };

// What every option says about itself, whichever options struct it belongs to.
struct OptionDescription {
  std::string name;   // as params() reports it and settings name it
  OptionRange range;
  std::string help;
  std::string alias{};  // a second name settings may give it ("lr" for a line search's first step)
  OptionGroup group = OptionGroup::kNone;
};

// One option of the options struct `Options`: its description, how to read it as params()
// reports it and how to set it from a value within its range.
template <class Options>
struct RuleOption : OptionDescription {
  std::function<nlohmann::json(const Options&)> get;
  std::function<void(Options&, const nlohmann::json&)> set;
  // When given, params() lists the option only where it is true (the numerical local inverse's
  // tolerances mean nothing for the analytic one).
  std::function<bool(const Options&)> applies{};
};

template <class Options>
using OptionList = std::vector<RuleOption<Options>>;

// An option of `Options` without its accessors.
template <class Options>
RuleOption<Options> described(std::string name, OptionRange range, std::string help) {
  RuleOption<Options> option;
  option.name = std::move(name);
  option.range = std::move(range);
  option.help = std::move(help);
  return option;
}

// An option that is a member of `Options`: a real, an integer or an enum.
template <class Options>
RuleOption<Options> rule_option(std::string name, double Options::*member, OptionRange range,
                                std::string help) {
  RuleOption<Options> option = described<Options>(std::move(name), std::move(range), std::move(help));
  option.get = [member](const Options& o) { return nlohmann::json(o.*member); };
  option.set = [member](Options& o, const nlohmann::json& v) { o.*member = v.get<double>(); };
  return option;
}

template <class Options>
RuleOption<Options> rule_option(std::string name, int Options::*member, OptionRange range,
                                std::string help) {
  range.type = OptionRange::Type::kInteger;
  RuleOption<Options> option = described<Options>(std::move(name), std::move(range), std::move(help));
  option.get = [member](const Options& o) { return nlohmann::json(o.*member); };
  option.set = [member](Options& o, const nlohmann::json& v) {
    o.*member = static_cast<int>(v.get<double>());
  };
  return option;
}

// An option that is the real `member` of the struct member `outer` of `Options` (the κ or τ of a
// rule's SpectralCut `cut`), as `description` describes it.
template <class Options, class Inner>
RuleOption<Options> rule_option(const OptionDescription& description, Inner Options::*outer,
                                double Inner::*member) {
  RuleOption<Options> option;
  static_cast<OptionDescription&>(option) = description;
  option.get = [outer, member](const Options& o) { return nlohmann::json((o.*outer).*member); };
  option.set = [outer, member](Options& o, const nlohmann::json& v) {
    (o.*outer).*member = v.get<double>();
  };
  return option;
}

// `option` in the front ends' group `group` (OptionGroup).
template <class Options>
RuleOption<Options> in_group(OptionGroup group, RuleOption<Options> option) {
  option.group = group;
  return option;
}

// An enum option: `values` in the order help texts list them, each named by to_string(value).
template <class Options, class Enum>
RuleOption<Options> rule_option(std::string name, Enum Options::*member, std::vector<Enum> values,
                                std::string help) {
  OptionRange range;
  range.type = OptionRange::Type::kChoice;
  for (const Enum value : values) range.choices.push_back(to_string(value));
  RuleOption<Options> option = described<Options>(std::move(name), std::move(range), std::move(help));
  option.get = [member](const Options& o) { return nlohmann::json(to_string(o.*member)); };
  option.set = [member, values](Options& o, const nlohmann::json& v) {
    for (const Enum value : values) {
      if (to_string(value) == v.get<std::string>()) o.*member = value;
    }
  };
  return option;
}

// The options of a nested options struct (Inner::descriptors()) as options of `Options`, under
// the same names.
template <class Options, class Inner>
OptionList<Options> nested_options(Inner Options::*member) {
  OptionList<Options> out;
  for (const RuleOption<Inner>& inner : Inner::descriptors()) {
    RuleOption<Options> option;
    static_cast<OptionDescription&>(option) = inner;
    option.get = [member, get = inner.get](const Options& o) { return get(o.*member); };
    option.set = [member, set = inner.set](Options& o, const nlohmann::json& v) {
      set(o.*member, v);
    };
    if (inner.applies) {
      option.applies = [member, applies = inner.applies](const Options& o) {
        return applies(o.*member);
      };
    }
    out.push_back(std::move(option));
  }
  return out;
}

// The lists one after another.
template <class Options>
OptionList<Options> joined(std::initializer_list<OptionList<Options>> lists) {
  OptionList<Options> out;
  for (const OptionList<Options>& list : lists) out.insert(out.end(), list.begin(), list.end());
  return out;
}

// The Error "RULE: NAME must be RANGE, got VALUE".
Error option_range_error(std::string_view rule, const OptionDescription& option,
                         const nlohmann::json& value);

// Every option of `options` that applies, by name: a rule's params().
template <class Options>
nlohmann::json option_values(const Options& options) {
  nlohmann::json values = nlohmann::json::object();
  for (const RuleOption<Options>& option : Options::descriptors()) {
    if (!option.applies || option.applies(options)) values[option.name] = option.get(options);
  }
  return values;
}

// Throws option_range_error naming `rule` for the first option outside its range.
template <class Options>
void check_options(std::string_view rule, const Options& options) {
  for (const RuleOption<Options>& option : Options::descriptors()) {
    const nlohmann::json value = option.get(options);
    if (!option.range.contains(value)) throw option_range_error(rule, option, value);
  }
}

// `options` after check_options(rule, options), for a constructor's initializer list.
template <class Options>
const Options& checked(std::string_view rule, const Options& options) {
  check_options(rule, options);
  return options;
}

// `options` with the option `option` set to `value`, after checking it against the range
// (option_range_error naming `rule` otherwise).
template <class Options>
void set_option(std::string_view rule, const RuleOption<Options>& option, Options& options,
                const nlohmann::json& value) {
  if (!option.range.contains(value)) throw option_range_error(rule, option, value);
  option.set(options, value);
}

}  // namespace physgrad
