// Pixel geometry of plots: polylines cut to a box (Liang–Barsky), data mapped to pixels with
// undrawable points left out or breaking the line, and the path data of lines, bands and dots.
#pragma once

#include <string>
#include <vector>

#include "physgrad/report/plot_axes.hpp"
#include "physgrad/report/svg_document.hpp"

namespace physgrad::plot {

using svg::Box;
using svg::Point;
using svg::Polyline;

// Cuts the segment a–b to the box; false when nothing of it is inside.
bool clip_segment(Point& a, Point& b, const Box& box);
// The parts of a polyline inside the box (a lone point inside stays a piece of one point).
std::vector<Polyline> clip(const Polyline& line, const Box& box);

// The points of (x, y) that can be drawn, in pixels. With `split`, a point that cannot be drawn
// ends the current piece; otherwise it is just left out.
std::vector<Polyline> to_pixels(const std::vector<double>& x, const std::vector<double>& y,
                                const Scale& sx, const Scale& sy, bool split);

// Path data for the pieces cut to `bounds`; a lone point becomes a dot (with round caps).
std::string line_path(const std::vector<Polyline>& pieces, const Box& bounds);
// Path data with a zero-length subpath per point inside `bounds`: dots when stroked with round
// caps.
std::string dot_path(const std::vector<Polyline>& pieces, const Box& bounds);
// The part of a closed polygon inside the box (Sutherland–Hodgman); fewer than three points
// when nothing is inside.
Polyline clip_polygon(const Polyline& polygon, const Box& box);
// Closed path data of the band between `low` and `high` over x, cut to `bounds`; samples where
// a bound cannot be drawn are left out. Empty when nothing of it is inside.
std::string band_path(const std::vector<double>& x, const std::vector<double>& low,
                      const std::vector<double>& high, const Scale& sx, const Scale& sy,
                      const Box& bounds);

// The positions in `earlier` of the series `pieces` retraces (empty: none): those whose every
// point inside `bounds` lies within 1.5 pixels of its lines there, so that drawn over them it
// would hide them. Only curves count, on both sides: lines that stay within 1.5 pixels of their
// first point (a series of one point) retrace nothing and are retraced by nothing.
std::vector<std::size_t> retraced(const std::vector<Polyline>& pieces,
                                  const std::vector<std::vector<Polyline>>& earlier,
                                  const Box& bounds);
// The stroke-dasharray of the k-th dash pattern (cycled): k = 0 the usual dashes of a dashed
// series, the others for series told apart from those they retrace ("2 3", "9 3 2 3", …).
inline constexpr int kDashPatterns = 8;
std::string dash_pattern(int k);
// The first dash pattern not in `taken` (the patterns of the series one retraces; −1 for solid
// ones), or 0 when every pattern is taken.
int free_dash_pattern(const std::vector<int>& taken);

// The box grown by a few pixels: geometry is cut to it, so that every coordinate stays inside
// the figure, and a clip path trims it to the box.
Box bounds_of(const Box& b);

}  // namespace physgrad::plot
