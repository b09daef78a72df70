#include "physgrad/report/line_plot.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>

#include "physgrad/error.hpp"
#include "physgrad/report/colors.hpp"
#include "physgrad/report/plot_axes.hpp"
#include "physgrad/report/plot_geometry.hpp"
#include "physgrad/report/plot_legend.hpp"
#include "physgrad/types.hpp"

namespace physgrad {

namespace {

using plot::Axis;
using plot::Box;
using plot::Point;
using plot::Polyline;
using plot::Scale;
using svg::num;


void check_lengths(const std::string& what, const Series& s, const std::vector<double>& values) {
  if (values.size() != s.x.size()) {
    throw Error("line_plot_svg: " + what + " of '" + s.label + "' has " +
                std::to_string(values.size()) + " values but x has " + std::to_string(s.x.size()));
  }
}

bool has_band(const Series& s) { return !s.band_low.empty() || !s.band_high.empty(); }

// The data range of the series that set it (all of them when none does).
struct Range {
  double x_lo = kInf, x_hi = -kInf, y_lo = kInf, y_hi = -kInf;
  bool found() const { return x_lo <= x_hi && y_lo <= y_hi; }
};

Range data_range(const std::vector<Series>& series, const LinePlotOptions& options) {
  const bool any_sets =
      std::any_of(series.begin(), series.end(), [](const Series& s) { return s.sets_range; });
  Range r;
  for (const Series& s : series) {
    const bool band = has_band(s);
    for (std::size_t k = 0; k < s.x.size(); ++k) {
      if (!plot::usable(s.x[k], options.log_x)) continue;
      for (const double v : {s.y[k], band ? s.band_low[k] : s.y[k], band ? s.band_high[k] : s.y[k]}) {
        if (!std::isfinite(v)) continue;
        r.x_lo = std::min(r.x_lo, s.x[k]);
        r.x_hi = std::max(r.x_hi, s.x[k]);
        if ((s.sets_range || !any_sets) && plot::usable(v, options.log_y)) {
          r.y_lo = std::min(r.y_lo, v);
          r.y_hi = std::max(r.y_hi, v);
        }
      }
    }
  }
  if (r.x_lo <= r.x_hi && !(r.y_lo <= r.y_hi)) {  // only values ≤ 0 on a log axis
    r.y_lo = 0.1;
    r.y_hi = 1;
  }
  return r;
}

// x and one of its value vectors as drawn: a staircase for steps (each value held until the
// next x).
void staircase(const Series& s, const std::vector<double>& values, std::vector<double>& x,
               std::vector<double>& y) {
  x = s.x;
  y = values;
  if (!s.steps || s.x.size() < 2) return;
  x.clear();
  y.clear();
  for (std::size_t k = 0; k + 1 < s.x.size(); ++k) {
    x.insert(x.end(), {s.x[k], s.x[k + 1]});
    y.insert(y.end(), {values[k], values[k]});
  }
  x.push_back(s.x.back());
  y.push_back(values.back());
}

std::string short_number(double v) {
  std::array<char, 32> buf{};
  std::snprintf(buf.data(), buf.size(), "%.4g", v);
  return buf.data();
}

// A × centred at p.
std::string cross(const Point& p, const std::string& color) {
  const std::string d = std::string("M") + num(p.x - 4) + " " + num(p.y - 4) + "l8 8M" + num(p.x - 4) + " " +
                        num(p.y + 4) + "l8 -8";
  return svg::path(d, "stroke=\"" + color + "\" stroke-width=\"2.2\" fill=\"none\"");
}

// An arrow at p pointing up (or down) out of the frame: a value beyond the axis.
std::string edge_arrow(const Point& p, bool up, const std::string& color) {
  const double tip = up ? -5 : 5;
  return svg::path(std::string("M") + num(p.x) + " " + num(p.y - tip) + "V" + num(p.y + tip) +
                       "M" + num(p.x - 4) + " " + num(p.y + tip - (up ? -4 : 4)) + "L" +
                       num(p.x) + " " + num(p.y + tip) + "L" + num(p.x + 4) + " " +
                       num(p.y + tip - (up ? -4 : 4)),
                   "stroke=\"" + color + "\" stroke-width=\"2\" fill=\"none\"");
}

// A ▼ with its tip at p.
std::string down_triangle(const Point& p, const std::string& color) {
  return svg::path(std::string("M") + num(p.x - 4.5) + " " + num(p.y - 8) + "h9L" + num(p.x) + " " + num(p.y) +
                       "Z",
                   "fill=\"" + color + "\" stroke=\"white\" stroke-width=\"0.8\"");
}

}  // namespace

std::string line_plot_svg(const std::vector<Series>& series, const LinePlotOptions& options) {
  if (options.width < 200 || options.height < 150) {
    throw Error("line_plot_svg: a figure of " + std::to_string(options.width) + "x" +
                std::to_string(options.height) + " pixels is too small (at least 200x150)");
  }
  for (const Series& s : series) {
    check_lengths("y", s, s.y);
    if (has_band(s)) {
      check_lengths("band low", s, s.band_low);
      check_lengths("band high", s, s.band_high);
    }
  }
  const Range range = data_range(series, options);
  const auto& fixed = options.x_range;
  const bool fixed_x = fixed && plot::usable(fixed->first, options.log_x) &&
                       plot::usable(fixed->second, options.log_x) && fixed->first < fixed->second;
  Axis ax = fixed_x ? plot::fixed_axis(fixed->first, fixed->second, options.log_x, 0, 1)
                    : plot::data_axis(range.x_lo, range.x_hi, range.found(), options.log_x, 0, 1);
  const auto& shared = options.y_range;
  const bool fixed_y = shared && plot::usable(shared->first, options.log_y) &&
                       plot::usable(shared->second, options.log_y) &&
                       shared->first <= shared->second;
  Axis ay = fixed_y ? plot::data_axis(shared->first, shared->second, true, options.log_y, 1, 0)
                    : plot::data_axis(range.y_lo, range.y_hi, range.found(), options.log_y, 1, 0);
  const Box box{std::max(40.0, plot::left_margin(ay, !options.y_label.empty())),
                plot::top_margin(!options.title.empty()), options.width - 16.0,
                options.height - plot::kBottomMargin};
  ax.scale.p0 = box.left;
  ax.scale.p1 = box.right;
  ay.scale.p0 = box.bottom;
  ay.scale.p1 = box.top;
  const Box bounds = plot::bounds_of(box);
  // On a log y axis, values ≤ 0 sit on the lower edge.
  Scale sy = ay.scale;
  const auto y_pixel = [&](double v) {
    return options.log_y && std::isfinite(v) && v <= 0 ? box.bottom : sy(v);
  };

  std::string content, notes;
  plot::Occupancy occupied(box);
  std::vector<plot::LegendEntry> entries;
  std::vector<Box> note_boxes;
  std::vector<std::vector<Polyline>> drawn;  // the pieces of the series before
  for (std::size_t n = 0; n < series.size(); ++n) {
    const Series& s = series[n];
    const std::string color = xml_escape(s.color.empty() ? palette_color(n) : s.color);
    std::vector<double> x, y;
    staircase(s, s.y, x, y);
    std::vector<Polyline> pieces(1);
    std::string zero_note;
    double last_value = NAN;  // the value of the last point drawn
    for (std::size_t k = 0; k < x.size(); ++k) {
      const Point p{ax.scale(x[k]), y_pixel(y[k])};
      if (std::isfinite(p.x) && std::isfinite(p.y)) {
        pieces.back().push_back(p);
        last_value = y[k];
        if (options.log_y && y[k] <= 0 && zero_note.empty()) {
          zero_note = (y[k] == 0 ? " (0 from " : " (≤ 0 from ") + short_number(x[k]) + " ▼)";
          notes += down_triangle(p, color);
          occupied.mark_box({p.x - 5, p.y - 8, p.x + 5, p.y});
        }
      } else if (!pieces.back().empty()) {
        pieces.emplace_back();
      }
    }
    if (pieces.back().empty()) pieces.pop_back();
    if (has_band(s)) {
      std::vector<double> band_x, low, high;
      staircase(s, s.band_low, band_x, low);
      staircase(s, s.band_high, band_x, high);
      const std::string band = plot::band_path(band_x, low, high, ax.scale, sy, bounds);
      content += svg::path(band, "fill=\"" + color + "\" fill-opacity=\"0.18\"");
      for (std::size_t k = 0; k < band_x.size(); ++k) {
        occupied.mark_segment({ax.scale(band_x[k]), sy(low[k])}, {ax.scale(band_x[k]), sy(high[k])});
      }
    }
    // A series that retraces an earlier one gets its own dashes, so that both stay visible.
    const int retraced = plot::retraces(pieces, drawn);
    drawn.push_back(pieces);
    const std::string dashes =
        retraced > 0 ? plot::dash_pattern(retraced) : s.dashed ? plot::dash_pattern(0) : "";
    content += svg::path(plot::line_path(pieces, bounds),
                         "fill=\"none\" stroke=\"" + color +
                             "\" stroke-width=\"1.8\" stroke-linejoin=\"round\" "
                             "stroke-linecap=\"round\"" +
                             (dashes.empty() ? "" : " stroke-dasharray=\"" + dashes + "\""));
    if (s.markers) {
      const std::vector<Polyline> points = plot::to_pixels(s.x, s.y, ax.scale, sy, false);
      const std::size_t count = points.empty() ? 0 : points.front().size();
      content += svg::path(plot::dot_path(points, bounds),
                           "stroke=\"" + color + "\" stroke-width=\"" +
                               (count <= 40 ? "5" : count <= 120 ? "3" : "2") +
                               "\" stroke-linecap=\"round\"");
    }
    for (const Polyline& piece : pieces) occupied.mark_polyline(piece);

    // The end of a diverged (or otherwise labelled) run: a × and its label inside the frame.
    std::string end = s.end_label;
    if (end.empty() && !s.y.empty() && !std::isfinite(s.y.back()) && !pieces.empty()) {
      std::size_t last = s.y.size();
      while (last > 0 && !std::isfinite(s.y[last - 1])) --last;
      end = last > 0 ? "not finite after x = " + short_number(s.x[last - 1]) : "";
    }
    // A series whose end lies off the scale (above or below the frame) ends in an arrow at
    // the frame's edge with its value, never on the curves inside.
    const bool off_scale =
        !pieces.empty() && (pieces.back().back().y < box.top || pieces.back().back().y > box.bottom);
    if (off_scale) end = (end.empty() ? "" : end + ", ") + "ends off scale at " + short_number(last_value);
    if (!end.empty() && !pieces.empty()) {
      const Point last = pieces.back().back();
      Point at{std::clamp(last.x, box.left + 5, box.right - 5),
               std::clamp(last.y, box.top + 5, box.bottom - 5)};
      notes += off_scale ? edge_arrow(at, last.y < box.top, color) : cross(at, color);
      const double w = svg::text_width(end);
      const bool left_side = at.x > (box.left + box.right) / 2;
      double lx = left_side ? at.x - 8 - w : at.x + 8;
      double ly = at.y + (at.y < box.top + 20 ? 16 : -8);
      for (const Box& other : note_boxes) {
        if (lx < other.right && lx + w > other.left && ly - 11 < other.bottom && ly > other.top) {
          ly = other.bottom + 13;
        }
      }
      lx = std::clamp(lx, box.left + 2, std::max(box.left + 2, box.right - 2 - w));
      note_boxes.push_back({lx, ly - 11, lx + w, ly + 2});
      occupied.mark_box(note_boxes.back());
      occupied.mark(at);
      notes += svg::text(lx, ly, end,
                         "fill=\"" + color +
                             "\" stroke=\"white\" stroke-width=\"3\" paint-order=\"stroke\"");
    }
    entries.push_back({s.label.empty() ? "" : s.label + zero_note, color, true, dashes,
                       s.markers, has_band(s)});
  }
  const plot::LegendLayout legend =
      plot::legend(entries, box, occupied, options.height - 4.0, options.width);
  const int height = options.height + static_cast<int>(std::ceil(legend.height_below));
  // The clip reaches a little past the frame, so that lines along the data range's ends
  // (which the axes end at) show in full.
  return svg::open(options.width, height) + plot::grid_lines(box, ax, ay) +
         svg::clipped(svg::grow(box, 3, 3), content) +
         plot::axes(options.width, box, ax, ay,
                    {options.title, options.x_label, options.y_label}) +
         notes + legend.svg + "</svg>\n";
}

}  // namespace physgrad
