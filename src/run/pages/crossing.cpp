#include "physgrad/run/pages/crossing.hpp"

#include <algorithm>
#include <iomanip>
#include <sstream>

#include "physgrad/run/pages/learning_verdict.hpp"  // ratio_text, value_text

namespace physgrad::run {

namespace {

// The median of `values` where NaN (never got there) counts as the largest.
double median_never_last(std::vector<double> values) {
  if (values.empty()) return NAN;
  std::sort(values.begin(), values.end(), [](double a, double b) {
    return std::isnan(b) ? !std::isnan(a) : (!std::isnan(a) && a < b);
  });
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

// A measured number as it is: whole below 10¹⁵ in full, else three significant digits.
std::string measured_text(double value) {
  if (value == std::round(value) && std::abs(value) < 1e15) {
    return std::to_string(std::llround(value));
  }
  return value_text(value);
}

// `value` rounded to the power of 10 at or below `width` (> 0; a width a rounding error below a
// power of 10, 1.0 − 0.99, counts as that power).
std::string at_resolution(double value, double width) {
  const double exponent = std::floor(std::log10(width) + 1e-9);
  const double unit = std::pow(10.0, exponent);
  const double rounded = std::round(value / unit) * unit;
  if (exponent >= 0) return std::to_string(std::llround(rounded));
  std::ostringstream out;
  out << std::fixed << std::setprecision(static_cast<int>(-exponent)) << rounded;
  return out.str();
}

// `ratio` with one significant digit ("40×").
std::string one_digit(double ratio) {
  const double unit = std::pow(10.0, std::floor(std::log10(ratio)));
  const double rounded = std::round(ratio / unit) * unit;
  std::ostringstream out;
  out << rounded;
  return out.str() + "×";
}

}  // namespace

Crossing crossing_of(const std::vector<TrainingRecord>& history, double level,
                     const std::function<double(const TrainingRecord&)>& value,
                     const std::function<double(const TrainingRecord&)>& progress) {
  for (std::size_t k = 0; k < history.size(); ++k) {
    const double v = value(history[k]);
    if (!(v <= level)) continue;
    const double p1 = progress(history[k]);
    if (k == 0) return {p1, p1, p1};
    const double before = value(history[k - 1]);
    double t = 1;
    if (std::isfinite(before) && before > v) {
      const bool logs = v > 0 && level > 0;
      t = logs ? std::log(before / level) / std::log(before / v) : (before - level) / (before - v);
    }
    const double p0 = progress(history[k - 1]);
    return {p0, p1, p0 + std::clamp(t, 0.0, 1.0) * (p1 - p0)};
  }
  return {};
}

Crossing updates_crossing(const TrainingSummary& run, double level,
                          const std::function<double(const TrainingRecord&)>& value) {
  return crossing_of(run.history, level, value, [](const TrainingRecord& r) {
    return static_cast<double>(r.iteration);
  });
}

Crossing seconds_crossing(const TrainingSummary& run, double level,
                          const std::function<double(const TrainingRecord&)>& value) {
  return crossing_of(run.history, level, value,
                     [](const TrainingRecord& r) { return r.train_seconds; });
}

double updates_to_reach(const TrainingSummary& run, double level,
                        const std::function<double(const TrainingRecord&)>& value) {
  return updates_crossing(run, level, value).estimate;
}

double seconds_to_reach(const TrainingSummary& run, double level,
                        const std::function<double(const TrainingRecord&)>& value) {
  return seconds_crossing(run, level, value).estimate;
}

Crossing median_crossing(const std::vector<Crossing>& runs) {
  std::vector<double> low, high, estimate;
  for (const Crossing& c : runs) {
    low.push_back(c.low);
    high.push_back(c.high);
    estimate.push_back(c.estimate);
  }
  Crossing out{median_never_last(low), median_never_last(high), median_never_last(estimate)};
  if (std::isnan(out.low) || std::isnan(out.high) || std::isnan(out.estimate)) return {};
  return out;
}

bool is_narrow(const Crossing& c) {
  // (a relative 1e-9 over, so that a width of exactly 10 % is not lost to rounding)
  return c.reached() && c.high - c.low <= 0.1 * std::abs(c.estimate) * (1 + 1e-9);
}

std::string crossing_text(const Crossing& c) {
  if (!c.reached()) return "–";
  const double width = c.high - c.low;
  if (!(width > 0)) return measured_text(c.estimate);
  if (is_narrow(c)) return at_resolution(c.estimate, width);
  return "between " + measured_text(c.low) + " and " + measured_text(c.high);
}

RatioRange ratio_range(const Crossing& a, const Crossing& b) {
  if (!a.reached() || !b.reached() || !(b.high > 0)) return {};
  return {a.low / b.high, b.low > 0 ? a.high / b.low : (a.high > 0 ? INFINITY : NAN)};
}

std::string ratio_range_text(double low, double high) {
  if (!std::isfinite(high)) return "at least " + ratio_text(low);
  const std::string a = ratio_text(low), b = ratio_text(high);
  if (a == b) return a;
  // One digit where both ends share it, but never "1×", which would read as no advantage.
  if (one_digit(low) == one_digit(high) && one_digit(low) != "1×") return one_digit(low);
  return a.substr(0, a.size() - std::string("×").size()) + "–" + b;
}

std::string advantage_text(const RatioRange& r, const std::string& fewer, const std::string& more,
                           const std::string& same, const std::string& apart) {
  if (std::isnan(r.low) || std::isnan(r.high)) return apart;
  if (r.low >= 1.1) return ratio_range_text(r.low, r.high) + " " + fewer;
  if (r.high <= 1 / 1.1) {
    return ratio_range_text(1 / r.high, r.low > 0 ? 1 / r.low : INFINITY) + " " + more;
  }
  if (r.low > 1 / 1.1 && r.high < 1.1) return same;
  return apart;
}

}  // namespace physgrad::run
