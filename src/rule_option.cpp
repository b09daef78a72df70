#include "physgrad/rule_option.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "physgrad/types.hpp"

namespace physgrad {

namespace {

// A value as a message shows it: numbers in the shortest form that reads back exactly (2, 1.5,
// 1e-06), nan and ±inf by name, text in quotes.
std::string value_text(const nlohmann::json& value) {
  if (value.is_string()) return in_quotes(value.get<std::string>());
  std::string text = value.dump();
  if (value.is_number_float()) {
    const double v = value.get<double>();
    if (std::isnan(v)) return "nan";
    if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
    if (text.size() > 2 && text.compare(text.size() - 2, 2, ".0") == 0) text.resize(text.size() - 2);
  }
  return text;
}

}  // namespace

bool OptionRange::contains(const nlohmann::json& value) const {
  if (type == Type::kChoice) {
    return value.is_string() &&
           std::find(choices.begin(), choices.end(), value.get<std::string>()) != choices.end();
  }
  if (!value.is_number()) return false;
  const double v = value.get<double>();
  if (!std::isfinite(v)) return false;
  if (type == Type::kInteger &&
      (v != std::floor(v) || std::abs(v) > std::numeric_limits<int>::max())) {
    return false;
  }
  const bool above = min_open ? v > min : v >= min;
  const bool below = max_open ? v < max : v <= max;
  return above && below;
}

std::string OptionRange::text() const {
  if (type == Type::kChoice) return "one of: " + comma_list(choices);
  const bool has_min = std::isfinite(min), has_max = std::isfinite(max);
  // An integer's bounds in all their digits (2147483647, not 2.14748e+09).
  const auto number = [this](double value) {
    return type == Type::kInteger ? std::to_string(static_cast<long long>(value))
                                  : report_number(value);
  };
  std::string bounds;
  if (has_min && has_max) {
    bounds = "in " + std::string(min_open ? "(" : "[") + number(min) + ", " + number(max) +
             (max_open ? ")" : "]");
  } else if (has_min) {
    bounds = (min_open ? "> " : "≥ ") + number(min);
  } else if (has_max) {
    bounds = (max_open ? "< " : "≤ ") + number(max);
  }
  if (type == Type::kInteger) return bounds.empty() ? "an integer" : "an integer " + bounds;
  return bounds.empty() ? "finite" : bounds;
}

OptionRange OptionRange::common(const OptionRange& other) const {
  if (type != other.type) throw Error("options of different types cannot share one range");
  OptionRange out = *this;
  if (type == Type::kChoice) {
    out.choices.clear();
    for (const std::string& name : choices) {
      if (std::find(other.choices.begin(), other.choices.end(), name) != other.choices.end()) {
        out.choices.push_back(name);
      }
    }
    if (out.choices.empty()) throw Error("the options share no value");
    return out;
  }
  if (other.min > min || (other.min == min && other.min_open)) {
    out.min = other.min;
    out.min_open = other.min_open;
  }
  if (other.max < max || (other.max == max && other.max_open)) {
    out.max = other.max;
    out.max_open = other.max_open;
  }
  if (out.min > out.max || (out.min == out.max && (out.min_open || out.max_open))) {
    throw Error("the options share no value");
  }
  return out;
}

namespace {
OptionRange real_range(double min, bool min_open, double max, bool max_open) {
  OptionRange range;
  range.min = min;
  range.min_open = min_open;
  range.max = max;
  range.max_open = max_open;
  return range;
}
}  // namespace

OptionRange positive() { return real_range(0, true, kInf, false); }
OptionRange non_negative() { return real_range(0, false, kInf, false); }
OptionRange fraction() { return real_range(0, false, 1, true); }
OptionRange open_fraction() { return real_range(0, true, 1, true); }
OptionRange integer_at_least(int min) {
  // Bounded by what the option's int can hold: a larger count is refused where it is given,
  // not found when the rule is made, after a run claimed its folder.
  OptionRange range = real_range(min, false, std::numeric_limits<int>::max(), false);
  range.type = OptionRange::Type::kInteger;
  return range;
}
OptionRange any_finite() { return real_range(-kInf, false, kInf, false); }

Error option_range_error(std::string_view rule, const OptionDescription& option,
                         const nlohmann::json& value) {
  return Error(std::string(rule) + ": " + option.name + " must be " + option.range.text() +
               ", got " + value_text(value));
}

}  // namespace physgrad
