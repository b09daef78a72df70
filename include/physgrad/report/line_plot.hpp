// Line plots (e.g. loss curves) on linear or log axes: lines, markers, shaded bands, steps,
// and runs that diverged or reached 0 marked instead of stretching the axes; a series that
// retraces another is told apart (own dashes and marker shape, "coincides with" in the legend),
// and every point shows its values on hover. Returns SVG, in a wide and a narrow layout.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace physgrad {

struct Series {
  std::string label;
  std::vector<double> x, y;
  std::string color{};  // any SVG colour; empty = a palette colour chosen by position
  bool markers = false;  // a dot at every point (e.g. the evaluations of a training run)
  bool dashed = false;
  // Optional shaded band (e.g. min–max over seeds) drawn under the line: both empty or both the
  // size of x. Samples where a bound cannot be drawn are left out of the band.
  std::vector<double> band_low{}, band_high{};
  // Drawn as steps: y[k] (and the band) holds from x[k] to x[k + 1] (repeat the last value at
  // the right end).
  bool steps = false;
  // False for a run that diverged: the axes are fitted to the other series, this one is cut at
  // the frame. (When no series sets the range, all do.)
  bool sets_range = true;
  // Written with a × at the series' last drawable point, e.g. "diverged at 77". A series whose
  // last point is not finite gets "not finite after x = …" when this is empty.
  std::string end_label{};
  // The marker shape (plot_marks.hpp: 0 a dot, 1 □, 2 △, 3 ◇, 4 ▽) when `markers` is set, e.g.
  // one per run folder where several draw the same rule.
  int shape = 0;
  // Labelled points on the curve, each drawn as a ◆ with its label (and on hover), e.g. where a
  // pretrained run switched from Adam to its rule.
  struct Mark {
    double x, y;
    std::string label;
  };
  std::vector<Mark> marks{};
  // With `dashed`: which dash pattern (plot_geometry.hpp's dash_pattern; 0 the usual dashes), e.g.
  // to tell apart variants of one rule that share its colour.
  int dash_pattern = 0;
};

struct LinePlotOptions {
  std::string title, x_label, y_label;
  bool log_x = false, log_y = false;
  int width = 640, height = 420;
  // The x axis spans exactly this range (e.g. [0, T]); unset: the data's, widened to nice values.
  std::optional<std::pair<double, double>> x_range{};
  // The y axis is fitted to this range (widened to nice values) in place of the data's, e.g. to
  // share one axis between figures side by side; unset: the data's.
  std::optional<std::pair<double, double>> y_range{};
  // Also a layout svg::kNarrowWidth pixels wide (legend below) for narrow screens
  // (svg::responsive); off: the one layout.
  bool narrow = true;
};

// Non-finite points are skipped and break the line. On a log y axis a value ≤ 0 is drawn on the
// axis' lower edge with a ▼ and the legend says where the series reaches it; on a log x axis
// such points are skipped. The legend goes where no data is (else below the plot, which makes
// the figure taller). A series drawn over earlier ones that it would hide (every point of theirs
// within 1.5 pixels of its line; both curves, not a lone point) gets a dash pattern and a marker shape of its own, its markers
// set off from theirs, and its legend entry says "coincides with" them; a series with no point to
// draw says so in its legend entry ("not drawn: …"). Each point has a hover title with its x and
// y (at most 60 a series). Each series is a <g class="series" data-label="…"> holding its line
// (class "line") and markers (class "marker", data-shape), with data-empty="…" when it has no
// point to draw. Throws Error when a series has x and y (or a band) of different lengths or the
// size is below 200x150.
std::string line_plot_svg(const std::vector<Series>& series, const LinePlotOptions& options);

}  // namespace physgrad
