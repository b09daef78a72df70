#include "physgrad/report/svg_plot.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <unordered_map>

#include "physgrad/error.hpp"

namespace physgrad {

std::string xml_escape(std::string_view text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default:
        if (static_cast<unsigned char>(c) >= 0x20 || c == '\t' || c == '\n') out += c;
    }
  }
  return out;
}

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int kShades = 64;  // colormap steps of the landscape shading

struct Point {
  double x, y;
};
using Polyline = std::vector<Point>;

struct Box {  // in pixels, y grows downwards
  double left, top, right, bottom;
};

// ----- text -----------------------------------------------------------------------------------

// A pixel coordinate with at most two decimals: "12.5", "-3", "0".
std::string num(double v) {
  std::array<char, 48> buf{};
  std::snprintf(buf.data(), buf.size(), "%.2f", v);
  std::string s(buf.data());
  while (s.back() == '0') s.pop_back();
  if (s.back() == '.') s.pop_back();
  return s == "-0" ? "0" : s;
}

// Approximate width of `text` at font-size 12, counting UTF-8 code points.
double text_width(std::string_view text) {
  const auto points = std::count_if(text.begin(), text.end(), [](char c) {
    return (static_cast<unsigned char>(c) & 0xC0) != 0x80;
  });
  return 7.0 * static_cast<double>(points);
}

std::string text(double x, double y, std::string_view content, std::string_view attributes = "") {
  std::string out = "<text x=\"" + num(x) + "\" y=\"" + num(y) + "\"";
  if (!attributes.empty()) out += " " + std::string(attributes);
  return out + ">" + xml_escape(content) + "</text>\n";
}

std::uint64_t fnv1a(std::string_view s) {
  std::uint64_t h = 14695981039346656037ULL;
  for (const unsigned char c : s) h = (h ^ c) * 1099511628211ULL;
  return h;
}

// ----- colours --------------------------------------------------------------------------------

constexpr std::array<const char*, 10> kPalette = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728",
                                                  "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
                                                  "#bcbd22", "#17becf"};

std::string series_color(const std::string& color, std::size_t index) {
  return color.empty() ? kPalette[index % kPalette.size()] : color;
}

// Viridis, interpolated between nine samples; t in [0, 1].
std::string viridis(double t) {
  static constexpr std::array<std::array<double, 3>, 9> kStops{{{68, 1, 84},
                                                                {71, 45, 123},
                                                                {59, 82, 139},
                                                                {44, 114, 142},
                                                                {33, 145, 140},
                                                                {40, 174, 128},
                                                                {94, 201, 98},
                                                                {173, 220, 48},
                                                                {253, 231, 37}}};
  const double s = std::clamp(t, 0.0, 1.0) * 8.0;
  const auto k = std::min<std::size_t>(7, static_cast<std::size_t>(s));
  const double f = s - static_cast<double>(k);
  std::array<int, 3> rgb{};
  for (std::size_t c = 0; c < 3; ++c) {
    rgb[c] = static_cast<int>(std::lround(kStops[k][c] * (1 - f) + kStops[k + 1][c] * f));
  }
  std::array<char, 8> buf{};
  std::snprintf(buf.data(), buf.size(), "#%02x%02x%02x", rgb[0], rgb[1], rgb[2]);
  return buf.data();
}

// ----- axes -----------------------------------------------------------------------------------

// Maps data to pixels; lo and hi are in log10 units on a log axis. Values that cannot be
// drawn (non-finite, ≤ 0 on a log axis) map to a non-finite pixel.
struct Scale {
  double lo, hi;
  bool log;
  double p0, p1;  // pixels of lo and hi
  double operator()(double v) const {
    const double t = log ? std::log10(v) : v;
    return p0 + (t - lo) / (hi - lo) * (p1 - p0);
  }
};

struct Tick {
  double value;
  std::string label;  // empty for a minor tick
};

struct Axis {
  Scale scale;
  std::vector<Tick> ticks;
};

bool usable(double v, bool log) { return std::isfinite(v) && (!log || v > 0); }

// 1, 2 or 5 times a power of ten, at least `raw`.
double nice_step(double raw) {
  const double decade = std::pow(10.0, std::floor(std::log10(raw)));
  const double f = raw / decade;
  return (f <= 1 ? 1 : f <= 2 ? 2 : f <= 5 ? 5 : 10) * decade;
}

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
  return buf.data();
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

std::string decade_label(int k) {
  if (k >= 0 && k <= 3) return "1" + std::string(static_cast<std::size_t>(k), '0');
  if (k == -1) return "0.1";
  if (k == -2) return "0.01";
  return "1e" + std::to_string(k);
}

// Decades lo..hi: about eight labelled, the others as minor ticks, and 2..9 × 10^k between
// them when the axis spans at most six decades.
std::vector<Tick> log_ticks(int lo, int hi) {
  std::vector<Tick> ticks;
  const int every = std::max(1, (hi - lo + 7) / 8);
  for (int k = lo; k <= hi; ++k) {
    const double decade = std::pow(10.0, k);
    ticks.push_back({decade, k % every == 0 ? decade_label(k) : ""});
    for (int m = 2; m <= 9 && k < hi && hi - lo <= 6; ++m) ticks.push_back({m * decade, ""});
  }
  return ticks;
}

// An axis covering [lo, hi] (the range of the data, found = false when there is none),
// widened to whole decades (log) or to multiples of a nice step (linear).
Axis data_axis(double lo, double hi, bool found, bool log, double p0, double p1) {
  if (log) {
    int a = found ? static_cast<int>(std::floor(std::log10(lo))) : 0;
    int b = found ? static_cast<int>(std::ceil(std::log10(hi))) : 1;
    if (a == b) {
      --a;
      ++b;
    }
    return {{static_cast<double>(a), static_cast<double>(b), true, p0, p1}, log_ticks(a, b)};
  }
  if (!found) {
    lo = 0;
    hi = 1;
  } else if (lo == hi) {
    const double pad = lo == 0 ? 1 : 0.1 * std::abs(lo);
    lo -= pad;
    hi += pad;
  }
  const double step = nice_step((hi - lo) / 5);
  lo = std::floor(lo / step) * step;
  hi = std::ceil(hi / step) * step;
  return {{lo, hi, false, p0, p1}, linear_ticks(lo, hi, step)};
}

// An axis spanning exactly [lo, hi].
Axis fixed_axis(double lo, double hi, double p0, double p1) {
  return {{lo, hi, false, p0, p1}, linear_ticks(lo, hi, nice_step((hi - lo) / 5))};
}

Box plot_box(int width, int height, bool title) {
  return {72.0, title ? 36.0 : 16.0, width - 16.0, height - 52.0};
}

Box grow(const Box& b, double dx, double dy) {
  return {b.left - dx, b.top - dy, b.right + dx, b.bottom + dy};
}

// The box enlarged by its own size on every side: geometry is cut to it so that coordinates
// stay moderate; the clip path then trims to the box.
Box bounds_of(const Box& b) { return grow(b, b.right - b.left, b.bottom - b.top); }

bool inside(const Point& p, const Box& b) {
  return p.x >= b.left && p.x <= b.right && p.y >= b.top && p.y <= b.bottom;
}

std::string grid_lines(const Box& b, const Axis& ax, const Axis& ay) {
  std::string d;
  for (const Tick& t : ax.ticks) {
    const double x = ax.scale(t.value);
    if (!t.label.empty() && x > b.left + 0.5 && x < b.right - 0.5) {
      d += "M" + num(x) + " " + num(b.top) + "V" + num(b.bottom);
    }
  }
  for (const Tick& t : ay.ticks) {
    const double y = ay.scale(t.value);
    if (!t.label.empty() && y > b.top + 0.5 && y < b.bottom - 0.5) {
      d += "M" + num(b.left) + " " + num(y) + "H" + num(b.right);
    }
  }
  return d.empty() ? "" : "<path d=\"" + d + "\" stroke=\"#e3e3e3\" fill=\"none\"/>\n";
}

// Frame, tick marks (outside the box), tick labels, title and axis labels.
std::string axes(int width, int height, const Box& b, const Axis& ax, const Axis& ay,
                 const std::string& title, const std::string& x_label, const std::string& y_label) {
  std::string out = "<rect x=\"" + num(b.left) + "\" y=\"" + num(b.top) + "\" width=\"" +
                    num(b.right - b.left) + "\" height=\"" + num(b.bottom - b.top) +
                    "\" fill=\"none\" stroke=\"#333\"/>\n";
  std::string marks, labels;
  for (const Tick& t : ax.ticks) {
    const double x = ax.scale(t.value);
    if (x < b.left - 0.5 || x > b.right + 0.5) continue;
    marks += "M" + num(x) + " " + num(b.bottom) + "v" + (t.label.empty() ? "3" : "5");
    if (!t.label.empty()) labels += text(x, b.bottom + 18, t.label, "text-anchor=\"middle\"");
  }
  for (const Tick& t : ay.ticks) {
    const double y = ay.scale(t.value);
    if (y < b.top - 0.5 || y > b.bottom + 0.5) continue;
    marks += "M" + num(b.left) + " " + num(y) + "h" + (t.label.empty() ? "-3" : "-5");
    if (!t.label.empty()) labels += text(b.left - 8, y + 4, t.label, "text-anchor=\"end\"");
  }
  out += "<path d=\"" + marks + "\" stroke=\"#333\" fill=\"none\"/>\n";
  out += "<g fill=\"#333\">\n" + labels + "</g>\n";
  const double cx = (b.left + b.right) / 2, cy = (b.top + b.bottom) / 2;
  if (!title.empty()) {
    out += text(width / 2.0, 22, title,
                "text-anchor=\"middle\" font-size=\"14\" font-weight=\"bold\"");
  }
  if (!x_label.empty()) out += text(cx, height - 14.0, x_label, "text-anchor=\"middle\"");
  if (!y_label.empty()) {
    out += "<text transform=\"translate(18 " + num(cy) + ") rotate(-90)\" text-anchor=\"middle\">" +
           xml_escape(y_label) + "</text>\n";
  }
  return out;
}

struct LegendEntry {
  std::string label, color;  // color already XML-escaped
  bool dashed, dot;
};

// A box in the top right corner of the plot, one row per entry with a label.
std::string legend(const Box& b, const std::vector<LegendEntry>& entries) {
  std::vector<const LegendEntry*> shown;
  double label_width = 0;
  for (const LegendEntry& e : entries) {
    if (e.label.empty()) continue;
    shown.push_back(&e);
    label_width = std::max(label_width, text_width(e.label));
  }
  if (shown.empty()) return "";
  const double row = 17, w = 44 + label_width, h = 8 + row * static_cast<double>(shown.size());
  const double x0 = b.right - w - 8, y0 = b.top + 8;
  std::string out = "<g>\n<rect x=\"" + num(x0) + "\" y=\"" + num(y0) + "\" width=\"" + num(w) +
                    "\" height=\"" + num(h) +
                    "\" fill=\"white\" fill-opacity=\"0.85\" stroke=\"#999\" rx=\"3\"/>\n";
  for (std::size_t k = 0; k < shown.size(); ++k) {
    const LegendEntry& e = *shown[k];
    const double y = y0 + 4 + row * (static_cast<double>(k) + 0.5);
    out += "<path d=\"M" + num(x0 + 8) + " " + num(y) + "h24\" stroke=\"" + e.color +
           "\" stroke-width=\"2\"" + (e.dashed ? " stroke-dasharray=\"6 4\"" : "") + "/>\n";
    if (e.dot) {
      out += "<circle cx=\"" + num(x0 + 20) + "\" cy=\"" + num(y) + "\" r=\"2.5\" fill=\"" +
             e.color + "\"/>\n";
    }
    out += text(x0 + 38, y + 4, e.label, "fill=\"#222\"");
  }
  return out + "</g>\n";
}

// ----- geometry -------------------------------------------------------------------------------

// Cuts the segment a–b to the box (Liang–Barsky); false when nothing of it is inside.
bool clip_segment(Point& a, Point& b, const Box& box) {
  const double dx = b.x - a.x, dy = b.y - a.y;
  if (!std::isfinite(dx) || !std::isfinite(dy)) return false;
  double t0 = 0, t1 = 1;
  const std::array<std::array<double, 2>, 4> pq{
      {{-dx, a.x - box.left}, {dx, box.right - a.x}, {-dy, a.y - box.top}, {dy, box.bottom - a.y}}};
  for (const auto& [p, q] : pq) {
    if (p == 0) {
      if (q < 0) return false;
      continue;
    }
    const double r = q / p;
    if (p < 0)
      t0 = std::max(t0, r);
    else
      t1 = std::min(t1, r);
    if (t0 > t1) return false;
  }
  const Point start = a;
  if (t0 > 0) a = {start.x + t0 * dx, start.y + t0 * dy};
  if (t1 < 1) b = {start.x + t1 * dx, start.y + t1 * dy};
  return true;
}

// The parts of a polyline inside the box.
std::vector<Polyline> clip(const Polyline& line, const Box& box) {
  std::vector<Polyline> pieces;
  if (line.size() == 1 && inside(line[0], box)) pieces.push_back(line);
  bool continues = false;  // the last piece ends at an uncut vertex
  for (std::size_t k = 1; k < line.size(); ++k) {
    Point a = line[k - 1], b = line[k];
    if (!clip_segment(a, b, box)) {
      continues = false;
      continue;
    }
    if (!continues) pieces.push_back({a});
    pieces.back().push_back(b);
    continues = b.x == line[k].x && b.y == line[k].y;
  }
  return pieces;
}

// The points of (x, y) that can be drawn, in pixels. With `split`, a point that cannot be drawn
// ends the current piece; otherwise it is just left out.
std::vector<Polyline> to_pixels(const std::vector<double>& x, const std::vector<double>& y,
                                const Scale& sx, const Scale& sy, bool split) {
  std::vector<Polyline> pieces(1);
  for (std::size_t k = 0; k < x.size(); ++k) {
    const Point p{sx(x[k]), sy(y[k])};
    if (std::isfinite(p.x) && std::isfinite(p.y)) {
      pieces.back().push_back(p);
    } else if (split && !pieces.back().empty()) {
      pieces.emplace_back();
    }
  }
  if (pieces.back().empty()) pieces.pop_back();
  return pieces;
}

void append_point(std::string& d, const Point& p) { d += num(p.x) + " " + num(p.y); }

// Closed path data of the band between `low` and `high` over x, each point clamped to `bounds`.
std::string band_path(const std::vector<double>& x, const std::vector<double>& low,
                      const std::vector<double>& high, const Scale& sx, const Scale& sy,
                      const Box& bounds) {
  std::vector<Point> upper, lower;
  for (std::size_t k = 0; k < x.size(); ++k) {
    const Point a{sx(x[k]), sy(high[k])}, b{sx(x[k]), sy(low[k])};
    if (!(std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(b.y))) continue;
    upper.push_back(a);
    lower.push_back(b);
  }
  if (upper.size() < 2) return {};
  std::string d = "M";
  const auto add = [&](Point p) {
    p.x = std::clamp(p.x, bounds.left, bounds.right);
    p.y = std::clamp(p.y, bounds.top, bounds.bottom);
    if (d.size() > 1) d += " ";
    append_point(d, p);
  };
  for (const Point& p : upper) add(p);
  for (auto it = lower.rbegin(); it != lower.rend(); ++it) add(*it);
  return d + "Z";
}

// Path data for the pieces cut to `bounds`; a lone point becomes a dot (with round caps).
std::string line_path(const std::vector<Polyline>& pieces, const Box& bounds) {
  std::string d;
  for (const Polyline& piece : pieces) {
    for (const Polyline& part : clip(piece, bounds)) {
      d += "M";
      for (std::size_t k = 0; k < part.size(); ++k) {
        if (k > 0) d += " ";
        append_point(d, part[k]);
      }
      if (part.size() == 1) d += "h0";
    }
  }
  return d;
}

// Path data with a zero-length subpath per point in `bounds`: dots when stroked with round caps.
std::string dot_path(const std::vector<Polyline>& pieces, const Box& bounds) {
  std::string d;
  for (const Polyline& piece : pieces) {
    for (const Point& p : piece) {
      if (!inside(p, bounds)) continue;
      d += "M";
      append_point(d, p);
      d += "h0";
    }
  }
  return d;
}

std::string path(const std::string& d, const std::string& attributes) {
  return d.empty() ? "" : "<path d=\"" + d + "\" " + attributes + "/>\n";
}

// `content` clipped to the box. The clip path's id derives from what it clips, so figures
// embedded side by side in one HTML page do not pick up each other's clip paths.
std::string clipped(const Box& b, const std::string& content) {
  const std::string rect = "x=\"" + num(b.left) + "\" y=\"" + num(b.top) + "\" width=\"" +
                           num(b.right - b.left) + "\" height=\"" + num(b.bottom - b.top) + "\"";
  std::array<char, 24> id{};
  std::snprintf(id.data(), id.size(), "clip%016llx",
                static_cast<unsigned long long>(fnv1a(rect + content)));
  return "<defs><clipPath id=\"" + std::string(id.data()) + "\"><rect " + rect +
         "/></clipPath></defs>\n<g clip-path=\"url(#" + id.data() + ")\">\n" + content + "</g>\n";
}

std::string svg_open(int width, int height) {
  const std::string w = std::to_string(width), h = std::to_string(height);
  return "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + w + "\" height=\"" + h +
         "\" viewBox=\"0 0 " + w + " " + h +
         "\" font-family=\"Helvetica, Arial, sans-serif\" font-size=\"12\">\n"
         "<rect width=\"" +
         w + "\" height=\"" + h + "\" fill=\"white\"/>\n";
}

// ----- validation -----------------------------------------------------------------------------

void check_size(const char* where, int width, int height) {
  if (width < 200 || height < 150) {
    throw Error(std::string(where) + ": a figure of " + std::to_string(width) + "x" +
                std::to_string(height) + " pixels is too small (at least 200x150)");
  }
}

void check_lengths(const char* where, const std::string& label, const std::vector<double>& x,
                   const std::vector<double>& y) {
  if (x.size() != y.size()) {
    throw Error(std::string(where) + ": '" + label + "' has " + std::to_string(x.size()) +
                " x values but " + std::to_string(y.size()) + " y values");
  }
}

void check_grid(const Grid2D& g) {
  if (g.nx < 2 || g.ny < 2) {
    throw Error("grid: nx = " + std::to_string(g.nx) + " and ny = " + std::to_string(g.ny) +
                " must both be at least 2");
  }
  const std::size_t n = static_cast<std::size_t>(g.nx) * static_cast<std::size_t>(g.ny);
  if (g.values.size() != n) {
    throw Error("grid: values has " + std::to_string(g.values.size()) +
                " entries but nx*ny = " + std::to_string(n));
  }
  if (!(g.x_min < g.x_max) || !(g.y_min < g.y_max) || !std::isfinite(g.x_max - g.x_min) ||
      !std::isfinite(g.y_max - g.y_min)) {
    throw Error("grid: the box [" + std::to_string(g.x_min) + ", " + std::to_string(g.x_max) +
                "] x [" + std::to_string(g.y_min) + ", " + std::to_string(g.y_max) +
                "] must be finite and non-empty");
  }
}

// ----- landscape ------------------------------------------------------------------------------

// Maps field values to [0, 1] for the colormap, in log10 when requested and possible.
struct FieldScale {
  bool log;
  double smallest;  // smallest positive value; values below count as this on a log scale
  double lo, hi;    // transformed minimum and maximum

  explicit FieldScale(const std::vector<double>& values, bool log_levels) {
    double min = kInf, max = -kInf, min_positive = kInf;
    for (const double v : values) {
      if (!std::isfinite(v)) continue;
      min = std::min(min, v);
      max = std::max(max, v);
      if (v > 0) min_positive = std::min(min_positive, v);
    }
    log = log_levels && min_positive < kInf;
    smallest = min_positive;
    lo = min < kInf ? transform(min) : 0;
    hi = max > -kInf ? transform(max) : 0;
  }
  double transform(double v) const { return log ? std::log10(std::max(v, smallest)) : v; }
  double unit(double v) const { return hi > lo ? (transform(v) - lo) / (hi - lo) : 0.5; }
  // The k-th of n levels, evenly spaced (in the transformed space) strictly inside (lo, hi).
  double level(int k, int n) const {
    const double t = lo + (hi - lo) * k / (n + 1);
    return log ? std::pow(10.0, t) : t;
  }
};

// One rectangle per grid node reaching halfway to its neighbours, coloured by the field. The
// colormap is quantized, so that cells of a colour share one path and row runs merge.
std::string shading(const Grid2D& g, const Scale& sx, const Scale& sy, const FieldScale& field) {
  const auto edges = [](int n, double lo, double hi, const Scale& s) {
    std::vector<double> e(static_cast<std::size_t>(n) + 1);
    const double step = (hi - lo) / (n - 1);
    for (int k = 0; k <= n; ++k)
      e[static_cast<std::size_t>(k)] = s(std::clamp(lo + (k - 0.5) * step, lo, hi));
    return e;
  };
  const std::vector<double> ex = edges(g.nx, g.x_min, g.x_max, sx);
  const std::vector<double> ey = edges(g.ny, g.y_min, g.y_max, sy);
  const auto shade = [&](int i, int j) {
    const double v = g.values[static_cast<std::size_t>(j) * g.nx + i];
    return std::isfinite(v) ? std::min(kShades - 1, static_cast<int>(field.unit(v) * kShades)) : -1;
  };
  std::array<std::string, kShades> paths;
  for (int j = 0; j < g.ny; ++j) {
    for (int i = 0; i < g.nx;) {
      const int q = shade(i, j);
      int end = i + 1;
      while (end < g.nx && shade(end, j) == q) ++end;
      if (q >= 0) {
        const std::size_t ju = static_cast<std::size_t>(j);
        std::string& d = paths[static_cast<std::size_t>(q)];
        d += 'M';
        d += num(ex[static_cast<std::size_t>(i)]) + " " + num(ey[ju + 1]) + "H" +
             num(ex[static_cast<std::size_t>(end)]) + "V" + num(ey[ju]) + "H" +
             num(ex[static_cast<std::size_t>(i)]) + "Z";
      }
      i = end;
    }
  }
  std::string out = "<g shape-rendering=\"crispEdges\">\n";
  for (int q = 0; q < kShades; ++q) {
    out +=
        path(paths[static_cast<std::size_t>(q)], "fill=\"" + viridis((q + 0.5) / kShades) + "\"");
  }
  return out + "</g>\n";
}

std::string star(const Point& c, double r) {
  std::string points;
  for (int k = 0; k < 10; ++k) {
    const double angle = k * std::acos(-1.0) / 5, radius = k % 2 == 0 ? r : 0.45 * r;
    if (k > 0) points += " ";
    points += num(c.x + radius * std::sin(angle)) + "," + num(c.y - radius * std::cos(angle));
  }
  return "<polygon points=\"" + points + "\" fill=\"white\" stroke=\"black\"/>\n";
}

}  // namespace

// ----- public ---------------------------------------------------------------------------------

std::string color_for(std::string_view key) {
  static constexpr std::array<std::pair<std::string_view, const char*>, 13> kFixed{{
      {"gd", "#1f77b4"},
      {"sgd", "#6baed6"},
      {"momentum", "#17becf"},
      {"adam", "#ff7f0e"},
      {"newton", "#d62728"},
      {"bfgs", "#9467bd"},
      {"lbfgs", "#c5a3e0"},
      {"gn", "#8c564b"},
      {"lm", "#e377c2"},
      {"ig", "#2ca02c"},
      {"pg", "#bcbd22"},
      {"hig", "#00633a"},
      {"sip", "#000000"},
  }};
  for (const auto& [id, color] : kFixed) {
    if (id == key) return color;
  }
  return kPalette[fnv1a(key) % kPalette.size()];
}

std::string line_plot_svg(const std::vector<Series>& series, const LinePlotOptions& options) {
  check_size("line_plot_svg", options.width, options.height);
  double x_lo = kInf, x_hi = -kInf, y_lo = kInf, y_hi = -kInf;
  for (const Series& s : series) {
    check_lengths("line_plot_svg: series", s.label, s.x, s.y);
    const bool band = !s.band_low.empty() || !s.band_high.empty();
    if (band) {
      check_lengths("line_plot_svg: band low of", s.label, s.x, s.band_low);
      check_lengths("line_plot_svg: band high of", s.label, s.x, s.band_high);
    }
    for (std::size_t k = 0; k < s.x.size(); ++k) {
      if (!usable(s.x[k], options.log_x)) continue;
      for (const double v : {s.y[k], band ? s.band_low[k] : s.y[k], band ? s.band_high[k] : s.y[k]}) {
        if (!usable(v, options.log_y)) continue;
        x_lo = std::min(x_lo, s.x[k]);
        x_hi = std::max(x_hi, s.x[k]);
        y_lo = std::min(y_lo, v);
        y_hi = std::max(y_hi, v);
      }
    }
  }
  const Box box = plot_box(options.width, options.height, !options.title.empty());
  const Box bounds = bounds_of(box);
  const bool found = x_lo <= x_hi;
  const Axis ax = data_axis(x_lo, x_hi, found, options.log_x, box.left, box.right);
  const Axis ay = data_axis(y_lo, y_hi, found, options.log_y, box.bottom, box.top);

  std::string content;
  std::vector<LegendEntry> entries;
  for (std::size_t n = 0; n < series.size(); ++n) {
    const Series& s = series[n];
    const std::string color = xml_escape(series_color(s.color, n));
    const std::vector<Polyline> pieces = to_pixels(s.x, s.y, ax.scale, ay.scale, true);
    if (!s.band_low.empty()) {
      const std::string band = band_path(s.x, s.band_low, s.band_high, ax.scale, ay.scale, bounds);
      if (!band.empty()) content += path(band, "fill=\"" + color + "\" fill-opacity=\"0.18\"");
    }
    content +=
        path(line_path(pieces, bounds),
             "fill=\"none\" stroke=\"" + color +
                 "\" stroke-width=\"1.8\" stroke-linejoin=\"round\" stroke-linecap=\"round\"" +
                 (s.dashed ? " stroke-dasharray=\"6 4\"" : ""));
    if (s.markers) {
      content += path(dot_path(pieces, bounds),
                      "stroke=\"" + color + "\" stroke-width=\"5\" stroke-linecap=\"round\"");
    }
    entries.push_back({s.label, color, s.dashed, s.markers});
  }
  // The clip reaches a little past the frame, so that lines along the data range's ends
  // (which the axes end at) show in full.
  return svg_open(options.width, options.height) + grid_lines(box, ax, ay) +
         clipped(grow(box, 3, 3), content) +
         axes(options.width, options.height, box, ax, ay, options.title, options.x_label,
              options.y_label) +
         legend(box, entries) + "</svg>\n";
}

std::string landscape_svg(const Grid2D& grid, const std::vector<Trajectory>& trajectories,
                          const LandscapeOptions& options) {
  check_grid(grid);
  check_size("landscape_svg", options.width, options.height);
  if (options.levels < 0) {
    throw Error("landscape_svg: levels = " + std::to_string(options.levels) + " is negative");
  }
  for (const Trajectory& t : trajectories) {
    check_lengths("landscape_svg: trajectory", t.label, t.x, t.y);
  }
  const Box box = plot_box(options.width, options.height, !options.title.empty());
  const Box bounds = bounds_of(box);
  const Axis ax = fixed_axis(grid.x_min, grid.x_max, box.left, box.right);
  const Axis ay = fixed_axis(grid.y_min, grid.y_max, box.bottom, box.top);
  const FieldScale field(grid.values, options.log_levels);

  std::string content = shading(grid, ax.scale, ay.scale, field);
  for (int k = 1; k <= options.levels && field.hi > field.lo; ++k) {
    std::vector<Polyline> lines;
    for (const auto& line : isolines(grid, field.level(k, options.levels))) {
      Polyline& pixels = lines.emplace_back();
      for (const auto& [x, y] : line) pixels.push_back({ax.scale(x), ay.scale(y)});
    }
    content += path(line_path(lines, bounds),
                    "class=\"isoline\" fill=\"none\" stroke=\"white\" stroke-opacity=\"0.55\" "
                    "stroke-width=\"0.8\"");
  }

  std::vector<LegendEntry> entries;
  for (std::size_t n = 0; n < trajectories.size(); ++n) {
    const Trajectory& t = trajectories[n];
    const std::string color = xml_escape(series_color(t.color, n));
    const std::vector<Polyline> pieces = to_pixels(t.x, t.y, ax.scale, ay.scale, false);
    const std::string d = line_path(pieces, bounds);
    content += path(d,
                    "fill=\"none\" stroke=\"white\" stroke-opacity=\"0.7\" stroke-width=\"3.6\" "
                    "stroke-linejoin=\"round\" stroke-linecap=\"round\"");
    content +=
        path(d, "fill=\"none\" stroke=\"" + color +
                    "\" stroke-width=\"1.6\" stroke-linejoin=\"round\" stroke-linecap=\"round\"");
    content += path(dot_path(pieces, bounds),
                    "stroke=\"" + color + "\" stroke-width=\"3.6\" stroke-linecap=\"round\"");
    if (!pieces.empty() && inside(pieces[0].front(), bounds)) {
      const Point& p = pieces[0].front();
      content += "<circle cx=\"" + num(p.x) + "\" cy=\"" + num(p.y) +
                 "\" r=\"4.5\" fill=\"white\" stroke=\"" + color + "\" stroke-width=\"1.8\"/>\n";
    }
    if (!pieces.empty() && inside(pieces[0].back(), bounds)) {
      const Point& p = pieces[0].back();
      content += "<rect x=\"" + num(p.x - 4) + "\" y=\"" + num(p.y - 4) +
                 "\" width=\"8\" height=\"8\" fill=\"" + color + "\" stroke=\"white\"/>\n";
    }
    entries.push_back({t.label, color, false, true});
  }
  for (const Marker& m : options.markers) {
    const Point p{ax.scale(m.x), ay.scale(m.y)};
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !inside(p, bounds)) continue;
    content += star(p, 8);
    if (!m.label.empty()) {
      content += text(p.x + 9, p.y - 8, m.label,
                      "fill=\"black\" stroke=\"white\" stroke-width=\"3\" paint-order=\"stroke\"");
    }
  }
  return svg_open(options.width, options.height) + clipped(box, content) +
         axes(options.width, options.height, box, ax, ay, options.title, options.x_label,
              options.y_label) +
         legend(box, entries) + "</svg>\n";
}

std::vector<std::vector<std::pair<double, double>>> isolines(const Grid2D& grid, double level) {
  check_grid(grid);
  if (!std::isfinite(level)) {
    throw Error("isolines: level " + std::to_string(level) + " is not finite");
  }
  const long long nx = grid.nx, ny = grid.ny;
  const auto value = [&](long long node) { return grid.values[static_cast<std::size_t>(node)]; };

  // Edge 2n joins node n = j*nx + i to its right neighbour, edge 2n+1 to the one above. The
  // crossing on an edge depends only on the edge, so both cells sharing it agree exactly.
  const auto crossing = [&](long long edge) -> std::pair<double, double> {
    const long long a = edge / 2, b = edge % 2 == 0 ? a + 1 : a + nx;
    const double t = (level - value(a)) / (value(b) - value(a));
    const double i = static_cast<double>(a % nx) + (edge % 2 == 0 ? t : 0);
    const double j = static_cast<double>(a / nx) + (edge % 2 == 0 ? 0 : t);
    return {grid.x_min + i * (grid.x_max - grid.x_min) / static_cast<double>(nx - 1),
            grid.y_min + j * (grid.y_max - grid.y_min) / static_cast<double>(ny - 1)};
  };

  std::vector<std::array<long long, 2>> segments;
  for (long long j = 0; j + 1 < ny; ++j) {
    for (long long i = 0; i + 1 < nx; ++i) {
      const long long n = j * nx + i;
      // Corners counter-clockwise from the bottom left; edges bottom, right, top, left.
      const std::array<double, 4> v{value(n), value(n + 1), value(n + nx + 1), value(n + nx)};
      if (!std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); })) continue;
      const std::array<long long, 4> edges{2 * n, 2 * (n + 1) + 1, 2 * (n + nx), 2 * n + 1};
      std::vector<long long> crossed;
      int above = 0;
      for (std::size_t c = 0; c < 4; ++c) {
        if ((v[c] > level) != (v[(c + 1) % 4] > level)) crossed.push_back(edges[c]);
        above |= (v[c] > level ? 1 : 0) << c;
      }
      if (crossed.size() == 2) {
        segments.push_back({crossed[0], crossed[1]});
      } else if (crossed.size() == 4) {
        // Saddle: the mean decides which pair of opposite corners is connected.
        const bool centre_above = (v[0] + v[1] + v[2] + v[3]) / 4 > level;
        if ((above == 5) == centre_above) {  // cut off the bottom-right and top-left corners
          segments.push_back({crossed[0], crossed[1]});
          segments.push_back({crossed[2], crossed[3]});
        } else {  // cut off the bottom-left and top-right corners
          segments.push_back({crossed[3], crossed[0]});
          segments.push_back({crossed[1], crossed[2]});
        }
      }
    }
  }

  // Each edge touches at most two segments: chain them, open chains from their ends first.
  std::unordered_map<long long, std::array<int, 2>> touching;
  for (int s = 0; s < static_cast<int>(segments.size()); ++s) {
    for (const long long e : segments[static_cast<std::size_t>(s)]) {
      auto [it, added] = touching.try_emplace(e, std::array<int, 2>{s, -1});
      if (!added) it->second[1] = s;
    }
  }
  std::vector<bool> used(segments.size(), false);
  std::vector<std::vector<std::pair<double, double>>> lines;
  const auto chain = [&](int s, long long from) {
    auto& line = lines.emplace_back(1, crossing(from));
    while (s >= 0 && !used[static_cast<std::size_t>(s)]) {
      used[static_cast<std::size_t>(s)] = true;
      const auto& seg = segments[static_cast<std::size_t>(s)];
      from = seg[0] == from ? seg[1] : seg[0];
      line.push_back(crossing(from));
      const auto& next = touching[from];
      s = next[0] == s ? next[1] : next[0];
    }
  };
  for (int s = 0; s < static_cast<int>(segments.size()); ++s) {
    for (const long long e : segments[static_cast<std::size_t>(s)]) {
      if (!used[static_cast<std::size_t>(s)] && touching[e][1] < 0) chain(s, e);
    }
  }
  for (int s = 0; s < static_cast<int>(segments.size()); ++s) {
    if (!used[static_cast<std::size_t>(s)]) chain(s, segments[static_cast<std::size_t>(s)][0]);
  }
  return lines;
}

}  // namespace physgrad
