// Axes of every plot: data-to-pixel scales (linear or log10), tick positions and labels, the
// frame with tick marks, grid lines, title and axis labels. One tick mechanism for all figures.
#pragma once

#include <string>
#include <vector>

#include "physgrad/report/svg_document.hpp"

namespace physgrad::plot {

// Maps data to pixels: p0 + (t(v) − lo)/(hi − lo)·(p1 − p0) with t = log10 on a log axis (lo and
// hi are then in log10 units). Values that cannot be drawn (non-finite, ≤ 0 on a log axis) map
// to a non-finite pixel.
struct Scale {
  double lo, hi;
  bool log;
  double p0, p1;  // pixels of lo and hi
  double operator()(double v) const;
};

struct Tick {
  double value;
  std::string label;  // empty for a minor tick
};

struct Axis {
  Scale scale;
  std::vector<Tick> ticks;
};

// True when v is finite and, on a log axis, positive.
bool usable(double v, bool log);

// An axis covering the data range [lo, hi] (found = false when there is no data), widened to
// nice values: multiples of 1, 2 or 5 × 10^k, the step that wastes least room past the data
// with at most twelve intervals (linear); whole decades when the range spans
// several decades (log), else 1–9 × 10^k with every tick labelled, so that a range inside one
// decade still has readable labels.
Axis data_axis(double lo, double hi, bool found, bool log, double p0, double p1);
// An axis spanning exactly [lo, hi] (log: lo, hi > 0 in data units), with the ticks inside it.
Axis fixed_axis(double lo, double hi, bool log, double p0, double p1);

// "0.25", "1e-06", "2e+05": the shortest label for a tick at v among ticks `step` apart.
std::string tick_label(double v, double step);

// The plot frame layout every figure uses: the width of an axis' widest tick label, and the
// room left of a plot box (the y tick labels, and the rotated y axis label when there is one),
// above it (the title when there is one) and below it (x tick labels and the x axis label).
double widest_label(const Axis& axis);
double left_margin(const Axis& ay, bool has_y_label);
double top_margin(bool has_title);
// The room above the plot box for `title` in a figure `width` pixels wide: a title wider than the
// figure is broken into two lines (title_lines).
double top_margin(const std::string& title, int width);
// The lines a title is drawn in: one, or two broken at the space nearest its middle when it is
// wider than the figure.
std::vector<std::string> title_lines(const std::string& title, int width);
inline constexpr double kBottomMargin = 52;

// Light grid lines at the labelled ticks inside the box.
std::string grid_lines(const svg::Box& box, const Axis& ax, const Axis& ay);

struct AxisTitles {
  std::string title, x_label, y_label;
};

// Frame, tick marks (outside the box), tick labels, the title centred above the box (in two
// lines when wider than the figure) and the axis labels. `width` is the figure's width (the
// title is centred in it).
std::string axes(int width, const svg::Box& box, const Axis& ax, const Axis& ay,
                 const AxisTitles& titles);

// Tick marks and labels of a vertical axis on the right of x = `left` (e.g. a colour bar).
std::string right_ticks(double left, const svg::Box& box, const Axis& axis);

}  // namespace physgrad::plot
