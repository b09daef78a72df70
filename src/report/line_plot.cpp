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
#include "physgrad/report/plot_marks.hpp"
#include "physgrad/types.hpp"

namespace physgrad {

namespace {

// An axis label that says its axis is logarithmic: "loss (log scale)".
std::string log_marked(const std::string& label, bool log) {
  if (!log) return label;
  return label.empty() ? "log scale" : label + " (log scale)";
}

using plot::Axis;
using plot::Box;
using plot::Point;
using plot::Polyline;
using plot::Scale;
using plot::short_number;
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

// The axes and the box of one layout: the x range fixed or from the data, the y range shared or
// from the data; on a log y axis, values ≤ 0 sit on the lower edge.
struct LineFrame {
  Axis ax, ay;
  Box box, bounds;
  bool log_y = false;
  double y_pixel(double v) const {
    return log_y && std::isfinite(v) && v <= 0 ? box.bottom : ay.scale(v);
  }
  Point pixel(double x, double y) const { return {ax.scale(x), y_pixel(y)}; }
};

LineFrame line_frame(const std::vector<Series>& series, const LinePlotOptions& options) {
  const Range range = data_range(series, options);
  const auto& fixed = options.x_range;
  const bool fixed_x = fixed && plot::usable(fixed->first, options.log_x) &&
                       plot::usable(fixed->second, options.log_x) && fixed->first < fixed->second;
  LineFrame f;
  f.ax = fixed_x ? plot::fixed_axis(fixed->first, fixed->second, options.log_x, 0, 1)
                 : plot::data_axis(range.x_lo, range.x_hi, range.found(), options.log_x, 0, 1);
  const auto& shared = options.y_range;
  const bool fixed_y = shared && plot::usable(shared->first, options.log_y) &&
                       plot::usable(shared->second, options.log_y) &&
                       shared->first <= shared->second;
  f.ay = fixed_y ? plot::data_axis(shared->first, shared->second, true, options.log_y, 1, 0)
                 : plot::data_axis(range.y_lo, range.y_hi, range.found(), options.log_y, 1, 0);
  f.box = Box{std::max(40.0, plot::left_margin(f.ay, !options.y_label.empty())),
              plot::top_margin(options.title, options.width), options.width - 16.0,
              options.height - plot::kBottomMargin};
  f.ax.scale.p0 = f.box.left;
  f.ax.scale.p1 = f.box.right;
  f.ay.scale.p0 = f.box.bottom;
  f.ay.scale.p1 = f.box.top;
  f.bounds = plot::bounds_of(f.box);
  f.log_y = options.log_y;
  return f;
}

// What the series drawn so far left: the SVG parts, the occupied cells the legend avoids, the
// legend entries, and each series' pieces, marker shape and dash pattern (-1: solid).
struct LinePlotParts {
  explicit LinePlotParts(const Box& box) : occupied(box) {}
  std::string content, notes, hover;
  plot::Occupancy occupied;
  std::vector<plot::LegendEntry> entries;
  std::vector<Box> note_boxes;
  std::vector<std::vector<Polyline>> drawn;
  std::vector<int> shapes;
  std::vector<int> dashes_of;
};

// One series' line as drawn: its finite pieces, the value of the last point drawn and the note
// for its first value ≤ 0 on a log axis (marked by a ▼ there).
struct LineTrace {
  std::vector<Polyline> pieces;
  double last_value = NAN;
  std::string zero_note;
};

LineTrace trace_line(const Series& s, const LineFrame& f, const std::string& color,
                     LinePlotParts& parts) {
  std::vector<double> x, y;
  staircase(s, s.y, x, y);
  LineTrace t;
  t.pieces.resize(1);
  for (std::size_t k = 0; k < x.size(); ++k) {
    const Point p = f.pixel(x[k], y[k]);
    if (std::isfinite(p.x) && std::isfinite(p.y)) {
      t.pieces.back().push_back(p);
      t.last_value = y[k];
      if (f.log_y && y[k] <= 0 && t.zero_note.empty()) {
        t.zero_note = (y[k] == 0 ? " (0 from " : " (≤ 0 from ") + short_number(x[k]) + " ▼)";
        parts.notes += plot::down_triangle(p, color);
        parts.occupied.mark_box({p.x - 5, p.y - 8, p.x + 5, p.y});
      }
    } else if (!t.pieces.back().empty()) {
      t.pieces.emplace_back();
    }
  }
  if (t.pieces.back().empty()) t.pieces.pop_back();
  return t;
}

// The band (e.g. the seeds' range) behind the line, if the series has one.
std::string draw_series_band(const Series& s, const LineFrame& f, const std::string& color,
                             LinePlotParts& parts) {
  if (!has_band(s)) return "";
  std::vector<double> band_x, low, high;
  staircase(s, s.band_low, band_x, low);
  staircase(s, s.band_high, band_x, high);
  const std::string band = plot::band_path(band_x, low, high, f.ax.scale, f.ay.scale, f.bounds);
  for (std::size_t k = 0; k < band_x.size(); ++k) {
    parts.occupied.mark_segment({f.ax.scale(band_x[k]), f.ay.scale(low[k])},
                                {f.ax.scale(band_x[k]), f.ay.scale(high[k])});
  }
  return svg::path(band, "fill=\"" + color + "\" fill-opacity=\"0.18\"");
}

// The series' dash pattern: its own, or where it retraces the series `under`, one none of them
// has.
int series_dash(const Series& s, const std::vector<std::size_t>& under,
                const LinePlotParts& parts) {
  if (under.empty()) return s.dashed ? s.dash_pattern : -1;
  std::vector<int> taken;
  for (const std::size_t k : under) taken.push_back(parts.dashes_of[k]);
  return plot::free_dash_pattern(taken);
}

// The series' marker shape (-1: none): its own unless one it retraces has it; where it retraces
// others and has none, a shape none of them has.
int series_shape(const Series& s, const std::vector<std::size_t>& under,
                 const LinePlotParts& parts) {
  int shape = s.markers ? s.shape : -1;
  for (const std::size_t k : under) {
    if (shape < 0 || shape == parts.shapes[k]) shape = -1;
  }
  if (under.empty()) return shape;
  for (int candidate = 1; candidate < plot::kShapes + 1 && shape < 0; ++candidate) {
    const bool taken = std::any_of(under.begin(), under.end(),
                                   [&](std::size_t k) { return parts.shapes[k] == candidate; });
    if (!taken) shape = candidate;
  }
  return shape;
}

// The markers: those of series drawn on one another are spread over the points in turns (a
// series of one point keeps it).
std::string draw_series_markers(const Series& s, const LineFrame& f, int shape, int retraced,
                                const std::string& color) {
  if (shape < 0) return "";
  const std::vector<Polyline> points = plot::to_pixels(s.x, s.y, f.ax.scale, f.ay.scale, false);
  const std::size_t count = points.empty() ? 0 : points.front().size();
  std::size_t every = retraced > 0                ? std::max<std::size_t>(2, count / 12)
                      : shape > 0 && count > 24 ? count / 12
                                                : 1;
  every = std::min(every, std::max<std::size_t>(count, 1));
  const double size = shape == 0 ? (count <= 40 ? 5 : count <= 120 ? 3 : 2) : 7;
  const std::size_t offset =
      static_cast<std::size_t>(retraced) * std::max<std::size_t>(1, every / 3);
  return plot::markers_svg(points, f.bounds, shape, size, color, every, offset);
}

// Every point its values on hover, with the band's ends (e.g. the seeds' range) where drawn.
std::string series_hover(const Series& s, const LineFrame& f, const LinePlotOptions& options) {
  std::vector<plot::HoverPoint> targets;
  const bool band = has_band(s);
  for (std::size_t k = 0; k < s.x.size(); ++k) {
    const Point p = f.pixel(s.x[k], s.y[k]);
    if (!(std::isfinite(p.x) && std::isfinite(p.y))) continue;
    targets.push_back({p, s.x[k], s.y[k], band ? s.band_low[k] : NAN, band ? s.band_high[k] : NAN});
  }
  return plot::hover_targets(targets, f.box, s.label,
                             options.x_label.empty() ? "x" : options.x_label,
                             options.y_label.empty() ? "y" : options.y_label, targets.size());
}

// The series' marks: a ◆ with its label on hover.
void draw_series_marks(const Series& s, const LineFrame& f, const std::string& color,
                       LinePlotParts& parts) {
  for (const Series::Mark& mark : s.marks) {
    const Point p = f.pixel(mark.x, mark.y);
    if (!(std::isfinite(p.x) && std::isfinite(p.y) && svg::inside(p, f.box))) continue;
    parts.notes += "<g class=\"mark\"><title>" + xml_escape(s.label + ": " + mark.label) +
                   "</title>\n" + plot::diamond_mark(p, color) + "</g>\n";
    parts.occupied.mark_box({p.x - 6, p.y - 6, p.x + 6, p.y + 6});
  }
}

// The end of a diverged (or otherwise labelled) run: a × and its label inside the frame. A
// series whose end lies off the scale (above or below the frame) ends in an arrow at the frame's
// edge with its value, never on the curves inside.
void draw_series_end(const Series& s, const LineTrace& t, const LineFrame& f,
                     const std::string& color, LinePlotParts& parts) {
  const Box& box = f.box;
  std::string end = s.end_label;
  if (end.empty() && !s.y.empty() && !std::isfinite(s.y.back()) && !t.pieces.empty()) {
    std::size_t last = s.y.size();
    while (last > 0 && !std::isfinite(s.y[last - 1])) --last;
    end = last > 0 ? "not finite after x = " + short_number(s.x[last - 1]) : "";
  }
  const bool off_scale = !t.pieces.empty() && (t.pieces.back().back().y < box.top ||
                                               t.pieces.back().back().y > box.bottom);
  if (off_scale) {
    end = (end.empty() ? "" : end + ", ") + "ends off scale at " + short_number(t.last_value);
  }
  if (end.empty() || t.pieces.empty()) return;
  const Point last = t.pieces.back().back();
  Point at{std::clamp(last.x, box.left + 5, box.right - 5),
           std::clamp(last.y, box.top + 5, box.bottom - 5)};
  parts.notes +=
      off_scale ? plot::edge_arrow(at, last.y < box.top, color) : plot::cross_mark(at, color);
  const double w = svg::text_width(end);
  const bool left_side = at.x > (box.left + box.right) / 2;
  double lx = left_side ? at.x - 8 - w : at.x + 8;
  double ly = at.y + (at.y < box.top + 20 ? 16 : -8);
  for (const Box& other : parts.note_boxes) {
    if (lx < other.right && lx + w > other.left && ly - 11 < other.bottom && ly > other.top) {
      ly = other.bottom + 13;
    }
  }
  lx = std::clamp(lx, box.left + 2, std::max(box.left + 2, box.right - 2 - w));
  parts.note_boxes.push_back({lx, ly - 11, lx + w, ly + 2});
  parts.occupied.mark_box(parts.note_boxes.back());
  parts.occupied.mark(at);
  parts.notes += svg::text(lx, ly, end,
                           "fill=\"" + color +
                               "\" stroke=\"white\" stroke-width=\"3\" paint-order=\"stroke\"");
}

// The series' legend label: what the figure does not show by itself (a value ≤ 0 on a log axis,
// the series it coincides with, its mark, why it is not drawn).
std::string series_legend_label(const Series& s, const std::string& zero_note,
                                const std::string& coincides, const std::string& not_drawn) {
  std::string label = s.label.empty() ? "" : s.label + zero_note;
  if (!label.empty() && !coincides.empty()) label += " (coincides with " + coincides + ")";
  if (!label.empty() && !s.marks.empty()) label += " (◆ " + s.marks.front().label + ")";
  if (!label.empty() && !not_drawn.empty()) label += " (not drawn: " + not_drawn + ")";
  return label;
}

// Series n: its band, line and markers in one group, its hover targets, marks and end label; a
// series that retraces earlier ones gets its own dashes and marker shape, its markers set off
// from theirs, and says so in the legend: both stay visible.
void draw_series(const std::vector<Series>& series, std::size_t n, const LineFrame& f,
                 const LinePlotOptions& options, LinePlotParts& parts) {
  const Series& s = series[n];
  const std::string color = xml_escape(s.color.empty() ? palette_color(n) : s.color);
  const LineTrace t = trace_line(s, f, color, parts);
  std::string group = draw_series_band(s, f, color, parts);
  const std::vector<std::size_t> under = plot::retraced(t.pieces, parts.drawn, f.box);
  parts.drawn.push_back(t.pieces);
  const int retraced = static_cast<int>(under.size());
  const int dash = series_dash(s, under, parts);
  parts.dashes_of.push_back(dash);
  const std::string dashes = dash < 0 ? "" : plot::dash_pattern(dash);
  group += svg::path(plot::line_path(t.pieces, f.bounds),
                     "fill=\"none\" stroke=\"" + color +
                         "\" stroke-width=\"1.8\" stroke-linejoin=\"round\" "
                         "stroke-linecap=\"round\" class=\"line\"" +
                         (dashes.empty() ? "" : " stroke-dasharray=\"" + dashes + "\""));
  std::string coincides;
  for (const std::size_t k : under) coincides += (coincides.empty() ? "" : ", ") + series[k].label;
  const int shape = series_shape(s, under, parts);
  parts.shapes.push_back(shape);
  group += draw_series_markers(s, f, shape, retraced, color);
  parts.hover += series_hover(s, f, options);
  draw_series_marks(s, f, color, parts);
  // A series with no point to draw says why, here and in its legend entry.
  const std::string not_drawn =
      !t.pieces.empty() ? "" : s.end_label.empty() ? "no finite value" : s.end_label;
  parts.content += "<g class=\"series\" data-label=\"" + xml_escape(s.label) + "\"" +
                   (not_drawn.empty() ? "" : " data-empty=\"" + xml_escape(not_drawn) + "\"") +
                   ">\n" + group + "</g>\n";
  for (const Polyline& piece : t.pieces) parts.occupied.mark_polyline(piece);
  draw_series_end(s, t, f, color, parts);
  parts.entries.push_back({series_legend_label(s, t.zero_note, coincides, not_drawn), color, true,
                           dashes, shape == 0, has_band(s), shape});
}

// The figure in one layout; the legend inside the plot where it covers no data when
// `legend_inside`, else below it.
std::string draw_line_plot(const std::vector<Series>& series, const LinePlotOptions& options,
                           bool legend_inside) {
  const LineFrame f = line_frame(series, options);
  LinePlotParts parts(f.box);
  for (std::size_t n = 0; n < series.size(); ++n) draw_series(series, n, f, options, parts);
  const plot::LegendLayout legend = plot::legend(
      parts.entries, f.box, parts.occupied, options.height - 4.0, options.width, legend_inside);
  const int height = options.height + static_cast<int>(std::ceil(legend.height_below));
  // The clip reaches a little past the frame, so that lines along the data range's ends
  // (which the axes end at) show in full.
  return svg::open(options.width, height) + plot::grid_lines(f.box, f.ax, f.ay) +
         svg::clipped(svg::grow(f.box, 3, 3), parts.content) +
         plot::axes(options.width, f.box, f.ax, f.ay,
                    {options.title, log_marked(options.x_label, options.log_x),
                     log_marked(options.y_label, options.log_y)}) +
         parts.notes + parts.hover + legend.svg + "</svg>\n";
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
  const std::string wide = draw_line_plot(series, options, true);
  if (!options.narrow || options.width <= svg::kNarrowWidth) return wide;
  LinePlotOptions narrow = options;
  narrow.width = svg::kNarrowWidth;
  narrow.height = std::max(240, options.height * 3 / 4);
  return svg::responsive(wide, draw_line_plot(series, narrow, false));
}

}  // namespace physgrad
