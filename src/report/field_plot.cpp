#include "physgrad/report/field_plot.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "physgrad/error.hpp"
#include "physgrad/report/colors.hpp"
#include "physgrad/types.hpp"

namespace physgrad {

namespace {

constexpr int kShades = 64;  // colormap steps of shading and colour bars
constexpr double kBarWidth = 14;

// The colour bar's axis in data units (a constant field gets a small range around its value).
plot::Axis bar_axis(const ColorScale& scale, double p0, double p1) {
  double lo = scale.log ? std::pow(10.0, scale.lo) : scale.lo;
  double hi = scale.log ? std::pow(10.0, scale.hi) : scale.hi;
  if (!(hi > lo)) {
    if (scale.log) {
      lo = lo > 0 ? lo / 2 : 0.5;
      hi = lo * 4;
    } else {
      const double pad = lo == 0 ? 1 : 0.1 * std::abs(lo);
      lo -= pad;
      hi += pad;
    }
  }
  return plot::fixed_axis(lo, hi, scale.log, p0, p1);
}

}  // namespace

Grid2D cell_grid(int n, const std::vector<double>& values) {
  const double last = n - 0.5;
  return {0.5, last, 0.5, last, n, n, values};
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

ColorScale ColorScale::of(const std::vector<const Grid2D*>& grids, bool log, bool diverging,
                          std::optional<std::pair<double, double>> range) {
  double min = kInf, max = -kInf, min_positive = kInf;
  for (const Grid2D* grid : grids) {
    for (const double v : grid->values) {
      if (!std::isfinite(v)) continue;
      min = std::min(min, v);
      max = std::max(max, v);
      if (v > 0) min_positive = std::min(min_positive, v);
    }
  }
  if (range && std::isfinite(range->first) && std::isfinite(range->second)) {
    min = range->first;
    max = range->second;
    if (min > 0) min_positive = min;
  }
  ColorScale s;
  s.diverging = diverging;
  s.log = log && !diverging && min_positive < kInf;
  s.smallest = min_positive;
  if (min > max) return s;  // no finite value
  if (diverging) {
    s.hi = std::max(std::abs(min), std::abs(max));
    s.lo = -s.hi;
  } else {
    s.lo = s.transform(min);
    s.hi = s.transform(max);
  }
  return s;
}

double ColorScale::transform(double v) const {
  return log ? std::log10(std::max(v, smallest)) : v;
}

double ColorScale::unit(double v) const {
  return hi > lo ? std::clamp((transform(v) - lo) / (hi - lo), 0.0, 1.0) : 0.5;
}

std::string ColorScale::color(double t) const {
  return diverging ? blue_white_red(t) : viridis(t);
}

double ColorScale::level(int k, int n) const {
  const double t = lo + (hi - lo) * k / (n + 1);
  return log ? std::pow(10.0, t) : t;
}

namespace plot {

std::string shading(const Grid2D& g, const Scale& sx, const Scale& sy, const ColorScale& scale) {
  // Cell edges halfway between nodes, cut to the axis' pixel range.
  const auto edges = [](int n, double lo, double hi, const Scale& s) {
    std::vector<double> e(static_cast<std::size_t>(n) + 1);
    const double step = (hi - lo) / (n - 1);
    const double p_lo = std::min(s.p0, s.p1), p_hi = std::max(s.p0, s.p1);
    for (int k = 0; k <= n; ++k) {
      e[static_cast<std::size_t>(k)] = std::clamp(s(lo + (k - 0.5) * step), p_lo, p_hi);
    }
    return e;
  };
  const std::vector<double> ex = edges(g.nx, g.x_min, g.x_max, sx);
  const std::vector<double> ey = edges(g.ny, g.y_min, g.y_max, sy);
  const auto shade = [&](int i, int j) {
    const double v = g.values[static_cast<std::size_t>(j) * g.nx + i];
    return std::isfinite(v) ? std::min(kShades - 1, static_cast<int>(scale.unit(v) * kShades)) : -1;
  };
  std::array<std::string, kShades> paths;
  for (int j = 0; j < g.ny; ++j) {
    for (int i = 0; i < g.nx;) {
      const int q = shade(i, j);
      int end = i + 1;
      while (end < g.nx && shade(end, j) == q) ++end;
      if (q >= 0) {
        const auto ju = static_cast<std::size_t>(j);
        std::string& d = paths[static_cast<std::size_t>(q)];
        d += 'M';
        d += svg::num(ex[static_cast<std::size_t>(i)]) + " " + svg::num(ey[ju + 1]) + "H" +
             svg::num(ex[static_cast<std::size_t>(end)]) + "V" + svg::num(ey[ju]) + "H" +
             svg::num(ex[static_cast<std::size_t>(i)]) + "Z";
      }
      i = end;
    }
  }
  std::string out = "<g shape-rendering=\"crispEdges\">\n";
  for (int q = 0; q < kShades; ++q) {
    out += svg::path(paths[static_cast<std::size_t>(q)],
                     "fill=\"" + scale.color((q + 0.5) / kShades) + "\"");
  }
  return out + "</g>\n";
}

double color_bar_width(const ColorScale& scale, const std::string& label) {
  return kBarWidth + 10 + widest_label(bar_axis(scale, 1, 0)) + (label.empty() ? 4 : 24);
}

std::string color_bar(const svg::Box& bar, const ColorScale& scale, const std::string& label) {
  std::string out = "<g class=\"colorbar\" shape-rendering=\"crispEdges\">\n";
  const double step = bar.height() / kShades;
  for (int q = 0; q < kShades; ++q) {
    const double top = bar.bottom - (q + 1) * step;
    out += svg::rect({bar.left, top, bar.right, top + step + 0.5},
                     "fill=\"" + scale.color((q + 0.5) / kShades) + "\"");
  }
  out += "</g>\n" + svg::rect(bar, "fill=\"none\" stroke=\"#333\"");
  const Axis axis = bar_axis(scale, bar.bottom, bar.top);
  out += right_ticks(bar.right, bar, axis);
  if (!label.empty()) {
    out += "<text transform=\"translate(" + svg::num(bar.right + 10 + widest_label(axis) + 16) +
           " " +
           svg::num((bar.top + bar.bottom) / 2) + ") rotate(-90)\" text-anchor=\"middle\">" +
           xml_escape(label) + "</text>\n";
  }
  return out;
}

svg::Box equal_aspect_box(const svg::Box& available, double x_extent, double y_extent) {
  const double ratio = y_extent / x_extent;
  double w = available.width(), h = w * ratio;
  if (h > available.height()) {
    h = available.height();
    w = h / ratio;
  }
  return {available.left, available.top, available.left + w, available.top + h};
}

}  // namespace plot

namespace {

// The panels in rows of `columns`, the colour bar right of the first row reaching down to the
// last.
std::string draw_field_panels(const std::vector<FieldPanel>& panels,
                              const FieldPanelsOptions& options, std::size_t columns,
                              int title_width = 100000) {
  const std::vector<std::string> title = plot::title_lines(options.title, title_width);
  std::vector<const Grid2D*> grids;
  for (const FieldPanel& p : panels) {
    check_grid(p.grid);
    grids.push_back(&p.grid);
  }
  const ColorScale scale = ColorScale::of(grids, options.log, options.diverging);
  const double first_top = plot::top_margin(options.title, title_width) + 10;  // and panel titles
  double top = first_top, right = 0;
  // Cells: each node stands for the cell around it, so the axes reach half a cell further.
  const auto cell_extent = [](const Grid2D& g) {
    const double hx = 0.5 * (g.x_max - g.x_min) / (g.nx - 1);
    const double hy = 0.5 * (g.y_max - g.y_min) / (g.ny - 1);
    return svg::Box{g.x_min - hx, g.y_min - hy, g.x_max + hx, g.y_max + hy};
  };
  std::string body;
  double x = 0, row_bottom = top;
  for (std::size_t k = 0; k < panels.size(); ++k) {
    if (k > 0 && k % columns == 0) {  // a new row
      x = 0;
      top = row_bottom + plot::kBottomMargin + 14;
    }
    const Grid2D& g = panels[k].grid;
    const svg::Box extent = cell_extent(g);
    plot::Axis ay = plot::fixed_axis(extent.top, extent.bottom, false, 1, 0);
    const double left = x + plot::left_margin(ay, k % columns == 0 && !options.y_label.empty());
    const svg::Box box = plot::equal_aspect_box(
        {left, top, left + options.panel_width, top + 4.0 * options.panel_width},
        extent.width(), extent.height());
    plot::Axis ax = plot::fixed_axis(extent.left, extent.right, false, box.left, box.right);
    ay.scale.p0 = box.bottom;
    ay.scale.p1 = box.top;
    body += svg::clipped(box, plot::shading(g, ax.scale, ay.scale, scale));
    body += plot::axes(0, box, ax, ay,
                       {"", options.x_label, k % columns == 0 ? options.y_label : std::string()});
    body += svg::text((box.left + box.right) / 2, top - 8, panels[k].title,
                      "text-anchor=\"middle\" font-weight=\"bold\"");
    x = box.right + 6;
    right = std::max(right, x);
    row_bottom = std::max(row_bottom, box.bottom);
  }
  const svg::Box bar{right + 10, first_top, right + 10 + kBarWidth, row_bottom};
  const int width = static_cast<int>(
      std::ceil(std::max(bar.left + plot::color_bar_width(scale, options.value_label) + 4,
                         std::min(svg::text_width(options.title, 14) + 20,
                                  static_cast<double>(title_width)))));
  const int height = static_cast<int>(std::ceil(row_bottom + plot::kBottomMargin));
  std::string out = svg::open(width, height) + body + plot::color_bar(bar, scale, options.value_label);
  for (std::size_t k = 0; k < title.size(); ++k) {
    out += svg::text(width / 2.0, 20 + 17 * static_cast<double>(k), title[k],
                     "text-anchor=\"middle\" font-size=\"14\" font-weight=\"bold\"");
  }
  return out + "</svg>\n";
}

}  // namespace

std::string field_panels_svg(const std::vector<FieldPanel>& panels,
                             const FieldPanelsOptions& options) {
  if (panels.empty()) throw Error("field_panels_svg: no panel to draw");
  if (options.panel_width < 60) {
    throw Error("field_panels_svg: panels of " + std::to_string(options.panel_width) +
                " pixels are too small (at least 60)");
  }
  const std::string wide = draw_field_panels(panels, options, panels.size());
  if (svg::size_of(wide).first <= svg::kNarrowWidth) return wide;
  // Fewer panels a row until the figure fits; one a row, narrower panels.
  for (std::size_t columns = panels.size() - 1; columns >= 1; --columns) {
    const std::string narrow = draw_field_panels(panels, options, columns, svg::kNarrowWidth);
    if (svg::size_of(narrow).first <= svg::kNarrowWidth) return svg::responsive(wide, narrow);
  }
  FieldPanelsOptions smaller = options;
  smaller.panel_width = 60;
  for (int w = options.panel_width; w >= 60; w -= 10) {
    smaller.panel_width = w;
    if (svg::size_of(draw_field_panels(panels, smaller, 1, svg::kNarrowWidth)).first <=
        svg::kNarrowWidth) {
      break;
    }
  }
  return svg::responsive(wide, draw_field_panels(panels, smaller, 1, svg::kNarrowWidth));
}

}  // namespace physgrad
