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

// A ◆ at p, outlined in white.
std::string diamond(const Point& p, const std::string& color) {
  return svg::path(plot::marker_path(3, p, 9),
                   "fill=\"" + color + "\" stroke=\"white\" stroke-width=\"1.2\"");
}

// The figure in one layout; the legend inside the plot where it covers no data when
// `legend_inside`, else below it.
std::string draw_line_plot(const std::vector<Series>& series, const LinePlotOptions& options,
                           bool legend_inside) {
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
                plot::top_margin(options.title, options.width), options.width - 16.0,
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
  std::vector<int> shapes;                    // the marker shape each series was drawn with
  std::vector<int> dashes_of;                 // and its dash pattern (-1: solid)
  std::string hover;
  for (std::size_t n = 0; n < series.size(); ++n) {
    const Series& s = series[n];
    const std::string color = xml_escape(s.color.empty() ? palette_color(n) : s.color);
    std::string group;  // the series' band, line and markers
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
      group += svg::path(band, "fill=\"" + color + "\" fill-opacity=\"0.18\"");
      for (std::size_t k = 0; k < band_x.size(); ++k) {
        occupied.mark_segment({ax.scale(band_x[k]), sy(low[k])}, {ax.scale(band_x[k]), sy(high[k])});
      }
    }
    // A series that retraces earlier ones gets its own dashes and marker shape, its markers set
    // off from theirs, and says so in the legend: both stay visible.
    const std::vector<std::size_t> under = plot::retraced(pieces, drawn, box);
    drawn.push_back(pieces);
    const int retraced = static_cast<int>(under.size());
    int dash = s.dashed ? s.dash_pattern : -1;  // -1: solid
    if (retraced > 0) {  // a pattern none of those it retraces has
      std::vector<int> taken;
      for (const std::size_t k : under) taken.push_back(dashes_of[k]);
      dash = plot::free_dash_pattern(taken);
    }
    dashes_of.push_back(dash);
    const std::string dashes = dash < 0 ? "" : plot::dash_pattern(dash);
    group += svg::path(plot::line_path(pieces, bounds),
                       "fill=\"none\" stroke=\"" + color +
                           "\" stroke-width=\"1.8\" stroke-linejoin=\"round\" "
                           "stroke-linecap=\"round\" class=\"line\"" +
                           (dashes.empty() ? "" : " stroke-dasharray=\"" + dashes + "\""));
    int shape = s.markers ? s.shape : -1;
    std::string coincides;
    for (const std::size_t k : under) {
      coincides += (coincides.empty() ? "" : ", ") + series[k].label;
      if (shape < 0 || shape == shapes[k]) shape = -1;
    }
    if (retraced > 0 && shape < 0) {  // a shape none of those it retraces has
      for (int candidate = 1; candidate < plot::kShapes + 1 && shape < 0; ++candidate) {
        const bool taken = std::any_of(under.begin(), under.end(),
                                       [&](std::size_t k) { return shapes[k] == candidate; });
        if (!taken) shape = candidate;
      }
    }
    shapes.push_back(shape);
    const std::vector<Polyline> points = plot::to_pixels(s.x, s.y, ax.scale, sy, false);
    const std::size_t count = points.empty() ? 0 : points.front().size();
    if (shape >= 0) {
      // Markers of series drawn on one another are spread over the points in turns (a series
      // of one point keeps it).
      std::size_t every = retraced > 0                ? std::max<std::size_t>(2, count / 12)
                          : shape > 0 && count > 24 ? count / 12
                                                    : 1;
      every = std::min(every, std::max<std::size_t>(count, 1));
      const double size = shape == 0 ? (count <= 40 ? 5 : count <= 120 ? 3 : 2) : 7;
      group += plot::markers_svg(points, bounds, shape, size, color, every,
                                 retraced * std::max<std::size_t>(1, every / 3));
    }
    // Every point its values on hover, with the band's ends (e.g. the seeds' range) where drawn.
    std::vector<plot::HoverPoint> targets;
    const bool band = has_band(s);
    for (std::size_t k = 0; k < s.x.size(); ++k) {
      const Point p{ax.scale(s.x[k]), y_pixel(s.y[k])};
      if (!(std::isfinite(p.x) && std::isfinite(p.y))) continue;
      targets.push_back({p, s.x[k], s.y[k], band ? s.band_low[k] : NAN,
                         band ? s.band_high[k] : NAN});
    }
    hover += plot::hover_targets(targets, box, s.label,
                                 options.x_label.empty() ? "x" : options.x_label,
                                 options.y_label.empty() ? "y" : options.y_label, targets.size());
    for (const Series::Mark& mark : s.marks) {
      const Point p{ax.scale(mark.x), y_pixel(mark.y)};
      if (!(std::isfinite(p.x) && std::isfinite(p.y) && svg::inside(p, box))) continue;
      notes += "<g class=\"mark\"><title>" + xml_escape(s.label + ": " + mark.label) +
               "</title>\n" + diamond(p, color) + "</g>\n";
      occupied.mark_box({p.x - 6, p.y - 6, p.x + 6, p.y + 6});
    }
    // A series with no point to draw says why, here and in its legend entry.
    const std::string not_drawn =
        !pieces.empty() ? "" : s.end_label.empty() ? "no finite value" : s.end_label;
    content += "<g class=\"series\" data-label=\"" + xml_escape(s.label) + "\"" +
               (not_drawn.empty() ? "" : " data-empty=\"" + xml_escape(not_drawn) + "\"") +
               ">\n" + group + "</g>\n";
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
    std::string label = s.label.empty() ? "" : s.label + zero_note;
    if (!label.empty() && !coincides.empty()) label += " (coincides with " + coincides + ")";
    if (!label.empty() && !s.marks.empty()) label += " (◆ " + s.marks.front().label + ")";
    if (!label.empty() && !not_drawn.empty()) label += " (not drawn: " + not_drawn + ")";
    entries.push_back({label, color, true, dashes, shape == 0, has_band(s), shape});
  }
  const plot::LegendLayout legend =
      plot::legend(entries, box, occupied, options.height - 4.0, options.width, legend_inside);
  const int height = options.height + static_cast<int>(std::ceil(legend.height_below));
  // The clip reaches a little past the frame, so that lines along the data range's ends
  // (which the axes end at) show in full.
  return svg::open(options.width, height) + plot::grid_lines(box, ax, ay) +
         svg::clipped(svg::grow(box, 3, 3), content) +
         plot::axes(options.width, box, ax, ay,
                    {options.title, log_marked(options.x_label, options.log_x),
                     log_marked(options.y_label, options.log_y)}) +
         notes + hover + legend.svg + "</svg>\n";
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
