#include "physgrad/report/plot_axes.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <utility>

namespace physgrad::plot {

using svg::num;

double Scale::operator()(double v) const {
  const double t = log ? std::log10(v) : v;
  return p0 + (t - lo) / (hi - lo) * (p1 - p0);
}

bool usable(double v, bool log) { return std::isfinite(v) && (!log || v > 0); }

namespace {

// 1, 2 or 5 times a power of ten, at least `raw`.
double nice_step(double raw) {
  const double decade = std::pow(10.0, std::floor(std::log10(raw)));
  const double f = raw / decade;
  return (f <= 1 ? 1 : f <= 2 ? 2 : f <= 5 ? 5 : 10) * decade;
}

// Multiples of `step` in [lo, hi].
std::vector<Tick> linear_ticks(double lo, double hi, double step) {
  std::vector<Tick> ticks;
  const auto first = static_cast<long long>(std::ceil(lo / step - 1e-6));
  const auto last = static_cast<long long>(std::floor(hi / step + 1e-6));
  for (long long k = first; k <= last; ++k) {
    const double v = static_cast<double>(k) * step;
    ticks.push_back({v, tick_label(v, step)});
  }
  return ticks;
}

int exponent_of(double v) { return static_cast<int>(std::floor(std::log10(v) + 1e-9)); }

// m × 10^k for a positive v: plain decimals from 0.001 to 9999, "2e-5" style otherwise.
std::string log_label(double v) {
  const int k = exponent_of(v);
  const double m = std::round(v / std::pow(10.0, k));
  std::array<char, 32> buf{};
  if (k >= -3 && k <= 3) {
    std::snprintf(buf.data(), buf.size(), "%.*f", std::max(0, -k), v);
  } else {
    std::snprintf(buf.data(), buf.size(), "%ge%d", m, k);
  }
  return buf.data();
}

// The largest m × 10^k ≤ v and the smallest ≥ v (m = 1 … 10), for v > 0.
double nice_floor(double v) {
  const double decade = std::pow(10.0, exponent_of(v));
  return std::max(1.0, std::floor(v / decade + 1e-9)) * decade;
}
double nice_ceil(double v) {
  const double decade = std::pow(10.0, exponent_of(v));
  return std::ceil(v / decade - 1e-9) * decade;
}

// Ticks of a log axis over [lo, hi] (data units, lo > 0). Over more than two decades: the
// decades, about eight labelled, with 2…9 × 10^k as minor ticks up to six decades. Over at
// most two: every m × 10^k, all labelled when there are at most ten, else 1, 2 and 5; when that
// gives fewer than three ticks, evenly spaced ones as on a linear axis.
std::vector<Tick> log_ticks(double lo, double hi) {
  std::vector<Tick> ticks;
  const int a = exponent_of(lo), b = exponent_of(hi) + 1;
  const double span = std::log10(hi / lo);
  const auto in_range = [&](double v) { return v >= lo * (1 - 1e-9) && v <= hi * (1 + 1e-9); };
  if (span > 2) {
    const int every = std::max(1, (b - a + 7) / 8);
    for (int k = a; k <= b; ++k) {
      const double decade = std::pow(10.0, k);
      if (in_range(decade)) ticks.push_back({decade, k % every == 0 ? log_label(decade) : ""});
      for (int m = 2; m <= 9 && span <= 6; ++m) {
        if (in_range(m * decade)) ticks.push_back({m * decade, ""});
      }
    }
    return ticks;
  }
  for (int k = a; k <= b; ++k) {
    for (int m = 1; m <= 9; ++m) {
      const double v = m * std::pow(10.0, k);
      if (in_range(v)) ticks.push_back({v, log_label(v)});
    }
  }
  if (ticks.size() < 3) {  // a narrow range such as [0.9, 1]: evenly spaced nice values
    const double step = nice_step((hi - lo) / 5);
    ticks = linear_ticks(lo, hi, step);
    ticks.erase(std::remove_if(ticks.begin(), ticks.end(), [](const Tick& t) { return t.value <= 0; }),
                ticks.end());
    return ticks;
  }
  if (ticks.size() > 10) {
    for (Tick& t : ticks) {
      const double m = std::round(t.value / std::pow(10.0, exponent_of(t.value)));
      if (m != 1 && m != 2 && m != 5) t.label.clear();
    }
  }
  return ticks;
}

}  // namespace

std::string tick_label(double v, double step) {
  const int step_exponent = static_cast<int>(std::floor(std::log10(step) + 1e-9));
  std::array<char, 40> buf{};
  if (step_exponent >= -6 && std::abs(v) < 1e7) {
    std::snprintf(buf.data(), buf.size(), "%.*f", std::max(0, -step_exponent), v);
  } else {
    const int digits =
        static_cast<int>(std::floor(std::log10(std::max(std::abs(v), step)))) - step_exponent + 1;
    std::snprintf(buf.data(), buf.size(), "%.*g", std::clamp(digits, 1, 17), v);
  }
  std::string s = buf.data();
  return s == "-0" ? "0" : s;
}

Axis data_axis(double lo, double hi, bool found, bool log, double p0, double p1) {
  if (log) {
    if (!found) {
      lo = 1;
      hi = 10;
    }
    double a = nice_floor(lo), b = nice_ceil(hi);
    if (a == b) {
      a = nice_floor(a * 0.999);
      b = nice_ceil(b * 1.001);
    }
    if (std::log10(b / a) > 2) {
      a = std::pow(10.0, exponent_of(lo));
      b = std::pow(10.0, std::ceil(std::log10(hi) - 1e-9));
      if (a == b) b *= 10;
    }
    return {{std::log10(a), std::log10(b), true, p0, p1}, log_ticks(a, b)};
  }
  if (!found) {
    lo = 0;
    hi = 1;
  } else if (lo == hi) {
    const double pad = lo == 0 ? 1 : 0.1 * std::abs(lo);
    lo -= pad;
    hi += pad;
  }
  // About five intervals of a nice step; the next smaller nice step when it wastes less room
  // past the data (a budget of 30.01 s gives 0…35, not 0…40) with at most twelve intervals.
  const auto widened = [lo, hi](double step) {
    return std::pair{std::floor(lo / step + 1e-9) * step, std::ceil(hi / step - 1e-9) * step};
  };
  double step = nice_step((hi - lo) / 5);
  auto [a, b] = widened(step);
  const double mantissa = step / std::pow(10.0, std::floor(std::log10(step) + 1e-9));
  const double smaller = step * (mantissa > 4 ? 0.4 : 0.5);  // 5 → 2, 2 → 1, 1 → 0.5
  const auto [c, d] = widened(smaller);
  if (d - c < b - a - 1e-9 * step && (d - c) / smaller <= 12 + 1e-9) {
    step = smaller;
    a = c;
    b = d;
  }
  return {{a, b, false, p0, p1}, linear_ticks(a, b, step)};
}

Axis fixed_axis(double lo, double hi, bool log, double p0, double p1) {
  if (log) return {{std::log10(lo), std::log10(hi), true, p0, p1}, log_ticks(lo, hi)};
  return {{lo, hi, false, p0, p1}, linear_ticks(lo, hi, nice_step((hi - lo) / 6))};
}

std::string grid_lines(const svg::Box& b, const Axis& ax, const Axis& ay) {
  std::string d;
  for (const Tick& t : ax.ticks) {
    const double x = ax.scale(t.value);
    if (!t.label.empty() && x > b.left + 0.5 && x < b.right - 0.5) {
      d += std::string("M") + num(x) + " " + num(b.top) + "V" + num(b.bottom);
    }
  }
  for (const Tick& t : ay.ticks) {
    const double y = ay.scale(t.value);
    if (!t.label.empty() && y > b.top + 0.5 && y < b.bottom - 0.5) {
      d += std::string("M") + num(b.left) + " " + num(y) + "H" + num(b.right);
    }
  }
  return svg::path(d, "stroke=\"#e3e3e3\" fill=\"none\"");
}

double widest_label(const Axis& axis) {
  double widest = 0;
  for (const Tick& t : axis.ticks) widest = std::max(widest, svg::text_width(t.label));
  return widest;
}

// Tick labels end 8 px left of the frame; a y axis label is 12 px high, centred 16 px left of
// the labels, so that it needs 34 px beside them.
double left_margin(const Axis& ay, bool has_y_label) {
  return widest_label(ay) + (has_y_label ? 34 : 16);
}

double top_margin(bool has_title) { return has_title ? 36 : 16; }

std::vector<std::string> title_lines(const std::string& title, int width) {
  if (title.empty()) return {};
  if (svg::text_width(title, 14) + 10 <= width) return {title};
  std::size_t best = std::string::npos;
  for (std::size_t at = title.find(' '); at != std::string::npos; at = title.find(' ', at + 1)) {
    const auto off = [&](std::size_t k) {
      return std::abs(static_cast<double>(k) - static_cast<double>(title.size()) / 2);
    };
    if (best == std::string::npos || off(at) < off(best)) best = at;
  }
  if (best == std::string::npos) return {title};
  return {title.substr(0, best), title.substr(best + 1)};
}

double top_margin(const std::string& title, int width) {
  return title.empty() ? 16 : 36 + 17 * static_cast<double>(title_lines(title, width).size() - 1);
}

std::string axes(int width, const svg::Box& b, const Axis& ax, const Axis& ay,
                 const AxisTitles& titles) {
  std::string out = svg::rect(b, "fill=\"none\" stroke=\"#333\"");
  std::string marks, labels;
  for (const Tick& t : ax.ticks) {
    const double x = ax.scale(t.value);
    if (!(x >= b.left - 0.5 && x <= b.right + 0.5)) continue;
    marks += std::string("M") + num(x) + " " + num(b.bottom) + "v" + (t.label.empty() ? "3" : "5");
    if (!t.label.empty()) labels += svg::text(x, b.bottom + 18, t.label, "text-anchor=\"middle\"");
  }
  for (const Tick& t : ay.ticks) {
    const double y = ay.scale(t.value);
    if (!(y >= b.top - 0.5 && y <= b.bottom + 0.5)) continue;
    marks += std::string("M") + num(b.left) + " " + num(y) + "h" + (t.label.empty() ? "-3" : "-5");
    if (!t.label.empty()) labels += svg::text(b.left - 8, y + 4, t.label, "text-anchor=\"end\"");
  }
  out += svg::path(marks, "stroke=\"#333\" fill=\"none\"");
  out += "<g fill=\"#333\">\n" + labels + "</g>\n";
  const std::vector<std::string> lines = title_lines(titles.title, width);
  for (std::size_t k = 0; k < lines.size(); ++k) {
    out += svg::text(width / 2.0, 22 + 17 * static_cast<double>(k), lines[k],
                     "text-anchor=\"middle\" font-size=\"14\" font-weight=\"bold\"");
  }
  if (!titles.x_label.empty()) {
    out += svg::text((b.left + b.right) / 2, b.bottom + 38, titles.x_label,
                     "text-anchor=\"middle\"");
  }
  if (!titles.y_label.empty()) {
    const double x = std::max(14.0, b.left - 16 - widest_label(ay));
    out += "<text transform=\"translate(" + num(x) + " " + num((b.top + b.bottom) / 2) +
           ") rotate(-90)\" text-anchor=\"middle\">" + xml_escape(titles.y_label) + "</text>\n";
  }
  return out;
}

std::string right_ticks(double left, const svg::Box& b, const Axis& axis) {
  std::string marks, labels;
  for (const Tick& t : axis.ticks) {
    const double y = axis.scale(t.value);
    if (!(y >= b.top - 0.5 && y <= b.bottom + 0.5)) continue;
    marks += std::string("M") + num(left) + " " + num(y) + "h" + (t.label.empty() ? "3" : "5");
    if (!t.label.empty()) labels += svg::text(left + 8, y + 4, t.label);
  }
  return svg::path(marks, "stroke=\"#333\" fill=\"none\"") + "<g fill=\"#333\">\n" + labels +
         "</g>\n";
}

}  // namespace physgrad::plot
