// Legends placed where no data is: the cells of the plot box that hold drawn data are marked,
// the legend goes to the first corner or edge position that covers none, else below the plot.
#pragma once

#include <string>
#include <vector>

#include "physgrad/report/svg_document.hpp"

namespace physgrad::plot {

struct LegendEntry {
  std::string label;  // entries with an empty label are not shown
  std::string color;  // any SVG colour
  bool line = true;   // a line swatch (else only the dot or symbol)
  std::string dashes{};  // the line's stroke-dasharray; empty: solid
  bool dot = false;   // a dot on the swatch (markers at data points)
  bool band = false;  // a shaded patch behind the swatch (a min–max band)
  int shape = -1;     // a marker shape on the swatch (plot_marks.hpp; 0 is the dot); -1: none
};

// The cells (square, `cell` pixels) of a box that hold drawn data.
class Occupancy {
 public:
  explicit Occupancy(const svg::Box& box, double cell = 6);
  void mark(const svg::Point& p);
  // Every cell the segment passes through (the part inside the box).
  void mark_segment(svg::Point a, svg::Point b);
  void mark_polyline(const svg::Polyline& line);
  void mark_box(const svg::Box& b);
  // Occupied cells overlapping b.
  int count(const svg::Box& b) const;

 private:
  svg::Box box_;
  double cell_;
  int nx_, ny_;
  std::vector<char> used_;
};

struct LegendLayout {
  std::string svg;
  double height_below = 0;  // figure height the legend takes below `below_top` (0 inside)
};

// The width of the legend's widest entry, with its swatch and padding.
double legend_entry_width(const std::vector<LegendEntry>& entries);

// The legend inside `box` at the first position (top right, top left, bottom right, bottom
// left, top centre, bottom centre, middle right, middle left) that covers no occupied cell;
// when `inside` is false or every position covers data, below the plot from y = below_top, in
// as many columns as fit in `width`; there a label wider than the figure is wrapped at spaces
// onto further lines.
LegendLayout legend(const std::vector<LegendEntry>& entries, const svg::Box& box,
                    const Occupancy& occupied, double below_top, int width, bool inside = true);

}  // namespace physgrad::plot
