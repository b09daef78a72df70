// Several runs of one setting (e.g. one per seed) drawn as one series: the median at each x and
// the min–max band, m(x) = median_k y_k(x) with y_k(x) = y_k at the last point of run k at or
// before x (a run holds its last value after it ended; before its first point it does not count).
#pragma once

#include <string>
#include <vector>

#include "physgrad/report/line_plot.hpp"

namespace physgrad {

struct Curve {
  std::vector<double> x, y;  // x ascending; non-finite points are ignored
};

// A series over the union of the curves' x (at most `max_points`, evenly picked) whose y is the
// median of the curves and whose band is their minimum and maximum (no band for a single
// curve). With `log`, the median of an even count is the geometric mean of the middle two.
// Throws Error when a curve has x and y of different lengths.
Series median_band(const std::string& label, const std::vector<Curve>& curves,
                   const std::string& color, bool log, std::size_t max_points = 1000);

}  // namespace physgrad
