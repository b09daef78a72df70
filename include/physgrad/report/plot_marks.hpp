// Marks on the points of a plot: the marker shapes that tell series apart (a dot, □, △, ◇, ▽),
// the hover targets that show a point's values (an SVG <title>, no script) and labelled marks on
// a curve (e.g. where a pretrained run switched rules).
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "physgrad/report/svg_document.hpp"

namespace physgrad::plot {

// How many marker shapes there are: 0 a round dot, 1 □, 2 △, 3 ◇, 4 ▽ (cycled beyond).
inline constexpr int kShapes = 5;

// Path data of marker `shape` (0 … kShapes − 1, cycled) centred at p, `size` pixels across.
std::string marker_path(int shape, const svg::Point& p, double size);
// Markers of `shape` at the points inside `bounds`: with `every` > 1 only each every-th point,
// starting at `offset`, so that the markers of series drawn on one another do not cover each
// other. Shape 0 draws round dots (stroke width `size`), the others outlined white-filled shapes.
std::string markers_svg(const std::vector<svg::Polyline>& pieces, const svg::Box& bounds,
                        int shape, double size, const std::string& color, std::size_t every = 1,
                        std::size_t offset = 0);

// One hover target per point (at most `most`, evenly spread over the points) inside `bounds`:
// a transparent circle whose <title> reads "LABEL: X_NAME = x, Y_NAME = y".
// With a finite low and high, the title adds "(from low to high)" (a band's ends, e.g. the
// seeds' range around their median).
struct HoverPoint {
  svg::Point pixel;
  double x, y;
  double low = NAN, high = NAN;
};
std::string hover_targets(const std::vector<HoverPoint>& points, const svg::Box& bounds,
                          const std::string& label, const std::string& x_name,
                          const std::string& y_name, std::size_t most = 60);

// A number as a hover title or a mark's label shows it: 4 significant digits.
std::string short_number(double v);

// The marks at a curve's points, outlined so they stand out on any line: a × centred at p (a run
// that ended, e.g. diverged), an arrow at p pointing up (or down) out of the frame (a value beyond
// the axis), a ▼ with its tip at p (a value ≤ 0 on a log axis) and a ◆ at p (a labelled mark).
std::string cross_mark(const svg::Point& p, const std::string& color);
std::string edge_arrow(const svg::Point& p, bool up, const std::string& color);
std::string down_triangle(const svg::Point& p, const std::string& color);
std::string diamond_mark(const svg::Point& p, const std::string& color);

}  // namespace physgrad::plot
