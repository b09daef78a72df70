// Standalone SVG figures: line plots (e.g. loss curves, linear or log axes) and 2-D loss
// landscapes with isolines and optimizer trajectories. Each function returns an SVG document.
#pragma once

#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace physgrad {

struct Series {
  std::string label;
  std::vector<double> x, y;
  std::string color{};  // any SVG colour; empty = a palette colour chosen by position
  bool markers = false;
  bool dashed = false;
  // Optional shaded band (e.g. mean ± std) drawn under the line: both empty or both the size
  // of x. Samples where a bound cannot be drawn are left out of the band.
  std::vector<double> band_low{}, band_high{};
};

struct LinePlotOptions {
  std::string title, x_label, y_label;
  bool log_x = false, log_y = false;
  int width = 640, height = 420;
};

// Points that are non-finite, or ≤ 0 on a log axis, are skipped and break the line.
// Throws Error when a series has x and y of different lengths or the size is below 200x150.
std::string line_plot_svg(const std::vector<Series>& series, const LinePlotOptions& options);

// A fixed colour for each optimizer id (gd, momentum, adam, newton, bfgs, lbfgs, gn, lm, ig,
// pg, sgd, hig, sip) and a palette colour chosen by a hash of the key otherwise; "#rrggbb".
std::string color_for(std::string_view key);

// Text for XML (SVG and HTML): & < > " ' escaped, control characters (invalid in XML) dropped.
std::string xml_escape(std::string_view text);

// Field samples on a regular grid: values[j*nx + i] at x_i = x_min + i*(x_max-x_min)/(nx-1)
// and y_j = y_min + j*(y_max-y_min)/(ny-1).
struct Grid2D {
  double x_min, x_max, y_min, y_max;
  int nx, ny;
  std::vector<double> values;
};

struct Trajectory {
  std::string label;
  std::vector<double> x, y;  // the iterates; non-finite ones are dropped
  std::string color{};       // empty = a palette colour chosen by position
};

struct Marker {
  double x, y;
  std::string label{};
};

struct LandscapeOptions {
  std::string title, x_label, y_label;
  int levels = 14;         // isolines, evenly spaced strictly between the field's min and max
  bool log_levels = true;  // space levels and colours in log10 (values ≤ 0 count as the
                           // smallest positive value)
  int width = 520, height = 480;
  std::vector<Marker> markers;  // drawn as labelled stars, e.g. the minimum
};

// Shaded field, isolines, trajectories (dots at iterates, circle at the start, square at the
// end), markers, legend and axes. Throws Error for an invalid grid, a trajectory with x and y
// of different lengths, negative levels or a size below 200x150.
std::string landscape_svg(const Grid2D& grid, const std::vector<Trajectory>& trajectories,
                          const LandscapeOptions& options);

// The level set {f = level} by marching squares: polylines (x, y) in data coordinates with
// points interpolated linearly along grid edges; a closed curve repeats its first point at the
// end. Saddle cells are resolved by the cell mean; cells with a non-finite corner are skipped.
// Throws Error for an invalid grid or a non-finite level.
std::vector<std::vector<std::pair<double, double>>> isolines(const Grid2D& grid, double level);

}  // namespace physgrad
