// Isolines of a sampled field by marching squares: the level set {f = level} as polylines with
// points interpolated linearly along grid edges.
#pragma once

#include <utility>
#include <vector>

#include "physgrad/report/field_plot.hpp"

namespace physgrad {

// The level set {f = level}: polylines (x, y) in data coordinates; a closed curve repeats its
// first point at the end. Saddle cells are resolved by the cell mean; cells with a non-finite
// corner are skipped. Throws Error for an invalid grid or a non-finite level.
std::vector<std::vector<std::pair<double, double>>> isolines(const Grid2D& grid, double level);

}  // namespace physgrad
