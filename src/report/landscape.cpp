#include "physgrad/report/landscape.hpp"

#include <algorithm>
#include <cmath>

#include "physgrad/error.hpp"
#include "physgrad/report/colors.hpp"
#include "physgrad/report/isolines.hpp"
#include "physgrad/report/plot_geometry.hpp"
#include "physgrad/report/plot_legend.hpp"

namespace physgrad {

namespace {

using plot::Box;
using plot::Point;
using plot::Polyline;
using svg::num;

std::string landscape_star(const Point& c, double r) {
  std::string points;
  for (int k = 0; k < 10; ++k) {
    const double angle = k * std::acos(-1.0) / 5, radius = k % 2 == 0 ? r : 0.45 * r;
    if (k > 0) points += " ";
    points += num(c.x + radius * std::sin(angle)) + "," + num(c.y - radius * std::cos(angle));
  }
  return "<polygon points=\"" + points + "\" fill=\"white\" stroke=\"black\"/>\n";
}

void check_landscape_options(const Grid2D& grid, const std::vector<Trajectory>& trajectories,
                   const LandscapeOptions& options) {
  check_grid(grid);
  if (options.width < 200 || options.height < 150) {
    throw Error("landscape_svg: a figure of " + std::to_string(options.width) + "x" +
                std::to_string(options.height) + " pixels is too small (at least 200x150)");
  }
  if (options.levels < 0) {
    throw Error("landscape_svg: levels = " + std::to_string(options.levels) + " is negative");
  }
  for (const Trajectory& t : trajectories) {
    if (t.x.size() != t.y.size()) {
      throw Error("landscape_svg: trajectory '" + t.label + "' has " + std::to_string(t.x.size()) +
                  " x values but " + std::to_string(t.y.size()) + " y values");
    }
  }
}

}  // namespace

namespace {

// The axes and the box of one layout (of equal aspect if asked), and the colour bar's width.
struct LandscapeFrame {
  plot::Axis ax, ay;
  Box box, bounds;
  double right = 0;  // the margin right of the box, holding the colour bar
};

LandscapeFrame landscape_frame(const Grid2D& grid, const ColorScale& scale,
                               const LandscapeOptions& options) {
  LandscapeFrame f;
  f.ax = plot::fixed_axis(grid.x_min, grid.x_max, false, 0, 1);
  f.ay = plot::fixed_axis(grid.y_min, grid.y_max, false, 1, 0);
  f.right = plot::color_bar_width(scale, options.value_label) + 14;
  const Box available{plot::left_margin(f.ay, !options.y_label.empty()),
                      plot::top_margin(options.title, options.width), options.width - f.right,
                      options.height - plot::kBottomMargin};
  f.box = options.equal_aspect ? plot::equal_aspect_box(available, grid.x_max - grid.x_min,
                                                        grid.y_max - grid.y_min)
                               : available;
  f.ax.scale.p0 = f.box.left;
  f.ax.scale.p1 = f.box.right;
  f.ay.scale.p0 = f.box.bottom;
  f.ay.scale.p1 = f.box.top;
  f.bounds = plot::bounds_of(f.box);
  return f;
}

// The isolines of `options.levels` evenly spaced levels over the shading.
std::string draw_isolines(const Grid2D& grid, const ColorScale& scale, const LandscapeFrame& f,
                          const LandscapeOptions& options) {
  std::string content;
  for (int k = 1; k <= options.levels && scale.hi > scale.lo; ++k) {
    std::vector<Polyline> lines;
    for (const auto& line : isolines(grid, scale.level(k, options.levels))) {
      Polyline& pixels = lines.emplace_back();
      for (const auto& [x, y] : line) pixels.push_back({f.ax.scale(x), f.ay.scale(y)});
    }
    content += svg::path(plot::line_path(lines, f.bounds),
                         "class=\"isoline\" fill=\"none\" stroke=\"white\" stroke-opacity=\"0.55\" "
                         "stroke-width=\"0.8\"");
  }
  return content;
}

// What the trajectories drawn so far left: the SVG inside the frame and over it, the legend
// entries, each path's pieces and its dash pattern (-1: solid).
struct TrajectoryParts {
  std::string content, notes;
  std::vector<plot::LegendEntry> entries;
  std::vector<std::vector<Polyline>> drawn;
  std::vector<int> dashes_of;
};

// A path that leaves the view (a diverging rule) is cut at its last step inside, and its way out
// drawn as an arrow at the frame; returns what the legend says of it ("" when it stays inside).
std::string cut_at_view(std::vector<Polyline>& pieces, const Box& box, const std::string& color,
                        std::string& notes) {
  if (pieces.empty()) return "";
  std::string left_at;
  Polyline& path = pieces.front();
  const auto out = std::find_if(path.begin(), path.end(),
                                [&](const Point& p) { return !svg::inside(p, box); });
  if (out != path.end() && out != path.begin()) {
    Point a = *(out - 1), b = *out;
    const auto step = out - path.begin();
    if (plot::clip_segment(a, b, box)) {
      notes += svg::path(std::string("M") + num(a.x) + " " + num(a.y) + "L" + num(b.x) + " " +
                             num(b.y),
                         "stroke=\"" + color + "\" stroke-width=\"1.6\" stroke-dasharray=\"2 3\"");
      notes += "<circle cx=\"" + num(b.x) + "\" cy=\"" + num(b.y) + "\" r=\"3.5\" fill=\"" +
               color + "\" stroke=\"white\"/>\n";
    }
    left_at = " (leaves the view at step " + std::to_string(step) + ")";
    path.erase(out, path.end());
  } else if (out == path.begin()) {
    left_at = " (outside the view)";
    path.clear();
  }
  if (path.empty()) pieces.clear();
  return left_at;
}

// The path's line (with a white halo unless it retraces another, which it would hide) and dots
// in one group, its start as a white circle and its end, where inside, as a square.
std::string draw_path(const std::vector<Polyline>& pieces, const Trajectory& t,
                      const LandscapeFrame& f, const std::string& color,
                      const std::string& dashes, const std::string& left_at) {
  const std::string d = plot::line_path(pieces, f.bounds);
  std::string out;
  if (dashes.empty()) {
    out += svg::path(d,
                     "fill=\"none\" stroke=\"white\" stroke-opacity=\"0.7\" "
                     "stroke-width=\"3.6\" stroke-linejoin=\"round\" stroke-linecap=\"round\"");
  }
  // A path with nothing to draw says why, here and in its legend entry.
  const std::string not_drawn = pieces.empty() ? left_at.substr(2, left_at.size() - 3) : "";
  out += "<g class=\"series\" data-label=\"" + xml_escape(t.label) + "\"" +
         (not_drawn.empty() ? "" : " data-empty=\"" + xml_escape(not_drawn) + "\"") + ">\n";
  out += svg::path(d, "fill=\"none\" stroke=\"" + color +
                          "\" stroke-width=\"1.6\" stroke-linejoin=\"round\" "
                          "stroke-linecap=\"round\" class=\"line\"" +
                          (dashes.empty() ? "" : " stroke-dasharray=\"" + dashes + "\""));
  out += svg::path(plot::dot_path(pieces, f.bounds),
                   "stroke=\"" + color + "\" stroke-width=\"3.6\" stroke-linecap=\"round\" "
                   "class=\"marker\" data-shape=\"0\"");
  out += "</g>\n";
  if (!pieces.empty() && svg::inside(pieces[0].front(), f.bounds)) {
    const Point& p = pieces[0].front();
    out += "<circle cx=\"" + num(p.x) + "\" cy=\"" + num(p.y) +
           "\" r=\"4.5\" fill=\"white\" stroke=\"" + color + "\" stroke-width=\"1.8\"/>\n";
  }
  if (!pieces.empty() && left_at.empty() && svg::inside(pieces[0].back(), f.bounds)) {
    const Point& p = pieces[0].back();
    out += svg::rect({p.x - 4, p.y - 4, p.x + 4, p.y + 4},
                     "fill=\"" + color + "\" stroke=\"white\"");
  }
  return out;
}

// Trajectory n; a path that retraces earlier ones gets dashes of its own and says so in the
// legend.
void draw_trajectory(const std::vector<Trajectory>& trajectories, std::size_t n,
                     const LandscapeFrame& f, TrajectoryParts& parts) {
  const Trajectory& t = trajectories[n];
  const std::string color = xml_escape(t.color.empty() ? palette_color(n) : t.color);
  std::vector<Polyline> pieces = plot::to_pixels(t.x, t.y, f.ax.scale, f.ay.scale, false);
  std::string left_at = cut_at_view(pieces, f.box, color, parts.notes);
  const std::vector<std::size_t> under = plot::retraced(pieces, parts.drawn, f.box);
  parts.drawn.push_back(pieces);
  std::string coincides;
  std::vector<int> taken;
  for (const std::size_t k : under) {
    coincides += (coincides.empty() ? "" : ", ") + trajectories[k].label;
    taken.push_back(parts.dashes_of[k]);
  }
  parts.dashes_of.push_back(under.empty() ? -1 : plot::free_dash_pattern(taken));
  const std::string dashes = under.empty() ? "" : plot::dash_pattern(parts.dashes_of.back());
  if (pieces.empty() && left_at.empty()) left_at = " (not drawn: no finite point)";
  parts.content += draw_path(pieces, t, f, color, dashes, left_at);
  parts.entries.push_back(
      {t.label + left_at + (coincides.empty() ? "" : " (coincides with " + coincides + ")"), color,
       true, dashes, true, false});
}

// The options' markers: a star with its label, where inside.
std::string draw_landscape_markers(const LandscapeOptions& options, const LandscapeFrame& f) {
  std::string content;
  for (const Marker& m : options.markers) {
    const Point p{f.ax.scale(m.x), f.ay.scale(m.y)};
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !svg::inside(p, f.bounds)) continue;
    content += landscape_star(p, 8);
    if (m.label.empty()) continue;
    const bool left = p.x > (f.box.left + f.box.right) / 2;
    content += svg::text(left ? p.x - 9 : p.x + 9, p.y - 8, m.label,
                         std::string(left ? "text-anchor=\"end\" " : "") +
                             "fill=\"black\" stroke=\"white\" stroke-width=\"3\" "
                             "paint-order=\"stroke\"");
  }
  return content;
}

std::string draw_landscape(const Grid2D& grid, const std::vector<Trajectory>& trajectories,
                           const LandscapeOptions& options) {
  const ColorScale scale =
      ColorScale::of({&grid}, options.log_levels, false, options.value_range);
  const LandscapeFrame f = landscape_frame(grid, scale, options);
  TrajectoryParts parts;
  parts.content = plot::shading(grid, f.ax.scale, f.ay.scale, scale) +
                  draw_isolines(grid, scale, f, options);
  for (std::size_t n = 0; n < trajectories.size(); ++n) draw_trajectory(trajectories, n, f, parts);
  parts.content += draw_landscape_markers(options, f);
  const Box& box = f.box;
  const double title_width =
      std::min(svg::text_width(options.title, 14) + 20, static_cast<double>(options.width));
  const int width = static_cast<int>(std::ceil(std::max(
      {box.right + f.right, title_width,
       std::min(plot::legend_entry_width(parts.entries), static_cast<double>(options.width))})));
  const double below = box.bottom + 48;
  const plot::LegendLayout legend =
      plot::legend(parts.entries, box, plot::Occupancy(box), below, width, false);
  const int height = static_cast<int>(std::ceil(below + legend.height_below + 8));
  const Box bar{box.right + 12, box.top, box.right + 26, box.bottom};
  return svg::open(width, height) + svg::clipped(box, parts.content) + parts.notes +
         plot::axes(width, box, f.ax, f.ay, {options.title, options.x_label, options.y_label}) +
         plot::color_bar(bar, scale, options.value_label) + legend.svg + "</svg>\n";
}

}  // namespace

std::string landscape_svg(const Grid2D& grid, const std::vector<Trajectory>& trajectories,
                          const LandscapeOptions& options) {
  check_landscape_options(grid, trajectories, options);
  const std::string wide = draw_landscape(grid, trajectories, options);
  if (svg::size_of(wide).first <= svg::kNarrowWidth) return wide;
  LandscapeOptions narrow = options;
  narrow.width = svg::kNarrowWidth;
  return svg::responsive(wide, draw_landscape(grid, trajectories, narrow));
}

}  // namespace physgrad
