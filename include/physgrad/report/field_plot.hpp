// Fields on a regular grid as heat maps: the colour scale (linear, log10, or signed around 0),
// shading, colour bar and equal-aspect boxes, and a row of panels sharing one colour range.
// Colour of v: t = (s(v) − s(lo))/(s(hi) − s(lo)), s = log10 or identity, then a colormap.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "physgrad/report/plot_axes.hpp"
#include "physgrad/report/svg_document.hpp"

namespace physgrad {

// Field samples on a regular grid: values[j*nx + i] at x_i = x_min + i*(x_max-x_min)/(nx-1)
// and y_j = y_min + j*(y_max-y_min)/(ny-1).
struct Grid2D {
  double x_min, x_max, y_min, y_max;
  int nx, ny;
  std::vector<double> values;
};

// An n×n field of unit cells, values[j·n + i] in cell (i, j): nodes at the cell centres
// 0.5 … n − 0.5, so that panels of it span 0 … n.
Grid2D cell_grid(int n, const std::vector<double>& values);

// Throws Error for fewer than 2×2 nodes, a value count other than nx·ny, or a box that is not
// finite and non-empty.
void check_grid(const Grid2D& grid);

// How field values map to colours.
struct ColorScale {
  bool log = false;        // in log10; values ≤ 0 count as the smallest positive value
  bool diverging = false;  // blue–white–red with white at 0 (lo = −hi); else viridis
  double smallest = 0;     // the smallest positive value (log)
  double lo = 0, hi = 0;   // transformed bounds

  // Bounds from the finite values of all grids, or `range` (data units) when given.
  static ColorScale of(const std::vector<const Grid2D*>& grids, bool log, bool diverging,
                       std::optional<std::pair<double, double>> range = std::nullopt);
  double transform(double v) const;
  double unit(double v) const;  // position in [0, 1] (clamped)
  std::string color(double t) const;  // the colormap at t ∈ [0, 1]
  // The k-th of n levels evenly spaced (transformed) strictly inside (lo, hi), in data units.
  double level(int k, int n) const;
};

namespace plot {

// One rectangle per grid node, reaching halfway to its neighbours, coloured by `scale`; the
// colours are quantized so that cells of one colour share one path and runs along a row merge.
std::string shading(const Grid2D& grid, const Scale& sx, const Scale& sy, const ColorScale& scale);

// A vertical colour bar filling `bar`, its ticks and labels on the right and `label` beside them.
std::string color_bar(const svg::Box& bar, const ColorScale& scale, const std::string& label);
// Horizontal room a colour bar with its labels needs right of the plot.
double color_bar_width(const ColorScale& scale, const std::string& label);

// The largest box inside `available` whose sides have the ratio of the data extents (equal
// aspect: one data unit is as long along x as along y), placed at the top left.
svg::Box equal_aspect_box(const svg::Box& available, double x_extent, double y_extent);

}  // namespace plot

struct FieldPanel {
  std::string title;
  Grid2D grid;
};

struct FieldPanelsOptions {
  std::string title, x_label, y_label;
  std::string value_label;  // beside the colour bar, e.g. "temperature"
  bool log = false;
  bool diverging = false;   // signed fields: white at 0, symmetric range
  int panel_width = 180;    // pixels of each panel's plot box (height by equal aspect)
};

// The panels side by side in one row, at equal aspect, with one colour range spanning all
// of them and one colour bar; in its narrow layout (svg::responsive) in rows of as many as fit
// svg::kNarrowWidth. Throws Error for no panel or an invalid grid.
std::string field_panels_svg(const std::vector<FieldPanel>& panels,
                             const FieldPanelsOptions& options);

}  // namespace physgrad
