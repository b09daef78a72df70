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

std::string star(const Point& c, double r) {
  std::string points;
  for (int k = 0; k < 10; ++k) {
    const double angle = k * std::acos(-1.0) / 5, radius = k % 2 == 0 ? r : 0.45 * r;
    if (k > 0) points += " ";
    points += num(c.x + radius * std::sin(angle)) + "," + num(c.y - radius * std::cos(angle));
  }
  return "<polygon points=\"" + points + "\" fill=\"white\" stroke=\"black\"/>\n";
}

void check_options(const Grid2D& grid, const std::vector<Trajectory>& trajectories,
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

std::string draw_landscape(const Grid2D& grid, const std::vector<Trajectory>& trajectories,
                           const LandscapeOptions& options) {
  const ColorScale scale =
      ColorScale::of({&grid}, options.log_levels, false, options.value_range);
  plot::Axis ax = plot::fixed_axis(grid.x_min, grid.x_max, false, 0, 1);
  plot::Axis ay = plot::fixed_axis(grid.y_min, grid.y_max, false, 1, 0);
  const double right = plot::color_bar_width(scale, options.value_label) + 14;
  const Box available{plot::left_margin(ay, !options.y_label.empty()),
                      plot::top_margin(options.title, options.width), options.width - right,
                      options.height - plot::kBottomMargin};
  const Box box = options.equal_aspect
                      ? plot::equal_aspect_box(available, grid.x_max - grid.x_min,
                                               grid.y_max - grid.y_min)
                      : available;
  ax.scale.p0 = box.left;
  ax.scale.p1 = box.right;
  ay.scale.p0 = box.bottom;
  ay.scale.p1 = box.top;
  const Box bounds = plot::bounds_of(box);

  std::string content = plot::shading(grid, ax.scale, ay.scale, scale);
  for (int k = 1; k <= options.levels && scale.hi > scale.lo; ++k) {
    std::vector<Polyline> lines;
    for (const auto& line : isolines(grid, scale.level(k, options.levels))) {
      Polyline& pixels = lines.emplace_back();
      for (const auto& [x, y] : line) pixels.push_back({ax.scale(x), ay.scale(y)});
    }
    content += svg::path(plot::line_path(lines, bounds),
                         "class=\"isoline\" fill=\"none\" stroke=\"white\" stroke-opacity=\"0.55\" "
                         "stroke-width=\"0.8\"");
  }

  std::vector<plot::LegendEntry> entries;
  std::vector<std::vector<Polyline>> drawn;
  std::vector<int> dashes_of;  // each path's dash pattern (-1: solid)
  std::string notes;
  for (std::size_t n = 0; n < trajectories.size(); ++n) {
    const Trajectory& t = trajectories[n];
    const std::string color = xml_escape(t.color.empty() ? palette_color(n) : t.color);
    std::vector<Polyline> pieces = plot::to_pixels(t.x, t.y, ax.scale, ay.scale, false);
    // A path that leaves the view (a diverging rule) is drawn up to its last step inside, and
    // its way out as an arrow at the frame labelled with the step: no stripes across the field.
    std::string left_at;
    if (!pieces.empty()) {
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
    }
    // A path that retraces earlier ones gets dashes of its own and says so in the legend.
    const std::vector<std::size_t> under = plot::retraced(pieces, drawn, box);
    drawn.push_back(pieces);
    std::string coincides;
    std::vector<int> taken;
    for (const std::size_t k : under) {
      coincides += (coincides.empty() ? "" : ", ") + trajectories[k].label;
      taken.push_back(dashes_of[k]);
    }
    dashes_of.push_back(under.empty() ? -1 : plot::free_dash_pattern(taken));
    const std::string dashes = under.empty() ? "" : plot::dash_pattern(dashes_of.back());
    const std::string d = plot::line_path(pieces, bounds);
    // A white halo under the path, but not under one that retraces another (it would hide it).
    if (dashes.empty()) {
      content += svg::path(d,
                           "fill=\"none\" stroke=\"white\" stroke-opacity=\"0.7\" "
                           "stroke-width=\"3.6\" stroke-linejoin=\"round\" stroke-linecap=\"round\"");
    }
    // A path with nothing to draw says why, here and in its legend entry.
    if (pieces.empty() && left_at.empty()) left_at = " (not drawn: no finite point)";
    const std::string not_drawn = pieces.empty() ? left_at.substr(2, left_at.size() - 3) : "";
    content += "<g class=\"series\" data-label=\"" + xml_escape(t.label) + "\"" +
               (not_drawn.empty() ? "" : " data-empty=\"" + xml_escape(not_drawn) + "\"") + ">\n";
    content += svg::path(d, "fill=\"none\" stroke=\"" + color +
                                "\" stroke-width=\"1.6\" stroke-linejoin=\"round\" "
                                "stroke-linecap=\"round\" class=\"line\"" +
                                (dashes.empty() ? "" : " stroke-dasharray=\"" + dashes + "\""));
    content += svg::path(plot::dot_path(pieces, bounds),
                         "stroke=\"" + color + "\" stroke-width=\"3.6\" stroke-linecap=\"round\" "
                         "class=\"marker\" data-shape=\"0\"");
    content += "</g>\n";
    if (!pieces.empty() && svg::inside(pieces[0].front(), bounds)) {
      const Point& p = pieces[0].front();
      content += "<circle cx=\"" + num(p.x) + "\" cy=\"" + num(p.y) +
                 "\" r=\"4.5\" fill=\"white\" stroke=\"" + color + "\" stroke-width=\"1.8\"/>\n";
    }
    if (!pieces.empty() && left_at.empty() && svg::inside(pieces[0].back(), bounds)) {
      const Point& p = pieces[0].back();
      content += svg::rect({p.x - 4, p.y - 4, p.x + 4, p.y + 4},
                           "fill=\"" + color + "\" stroke=\"white\"");
    }
    entries.push_back({t.label + left_at + (coincides.empty() ? "" : " (coincides with " +
                                                                   coincides + ")"),
                       color, true, dashes, true, false});
  }
  for (const Marker& m : options.markers) {
    const Point p{ax.scale(m.x), ay.scale(m.y)};
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !svg::inside(p, bounds)) continue;
    content += star(p, 8);
    if (!m.label.empty()) {
      const bool left = p.x > (box.left + box.right) / 2;
      content += svg::text(left ? p.x - 9 : p.x + 9, p.y - 8, m.label,
                           std::string(left ? "text-anchor=\"end\" " : "") +
                               "fill=\"black\" stroke=\"white\" stroke-width=\"3\" "
                               "paint-order=\"stroke\"");
    }
  }
  const double title_width =
      std::min(svg::text_width(options.title, 14) + 20, static_cast<double>(options.width));
  const int width = static_cast<int>(std::ceil(std::max(
      {box.right + right, title_width,
       std::min(plot::legend_entry_width(entries), static_cast<double>(options.width))})));
  const double below = box.bottom + 48;
  const plot::LegendLayout legend =
      plot::legend(entries, box, plot::Occupancy(box), below, width, false);
  const int height = static_cast<int>(std::ceil(below + legend.height_below + 8));
  const Box bar{box.right + 12, box.top, box.right + 26, box.bottom};
  return svg::open(width, height) + svg::clipped(box, content) + notes +
         plot::axes(width, box, ax, ay, {options.title, options.x_label, options.y_label}) +
         plot::color_bar(bar, scale, options.value_label) + legend.svg + "</svg>\n";
}

}  // namespace

std::string landscape_svg(const Grid2D& grid, const std::vector<Trajectory>& trajectories,
                          const LandscapeOptions& options) {
  check_options(grid, trajectories, options);
  const std::string wide = draw_landscape(grid, trajectories, options);
  if (svg::size_of(wide).first <= svg::kNarrowWidth) return wide;
  LandscapeOptions narrow = options;
  narrow.width = svg::kNarrowWidth;
  return svg::responsive(wide, draw_landscape(grid, trajectories, narrow));
}

}  // namespace physgrad
