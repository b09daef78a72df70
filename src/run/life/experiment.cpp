#include "physgrad/run/life/experiment.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "physgrad/run/life/interrupt.hpp"
#include "physgrad/error.hpp"
#include "physgrad/memory.hpp"
#include "physgrad/text.hpp"

namespace physgrad::run {

namespace {

using Kind = OptionSpec::Kind;

std::string trim(const std::string& text) {
  const auto first = text.find_first_not_of(" \t");
  if (first == std::string::npos) return {};
  return text.substr(first, text.find_last_not_of(" \t") - first + 1);
}

// Comma-separated items; an empty item (",1", "1,,2", "1,") stays in the list as "".
std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> items;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = text.find(',', start);
    items.push_back(trim(text.substr(start, comma == std::string::npos ? comma : comma - start)));
    if (comma == std::string::npos) return items;
    start = comma + 1;
  }
}

std::string format_number(double value) {
  std::ostringstream out;
  out.precision(10);
  out << value;
  return out.str();
}

// Decimal notation, the one form of a number on the command line and in config files: an
// optional sign, digits with at most one point (reals), and for reals an optional exponent
// (e or E, an optional sign, digits). What strtod would read besides — hexadecimal (0x10,
// 0x1p4), inf, nan, white space — is not a number here.
bool is_decimal(const std::string& item, bool whole) {
  std::size_t at = item.empty() || (item[0] != '+' && item[0] != '-') ? 0 : 1;
  const auto digits = [&item, &at] {
    const std::size_t first = at;
    while (at < item.size() && item[at] >= '0' && item[at] <= '9') ++at;
    return at - first;
  };
  std::size_t mantissa = digits();
  if (!whole && at < item.size() && item[at] == '.') {
    ++at;
    mantissa += digits();
  }
  if (mantissa == 0) return false;
  if (!whole && at < item.size() && (item[at] == 'e' || item[at] == 'E')) {
    ++at;
    if (at < item.size() && (item[at] == '+' || item[at] == '-')) ++at;
    if (digits() == 0) return false;
  }
  return at == item.size();
}

// A number is exactly its decimal text: blanks around it ('5 ', ' 5') make it no number, as
// any other character would (a list's entries are cut at the commas and their blanks dropped
// before they get here).
double parse_real(const OptionSpec& spec, const std::string& text) {
  if (!is_decimal(text, false)) {
    throw Error(spec.flag() + ": " + in_quotes(text) +
                " is not a number (decimal, like 16, -2.5 or 1e-3)");
  }
  // strtod, not stod: a value below the normal range (1e-310) is kept as the subnormal it is.
  errno = 0;
  const double value = std::strtod(text.c_str(), nullptr);
  if (errno == ERANGE && std::isinf(value)) {
    throw Error(spec.flag() + ": " + in_quotes(text) + " is out of the range of a double");
  }
  if (errno == ERANGE && value == 0) {
    throw Error(spec.flag() + ": " + in_quotes(text) +
                " is too close to 0 for a double (it would read 0)");
  }
  const bool below = spec.min_exclusive ? !(value > spec.min) : !(value >= spec.min);
  const bool beyond = spec.max_exclusive ? !(value < spec.max) : !(value <= spec.max);
  if (below || beyond || (spec.nonzero && value == 0)) {
    throw Error(spec.flag() + ": must be " + describe_range(spec) + ", got " + in_quotes(text));
  }
  return value;
}

long long parse_integer(const OptionSpec& spec, const std::string& text) {
  if (!is_decimal(text, true)) {
    throw Error(spec.flag() + ": " + in_quotes(text) +
                " is not a whole number (decimal digits, like 16)");
  }
  errno = 0;
  const long long value = std::strtoll(text.c_str(), nullptr, 10);
  const bool beyond = errno == ERANGE;  // a whole number beyond ±9.2e18
  const auto as_double = static_cast<double>(value);
  if (beyond || as_double < spec.min || as_double > spec.max || (spec.nonzero && value == 0)) {
    throw Error(spec.flag() + ": must be " + describe_range(spec) + ", got " + in_quotes(text));
  }
  return value;
}

std::string parse_text(const OptionSpec& spec, const std::string& text) {
  if (const std::string problem = text_problem(text); !problem.empty()) {
    throw Error(spec.flag() + ": " + in_quotes(text) + " " + problem);
  }
  const std::string item = trim(text);
  if (!spec.choices.empty() &&
      std::find(spec.choices.begin(), spec.choices.end(), item) == spec.choices.end()) {
    throw Error(spec.flag() + ": " + unknown_name_text("value", item, spec.choices));
  }
  return item;
}

}  // namespace

namespace {
OptionSpec make_option(std::string name, Kind kind, std::string default_text, std::string help) {
  OptionSpec spec;
  spec.name = std::move(name);
  spec.kind = kind;
  spec.default_text = std::move(default_text);
  spec.help = std::move(help);
  return spec;
}
}  // namespace

OptionSpec real_option(std::string name, std::string default_text, std::string help) {
  return make_option(std::move(name), Kind::kReal, std::move(default_text), std::move(help));
}
OptionSpec integer_option(std::string name, std::string default_text, std::string help) {
  return make_option(std::move(name), Kind::kInteger, std::move(default_text), std::move(help));
}
OptionSpec text_option(std::string name, std::string default_text, std::string help) {
  return make_option(std::move(name), Kind::kText, std::move(default_text), std::move(help));
}
OptionSpec real_list_option(std::string name, std::string default_text, std::string help) {
  return make_option(std::move(name), Kind::kRealList, std::move(default_text), std::move(help));
}
OptionSpec text_list_option(std::string name, std::string default_text, std::string help) {
  return make_option(std::move(name), Kind::kTextList, std::move(default_text), std::move(help));
}

std::string describe_range(const OptionSpec& spec) {
  if (spec.kind == Kind::kText || spec.kind == Kind::kTextList) {
    return spec.choices.empty() ? "" : "one of: " + comma_list(spec.choices);
  }
  std::vector<std::string> parts;
  const bool has_min = std::isfinite(spec.min);
  const bool has_max = std::isfinite(spec.max);
  if (has_min && has_max) {
    parts.push_back("in " + std::string(spec.min_exclusive ? "(" : "[") + format_number(spec.min) +
                    ", " + format_number(spec.max) + (spec.max_exclusive ? ")" : "]"));
  } else if (has_min) {
    parts.push_back((spec.min_exclusive ? "> " : "≥ ") + format_number(spec.min));
  } else if (has_max) {
    parts.push_back((spec.max_exclusive ? "< " : "≤ ") + format_number(spec.max));
  }
  if (spec.nonzero) parts.push_back("nonzero");
  std::string out = comma_list(parts);
  if (out.empty()) out = spec.kind == Kind::kInteger ? "a whole number" : "a finite number";
  return out;
}

std::string flag_name(std::string rule_option) {
  std::replace(rule_option.begin(), rule_option.end(), '_', '-');
  return rule_option;
}

OptionSpec rule_option_spec(const std::string& rule_option, std::optional<RuleKind> kind,
                            const std::vector<std::string>& offered) {
  const std::string name = flag_name(rule_option);
  const SharedRuleOption shared = shared_rule_option(rule_option, kind);
  std::vector<std::string> rules;
  for (const std::string& id : shared.rules) {
    if (std::find(offered.begin(), offered.end(), id) != offered.end()) rules.push_back(id);
  }
  return option_in_range(name, shared.option.range,
                         shared.option.help + " (" +
                             (rules.empty() ? "" : comma_list(rules) + "; ") +
                             "default: each rule's own)");
}

OptionSpec option_in_range(std::string name, const OptionRange& range, std::string help) {
  if (range.type == OptionRange::Type::kChoice) {
    return text_option(std::move(name), "", std::move(help)).one_of(range.choices);
  }
  OptionSpec spec = range.type == OptionRange::Type::kInteger
                        ? integer_option(std::move(name), "", std::move(help))
                        : real_option(std::move(name), "", std::move(help));
  spec.min = range.min;
  spec.min_exclusive = range.min_open;
  spec.max = range.max;
  spec.max_exclusive = range.max_open;
  return spec;
}

RuleSettings rule_settings(const Settings& settings, RuleKind kind) {
  RuleSettings rule;
  for (const std::string& name : rule_option_names(kind)) {
    const std::string flag = flag_name(name);
    if (settings.json().contains(flag) && !settings.json().at(flag).is_null()) {
      rule[name] = settings.json().at(flag);
    }
  }
  return rule;
}

nlohmann::json parse_option(const OptionSpec& spec, const std::string& text) {
  switch (spec.kind) {
    case Kind::kReal: return parse_real(spec, text);
    case Kind::kInteger: return parse_integer(spec, text);
    case Kind::kText: return parse_text(spec, text);
    case Kind::kRealList:
    case Kind::kTextList: {
      if (trim(text).empty()) throw Error(spec.flag() + ": needs at least one value");
      nlohmann::json items = nlohmann::json::array();
      std::vector<std::string> entries, names;  // as given, and as labels show them
      for (const std::string& item : split_list(text)) {
        if (item.empty()) throw Error(spec.flag() + ": empty entry in list " + in_quotes(text));
        const bool number = spec.kind == Kind::kRealList;
        const double value = number ? parse_real(spec, item) : 0.0;
        const std::string name = number ? format_value(value) : parse_text(spec, item);
        const auto same = std::find(names.begin(), names.end(), name);
        if (spec.distinct && same != names.end()) {
          const std::string& first = entries[static_cast<std::size_t>(same - names.begin())];
          throw Error(spec.flag() + ": " +
                      (first == item ? in_quotes(item) + " is listed twice"
                                     : in_quotes(first) + " and " + in_quotes(item) +
                                           " both read " + in_quotes(name) +
                                           " in labels and file names"));
        }
        entries.push_back(item);
        names.push_back(name);
        items.push_back(number ? nlohmann::json(value) : nlohmann::json(name));
      }
      return items;
    }
  }
  return nullptr;
}

const nlohmann::json& Settings::at(const std::string& name) const {
  if (!values_.contains(name) || values_.at(name).is_null()) {
    throw Error("setting " + in_quotes(name) + " is not set");
  }
  return values_.at(name);
}

bool Settings::has(const std::string& name) const {
  return values_.contains(name) && !values_.at(name).is_null();
}
double Settings::real(const std::string& name) const { return at(name).get<double>(); }
long long Settings::integer(const std::string& name) const { return at(name).get<long long>(); }
std::string Settings::text(const std::string& name) const { return at(name).get<std::string>(); }
std::vector<double> Settings::reals(const std::string& name) const {
  return at(name).get<std::vector<double>>();
}
std::vector<std::string> Settings::texts(const std::string& name) const {
  return at(name).get<std::vector<std::string>>();
}

void RunContext::add_metrics_row(nlohmann::json row) { metrics_.push_back(std::move(row)); }

void RunContext::progress(const std::string& line) {
  if (show_progress_) show_progress_(line);
}

void RunContext::progress_event(const std::string& line) {
  finish_progress();
  if (show_event_) show_event_(line);
}

void RunContext::finish_progress() {
  if (end_progress_) end_progress_();
}

void RunContext::check_interrupt() const {
  if (stop_ != nullptr && stop_->load()) {
    stop_point_reached();
    throw Interrupted(experiment_name_ + ": stopped on request");
  }
}

std::vector<OptionSpec> common_options(const Experiment& experiment) {
  std::string defaults = comma_list(experiment.default_optimizers());
  defaults.erase(std::remove(defaults.begin(), defaults.end(), ' '), defaults.end());
  return {
      text_list_option("optimizers", defaults, "comma-separated update rules to run")
          .one_of(experiment.optimizer_choices()),
      integer_option("iters",
                     experiment.default_iterations() > 0
                         ? std::to_string(experiment.default_iterations())
                         : std::string(),
                     "iterations per run")
          .at_least(1)
          .at_most(1e9)
          .quick("2"),
      rule_option_spec("lr", std::nullopt, experiment.optimizer_choices()),
      integer_option("threads", "",
                     "BLAS threads (default: OPENBLAS_NUM_THREADS or OMP_NUM_THREADS if set, "
                     "else 1)")
          .at_least(1)
          .at_most(256),
      integer_option("distributed-gram-rows", "",
                     "under mpirun, B·m from which the ranks share the Gram step "
                     "(ScaLAPACK; 0: never; default 8192, docs/distributed.md)")
          .at_least(0)
          .at_most(1e9),
      integer_option("seed", "0", "random seed of stochastic parts (data, initialisation)").at_least(0).at_most(4294967295.0),
      text_option("out", "", "run folder (default: runs/NAME-<timestamp>)"),
  };
}


std::vector<OptionSpec> all_options(const Experiment& experiment) {
  std::vector<OptionSpec> options = common_options(experiment);
  for (OptionSpec& spec : experiment.options()) options.push_back(std::move(spec));
  // A rule option the Adam part of the Adam→ twins takes apart (--pretrain-lr beside --lr) says
  // which runs each reaches.
  for (OptionSpec& spec : options) {
    const std::string part = "pretrain-" + spec.name;
    if (std::any_of(options.begin(), options.end(),
                    [&](const OptionSpec& other) { return other.name == part; })) {
      spec.help += "; with --pretrain, the Adam part of the Adam→ twins too unless --" + part +
                   " is given";
    }
  }
  return options;
}

const OptionSpec& find_option(const Experiment& experiment, const std::vector<OptionSpec>& specs,
                              const std::string& name) {
  std::vector<std::string> known;
  for (const OptionSpec& spec : specs) {
    if (spec.name == name) return spec;
    known.push_back(spec.name);
  }
  throw Error("experiment " + in_quotes(experiment.name()) + ": " +
              unknown_name_text("option", name, known));
}

Settings resolve_settings(const Experiment& experiment,
                          const std::vector<std::pair<std::string, std::string>>& given) {
  const std::vector<OptionSpec> specs = all_options(experiment);
  nlohmann::json values = nlohmann::json::object();
  for (const auto& [name, text] : given) {
    values[name] = parse_option(find_option(experiment, specs, name), text);
  }
  for (const OptionSpec& spec : specs) {
    if (values.contains(spec.name)) continue;
    values[spec.name] = spec.default_text.empty() ? nlohmann::json(nullptr)
                                                  : parse_option(spec, spec.default_text);
  }
  Settings settings(std::move(values));
  experiment.validate(settings);
  for (const OptionSpec& spec : specs) {
    if (!spec.bytes_each || !settings.has(spec.name)) continue;
    const double each = spec.bytes_each(settings);
    const long long count = settings.integer(spec.name);
    require_memory(static_cast<double>(count) * each,
                   spec.flag() + ": " + std::to_string(count) + " (items of at least " +
                       format_bytes(each) + " each)");
  }
  return settings;
}

std::string format_value(double value) {
  std::ostringstream out;
  out.precision(4);
  out << value;
  return out.str();
}

double median(std::vector<double> values) {
  std::erase_if(values, [](double v) { return std::isnan(v); });
  if (values.empty()) return NAN;
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

}  // namespace physgrad::run
