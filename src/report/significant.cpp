#include "physgrad/report/significant.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

namespace physgrad {

Spread spread_of(std::vector<double> values) {
  std::erase_if(values, [](double v) { return !std::isfinite(v); });
  Spread s;
  s.count = values.size();
  if (values.empty()) return s;
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  s.median = n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
  s.low = values.front();
  s.high = values.back();
  return s;
}

int digits_for(const Spread& s) {
  if (s.count < 2 || !(s.high > s.low) || s.median == 0) return 2;
  const double magnitude = std::floor(std::log10(std::abs(s.median)));
  const double width = std::floor(std::log10(s.high - s.low));
  return static_cast<int>(std::clamp(magnitude - width + 2, 1.0, 6.0));
}

std::string with_digits(double value, int digits) {
  if (std::isnan(value)) return "–";
  if (!std::isfinite(value)) return value > 0 ? "inf" : "-inf";
  if (value == std::round(value) && std::abs(value) < 1e15) {
    return std::to_string(std::llround(value));
  }
  const double exponent = std::floor(std::log10(std::abs(value)));
  if (exponent >= digits - 1 && exponent < 6) {  // 545.5 at two digits: 550, not 5.5e+02
    const double unit = std::pow(10.0, exponent - digits + 1);
    return std::to_string(std::llround(std::round(value / unit) * unit));
  }
  // Trailing zeros kept (1.0, 0.50): they are digits the spread supports.
  std::array<char, 40> buf{};
  std::snprintf(buf.data(), buf.size(), "%#.*g", digits, value);
  std::string out = buf.data();
  // One digit keeps no point: "4." and "4.e-05" read "4" and "4e-05".
  const std::size_t point = out.find('.');
  if (point != std::string::npos && (point + 1 == out.size() || out[point + 1] == 'e')) {
    out.erase(point, 1);
  }
  return out;
}

std::string median_and_range(const Spread& s) {
  if (s.count == 0) return "–";
  const int digits = digits_for(s);
  const std::string m = with_digits(s.median, digits);
  if (!(s.high > s.low)) return m;
  return m + " (" + with_digits(s.low, digits) + "–" + with_digits(s.high, digits) + ")";
}

int ratio_digits(const Spread& a, const Spread& b) {
  if (a.count < 2 || b.count < 2 || a.median == 0 || b.median == 0) return 2;
  const double relative = std::max((a.high - a.low) / std::abs(a.median),
                                   (b.high - b.low) / std::abs(b.median));
  if (!(relative > 0)) return 2;
  return static_cast<int>(std::clamp(std::floor(-std::log10(relative)) + 2, 1.0, 4.0));
}

std::string ratio_text(const Spread& a, const Spread& b) {
  return with_digits(a.median / b.median, ratio_digits(a, b));
}

}  // namespace physgrad
