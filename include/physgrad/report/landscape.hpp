// 2-D loss landscapes: the shaded field with a colour bar, isolines, optimizer trajectories and
// labelled markers, at equal aspect (one data unit as long along x as along y). Returns SVG.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "physgrad/report/field_plot.hpp"

namespace physgrad {

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
  int levels = 14;         // isolines, evenly spaced strictly between the colour range's ends
  bool log_levels = true;  // space levels and colours in log10 (values ≤ 0 count as the
                           // smallest positive value)
  int width = 520, height = 480;  // the largest size; equal aspect may make the figure smaller
  std::vector<Marker> markers;    // drawn as labelled stars, e.g. the minimum
  std::string value_label{};      // beside the colour bar, e.g. "L"
  bool equal_aspect = true;
  // The values the colours span (e.g. shared by several figures); unset: the field's range.
  std::optional<std::pair<double, double>> value_range{};
};

// Shaded field, isolines, trajectories (dots at iterates, circle at the start, square at the
// end), markers, axes, colour bar and a legend below the plot (the field fills the box). Throws
// Error for an invalid grid, a trajectory with x and y of different lengths, negative levels or
// a size below 200x150.
std::string landscape_svg(const Grid2D& grid, const std::vector<Trajectory>& trajectories,
                          const LandscapeOptions& options);

}  // namespace physgrad
